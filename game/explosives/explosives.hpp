#pragma once
// Explosives, one game system for every scene that lists them (the fountain, the blob monster):
// the player throws a fused charge, a Bullet sphere that bounces and rolls; when its fuse runs out
// (or, optionally, on a hard impact) it detonates where it lies. A detonation is a fluid::Blast
// (fluid/core/blast.hpp) that this step's consumers apply with the one shared law: the crates
// (engine::applyBlast), the SPH water, the blob monster's particles and the GPU sprites; the
// system itself only pushes Bullet bodies. Charges are recycled, never removed, so body ids stay
// valid (engine/physics).

#include "engine/physics/physics_world.hpp"
#include "fluid/collide/collider_cache.hpp"
#include "fluid/core/blast.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace game {

struct ExplosiveParams {
  float fuse_seconds = 2.5f;      // from the throw to the detonation
  float throw_speed = 9.0f;       // m/s
  float lob_degrees = 0.0f;       // the throw leaves this much above the aimed direction (0: along the aim)
  float radius = 0.1f;            // m, the charge's sphere
  float mass = 1.2f;              // kg
  float impact_speed_change = 0;  // m/s: detonate early when one step changes its velocity by more; 0 = fuse only
  // The blast (fluid/core/blast.hpp); its centre is the charge at detonation.
  float impulse_at_1m = 60.0f;  // Pa s: specific impulse 1 m from the charge
  float core_radius = 0.25f;    // m
  float reach = 4.0f;           // m
  int max_live = 6;             // charges in flight at once; a throw beyond recycles the oldest
};

// The blast of a charge detonating at `centre`.
fluid::Blast blastOf(const ExplosiveParams& params, glm::vec3 centre);

// Empty when usable; otherwise names the bad field and value.
std::string validateExplosiveParams(const ExplosiveParams& params);

struct Charge {
  engine::BodyId body = -1;
  double detonates_at = 0.0;  // s, system time
  glm::vec3 last_velocity{0.0f};
  bool live = false;
};

struct Explosives {
  ExplosiveParams params;
  std::vector<Charge> charges;           // one Bullet body each, created on first use, then recycled
  std::vector<fluid::Blast> detonations;  // this step's blasts, for the other effects to apply
  double time = 0.0;                     // s
  std::uint64_t thrown = 0, detonated = 0;
  std::uint64_t bodies_pushed = 0;  // crates and charges moved by blasts so far
};

// Throws a charge from `origin` along `direction` (normalised here; zero = forward -z) raised by
// params.lob_degrees, at params.throw_speed, adding to `initial_velocity` (the thrower's own).
// Creates its Bullet body on first use.
void throwExplosive(Explosives& explosives, engine::PhysicsWorld& physics, glm::vec3 origin, glm::vec3 direction,
                    glm::vec3 initial_velocity = glm::vec3(0.0f));

// Where the player's hand lets a charge go: a little right of and below the eye, so the charge
// and its aim arc are seen leaving the hand instead of hiding behind the view's centre.
glm::vec3 throwOrigin(glm::vec3 eye, glm::vec3 view_dir);

// The velocity a throw along `direction` gives a charge: params.throw_speed along the direction
// raised by params.lob_degrees. throwExplosive and the aim arc share it, so the arc is the throw's.
glm::vec3 throwVelocity(const ExplosiveParams& params, glm::vec3 direction);

// The aim arc: where a charge thrown now would fly and land.
struct AimArc {
  std::vector<glm::vec3> path;  // points of the flight, every AimArc::kSampleSeconds from the throw
  glm::vec3 end{0.0f};          // the landing point, or where the fuse runs out in the air
  glm::vec3 end_normal{0.0f, 1.0f, 0.0f};  // the surface's normal at the landing point
  bool lands = false;           // touches a collider before its fuse runs out
  float flight_seconds = 0.0f;  // from the throw to `end`
  static constexpr float kSampleSeconds = 1.0f / 120.0f;
};

// The charge's free flight from `origin` (no drag: Bullet's bodies have none) under `gravity`,
// until its sphere touches one of the level's depth-map colliders (Kolb & Latta 2004 §3.3.2's
// query: the signed distance at the centre is below the radius; the contact time is refined by
// bisection) or its fuse runs out. Bounces and crates are not predicted: the arc ends at the
// first contact, where the player aimed.
void predictThrow(const ExplosiveParams& params, glm::vec3 origin, glm::vec3 direction, glm::vec3 gravity,
                  std::span<const fluid::CachedCollider> colliders, AimArc& out);

// Advances the fuses by `dt` after the physics step: every charge whose fuse ran out (or that hit
// something hard enough, see impact_speed_change) detonates. `detonations` is cleared first and
// then holds this step's blasts; each one has already pushed the Bullet bodies (live charges too,
// which may throw a neighbouring charge). The detonated charge leaves the simulation.
void stepExplosives(Explosives& explosives, engine::PhysicsWorld& physics, double dt);

int liveCharges(const Explosives& explosives);

}  // namespace game
