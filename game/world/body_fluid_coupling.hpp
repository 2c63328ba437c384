#pragma once
// Two-way coupling between Bullet boxes (the `rigid_bodies` crates) and the SPH water
// (`sph_fluid`), active when a scene lists both. Explicit and staggered, one game step apart:
//  1. before the SPH step, every coupled box becomes an SPH collider (fluid::BoxShape) at the
//     box's Bullet pose, moving with its Bullet velocities, so the water is pushed aside
//     (boundary pressure + the Kolb 2004 §3.3.2 collision reaction in fluid/sph);
//  2. after it, the force and torque the water exerted on each collider (averaged over the SPH
//     sub-steps, fluid/sph's coupling output) are held on the Bullet body for the next physics
//     step (engine::setExternalForce).
// Only boxes whose centre lies in `region` and within reach of the water's current bounds take
// part, so crates away from the water cost the SPH step nothing.
//
// Stability guard: water caught in a thin film between a box and another collider (a crate
// landing on the basin floor) is compressed far beyond what the pressure solver resolves in one
// step, and the explicit force on the box then reaches tens of kN (measured: 81 kN on a 12 kg
// box, which Bullet fires away at 50 m/s). The force handed to Bullet is therefore capped at
// `force_limit` times the buoyancy of the fully submerged box (rho_0 |g| V), and the torque at
// that force times the box's half diagonal; `clamped` counts how often the cap acted.
//
// Film under a box (sub-particle closure): where a box face lies closer to one of the scene's
// colliders than one particle spacing d, no layer of particles fits between them, so the SPH
// cannot resolve the water there: it either leaves the face dry or squeezes a particle into the
// gap, whose push reads the squeeze, not the water. Real water in the film carries the pressure of
// the water around it. Without a closure a crate lighter than water that reaches the floor of the
// fountain's pool (about three particle layers deep: a 500 kg/m^3 crate at its Archimedes draft
// leaves 8.6 cm, about d, under it) stays on it or floats too deep. So every face point within d
// of a scene collider that faces it across the film (fluid::facesAcrossAFilm) gets the pressure
// filmForce extrapolates from the water around it (the particles within twice the kernel support,
// each shifted hydrostatically by rho_0 |g| (y_j - y) from its height to the point's, as Akinci et
// al. 2012's boundary samples take the fluid's pressure), leaving out the particles in the film
// itself; and the SPH leaves the push of water squeezed between the box and such a collider out
// of the box's force (fluid::SphCollider::film_gap = d, film_partner_count = the scene's
// colliders), so the film is counted once.

#include "engine/physics/physics_world.hpp"
#include "fluid/sph/sph.hpp"

#include <glm/glm.hpp>

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace game {

// The stability cap above, shared by every particle body coupled to crates (the water here, the
// blob's goo in game/world/blob_crates.hpp): a force longer than max_force is shortened to it, a
// torque longer than max_torque likewise. Returns true when either was shortened.
struct WrenchCap {
  float max_force = 0.0f, max_torque = 0.0f;  // N, N m
};
bool capWrench(const WrenchCap& cap, glm::vec3& force, glm::vec3& torque);

// The box of `points` grown by `grow` on every side: a crate whose centre lies outside it cannot
// touch them this step and is left out of the coupling. Empty points give an empty box (lo > hi).
void grownBounds(std::span<const glm::vec3> points, glm::vec3 grow, glm::vec3& lo, glm::vec3& hi);

// Caller-owned scratch of filmForce, kept between calls.
struct FilmScratch {
  std::vector<std::size_t> nearby;     // particles within reach of the box
  std::vector<glm::vec3> nearby_in_box;  // their positions in the box's frame
  std::vector<glm::vec3> points, local;
  std::vector<float> gap;
  std::vector<fluid::ColliderSample> samples;
};

struct BodyFluidCoupling {
  std::shared_ptr<const fluid::SignedDistanceShape> box_shape;  // one shape, shared by every box
  fluid::CollisionMaterial material;
  float force_limit = 4.0f;                      // x full-submersion buoyancy (rho_0 |g| V of one box)
  WrenchCap cap;                                 // from force_limit, set by init
  float reach = 0.0f;                            // half diagonal of a box (m)
  glm::vec3 region_min{0.0f}, region_max{0.0f};  // world AABB the box centres must be in
  std::size_t first_collider = 0;                // SPH colliders before this one are the scene's own
  std::vector<engine::BodyId> coupled;           // body of collider first_collider + k, last SPH step
  std::uint64_t forces_applied = 0;              // body forces handed to Bullet so far
  std::uint64_t clamped = 0;                     // of those, shortened by the cap
  glm::vec3 half_extents{0.0f};                  // of every box (m)
  // The boxes' force reads the water's pressure at their faces (fluid::SphCollider::
  // surface_pressure_force, Adami et al. 2012 eq. 27), so they float at their draft; false: the
  // mirrored boundary pressure of the water's own term, about r too deep (`bench_archimedes
  // --mirrored` compares the two).
  bool surface_pressure_force = true;
  std::uint64_t film_points = 0;                 // face points in a film that got its pressure, so far
  FilmScratch film_scratch;
};

// The film's pressure on one box (see the header comment): face points on a regular grid of
// about d; each that lies within d of a scene collider (sph.colliders before first_collider)
// facing it gets the extrapolated pressure of the water around it, with the particles within d
// of the face and inside its outline (the film's own) left out of the extrapolation. Force (N) and torque
// (N m, about the box centre) on the box at `pose`; `points` counts the face points that got it.
struct FilmWrench {
  glm::vec3 force{0.0f}, torque{0.0f};
  int points = 0;
};
FilmWrench filmForce(const BodyFluidCoupling& coupling, const fluid::SphWorld& sph, const fluid::ColliderPose& pose,
                     FilmScratch& scratch);

// `half_extents` of the boxes (all equal, m); the SPH world's current colliders stay in front.
// Reads rest density and gravity from sph.params for the force cap.
void initBodyFluidCoupling(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, glm::vec3 half_extents,
                           glm::vec3 region_min, glm::vec3 region_max);

// Step 1: replaces the SPH colliders from first_collider on by the boxes of `bodies` inside the
// region, at their current Bullet state.
void collidersFromBodies(BodyFluidCoupling& coupling, const engine::PhysicsWorld& physics,
                         std::span<const engine::BodyId> bodies, fluid::SphWorld& sph);

// Step 2: hands each coupled collider's force and torque to its body for the next physics step.
// Returns an empty string, or names the first body whose force was not finite (nothing applied
// to it).
std::string forcesToBodies(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, engine::PhysicsWorld& physics);

}  // namespace game
