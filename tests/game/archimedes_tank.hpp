#pragma once
// The Archimedes tank shared by tests/game/test_body_fluid_coupling.cpp and bench_archimedes: a
// 0.4 x 0.4 m SPH tank (container collider, the same walls in Bullet) with a 0.14 m crate coupled
// through game/world/body_fluid_coupling, and the measurements of its draft.
#include "engine/physics/physics_world.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "game/world/body_fluid_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace archimedes_tank {

constexpr float kTankHalf = 0.2f;  // tank 0.4 x 0.4 m, floor at y = 0
constexpr float kBoxHalf = 0.07f;  // 0.14 m box

struct Tank {
  std::unique_ptr<engine::PhysicsWorld> physics;
  engine::BodyId box = -1;
  fluid::SphWorld sph;
  game::BodyFluidCoupling coupling;
};

// The water level far from the box: per column of one spacing (x, z) at least `clearance` outside
// the box's footprint, the top particle's centre plus r (the free surface of a resting lattice);
// the median over those columns.
inline float farFieldLevel(const fluid::SphWorld& sph, glm::vec3 box_centre, float clearance) {
  const float d = fluid::sphSpacing(sph.params), r = sph.params.particle_radius;
  const int n = static_cast<int>(std::ceil(2.0f * kTankHalf / d));
  std::vector<float> top(static_cast<std::size_t>(n * n), -1.0f);
  for (const glm::vec3& x : sph.particles.position) {
    if (std::abs(x.x - box_centre.x) < kBoxHalf * std::sqrt(2.0f) + clearance &&
        std::abs(x.z - box_centre.z) < kBoxHalf * std::sqrt(2.0f) + clearance)
      continue;  // near the box (any turn about y)
    const int i = std::clamp(static_cast<int>((x.x + kTankHalf) / d), 0, n - 1);
    const int k = std::clamp(static_cast<int>((x.z + kTankHalf) / d), 0, n - 1);
    float& t = top[static_cast<std::size_t>(k * n + i)];
    t = std::max(t, x.y);
  }
  std::vector<float> tops;
  for (const float t : top)
    if (t >= 0.0f) tops.push_back(t + r);
  if (tops.empty()) return NAN;
  std::nth_element(tops.begin(), tops.begin() + static_cast<long>(tops.size() / 2), tops.end());
  return tops[tops.size() / 2];
}

// Fraction of a cube's volume (half edge `half`) below the plane y = level: cells^3 cell centres
// in its own frame.
inline float submergedFraction(const engine::BodyState& box, float level, float half = kBoxHalf, int cells = 20) {
  int below = 0;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k) {
        const glm::vec3 local = half * (2.0f * (glm::vec3(i, j, k) + 0.5f) / float(cells) - 1.0f);
        below += (box.rotation * local + box.position).y < level;
      }
  return float(below) / float(cells * cells * cells);
}

// Water level by volume: the level still water at the rest density would have in the tank with
// this many particles (volume m / rho_0 each) and the box's part below that level (its own
// fraction below it, solved by fixed-point iteration). The visible surface (farFieldLevel) lies
// about 0.6 r lower: SPH water settles slightly denser than rho_0 by volume (the layers 1-2 %
// closer than d, the top layer sagging onto the one below, where its deficient density meets no
// pressure), and a floating box feels the pressure of the water's mass, not the visible surface.
inline float volumeLevel(const fluid::SphWorld& sph, const engine::BodyState& box) {
  const float area = 4.0f * kTankHalf * kTankHalf, box_volume = std::pow(2.0f * kBoxHalf, 3.0f);
  const float water =
      static_cast<float>(sph.particles.size()) * fluid::sphParticleMass(sph.params) / sph.params.rest_density;
  float level = water / area;
  for (int it = 0; it < 20; ++it) level = (water + box_volume * submergedFraction(box, level)) / area;
  return level;
}

struct Floating {
  float fraction = 0.0f;               // mean submerged fraction below the volume level, last 0.5 s
  float visible_fraction = 0.0f;       // the same below the visible far-field level
  float level = 0.0f;                  // volume level then (m)
  float visible_level = 0.0f;          // far-field level then (m)
  float lowest = 1e9f;                 // lowest box corner above the floor over the whole run (m)
  float top_gap = 1e9f;                // visible level minus the highest box corner, minimum over the run (m)
  float drift = 0.0f;                  // centre height change over the last 0.5 s (m)
  float start_y = 0.0f, end_y = 0.0f;  // centre height at release and at the end (m)
  std::string error;                   // empty, or why the run stopped early
};

// The tank's water: DFSPH parameters with particles of `particle_radius` and the tank as the SPH
// container collider (0.4 x 0.4 m, 1 m high, floor at y = 0). False when the parameters are refused.
inline bool setUpTankWater(Tank& t, float particle_radius, std::size_t max_particles) {
  fluid::SphParams& p = t.sph.params;
  p.solver = fluid::SphSolverKind::dfsph;
  p.particle_radius = particle_radius;
  p.viscosity = 0.01f;
  p.max_particles = max_particles;
  p.domain_min = glm::vec3(-kTankHalf, -0.05f, -kTankHalf);
  p.domain_max = glm::vec3(kTankHalf, 0.6f, kTankHalf);
  if (!fluid::validateSphParams(p).ok()) return false;
  fluid::SphCollider tank;
  tank.shape = std::make_shared<fluid::BoxShape>(glm::vec3(kTankHalf, 0.5f, kTankHalf), true);
  tank.pose.translation = glm::vec3(0.0f, 0.5f, 0.0f);
  tank.integrate_pose = false;
  tank.material.resilience = 0.0f;
  t.sph.colliders.push_back(tank);
  return true;
}

// The same walls in Bullet (floor and four sides), a box of `density` centred at `centre`, and the
// coupling between it and the water.
inline void addTankBox(Tank& t, float density, glm::vec3 centre) {
  t.physics = engine::createPhysicsWorld({});
  engine::addStaticPlane(*t.physics, glm::vec3(0, 1, 0), 0.0f);
  for (const glm::vec3 n : {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)})
    engine::addStaticPlane(*t.physics, n, -kTankHalf);
  engine::BodyDesc box;
  box.mass = density * std::pow(2.0f * kBoxHalf, 3.0f);
  box.position = centre;
  t.box = engine::addBox(*t.physics, box, glm::vec3(kBoxHalf));
  game::initBodyFluidCoupling(t.coupling, t.sph, glm::vec3(kBoxHalf), t.sph.params.domain_min, t.sph.params.domain_max);
}

// A tank (the SPH container and the same walls in Bullet) with `layers` lattice layers of water
// over its whole floor, and a box of `density` with its centre at `box_y`. Water particles the
// box would overlap are left out (a box released under water).
// Returns false (nothing built) when the parameters are refused.
inline bool buildDeepTank(Tank& t, float density, int layers, float box_y, float particle_radius = 0.0125f) {
  if (!setUpTankWater(t, particle_radius, 200000)) return false;
  const float r = particle_radius, d = 2.0f * r;
  const int columns = static_cast<int>(std::lround(2.0f * kTankHalf / d));
  const glm::vec3 centre(0.0f, box_y, 0.0f);
  for (int y = 0; y < layers; ++y)
    for (int z = 0; z < columns; ++z)
      for (int x = 0; x < columns; ++x) {
        const glm::vec3 q(-kTankHalf + r + d * x, r + d * y, -kTankHalf + r + d * z);
        if (glm::all(glm::lessThan(glm::abs(q - centre), glm::vec3(kBoxHalf + r)))) continue;
        fluid::addSphParticle(t.sph, q);
      }
  addTankBox(t, density, centre);
  return true;
}

// Steps a deep tank `seconds` coupled and measures the last 0.5 s (and extremes over the run).
// `mirrored`: the box's force from the mirrored boundary pressure instead of the pressure at its
// faces (BodyFluidCoupling::surface_pressure_force off), for the comparison in docs/engine.md.
inline Floating floatBox(float density, int layers, float box_y, double seconds, float particle_radius = 0.0125f,
                         bool mirrored = false) {
  Tank t;
  Floating out;
  if (!buildDeepTank(t, density, layers, box_y, particle_radius)) {
    out.error = "tank parameters refused";
    return out;
  }
  t.coupling.surface_pressure_force = !mirrored;
  const double dt = 1.0 / 60.0;
  const int steps = static_cast<int>(std::lround(seconds / dt)), tail = static_cast<int>(std::lround(0.5 / dt));
  const engine::BodyId bodies[] = {t.box};
  out.start_y = box_y;
  float y_tail = 0.0f;
  for (int s = 0; s < steps; ++s) {
    engine::stepPhysics(*t.physics, dt, 2);
    game::collidersFromBodies(t.coupling, *t.physics, bodies, t.sph);
    const fluid::SphStatus st = fluid::advanceSph(
        t.sph, dt, [](const fluid::SphStepStats&) {}, 100000);
    if (!st.ok()) {
      out.error = st.error;
      return out;
    }
    if (std::string bad = game::forcesToBodies(t.coupling, t.sph, *t.physics); !bad.empty()) {
      out.error = bad;
      return out;
    }
    const engine::BodyState box = engine::bodyState(*t.physics, t.box);
    const float visible = farFieldLevel(t.sph, box.position, 0.02f);
    float lowest = 1e9f, highest = -1e9f;
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 corner(c & 1 ? kBoxHalf : -kBoxHalf, c & 2 ? kBoxHalf : -kBoxHalf, c & 4 ? kBoxHalf : -kBoxHalf);
      lowest = std::min(lowest, (box.rotation * corner + box.position).y);
      highest = std::max(highest, (box.rotation * corner + box.position).y);
    }
    out.lowest = std::min(out.lowest, lowest);
    out.top_gap = std::min(out.top_gap, visible - highest);
    out.end_y = box.position.y;
    if (s < steps - tail) continue;
    if (s == steps - tail) y_tail = box.position.y;
    const float level = volumeLevel(t.sph, box);
    out.level += level / tail;
    out.visible_level += visible / tail;
    out.fraction += submergedFraction(box, level) / tail;
    out.visible_fraction += submergedFraction(box, visible) / tail;
    out.drift = box.position.y - y_tail;
  }
  return out;
}

inline void printFloating(float rho, const Floating& f, float particle_radius) {
  std::printf(
      "[ metric ] r %.4f m, edge %.2f m = %.1f spacings, crate %4.0f kg/m^3: submerged %.3f below the volume level "
      "%.3f m "
      "(%.3f below the visible %.3f m; Archimedes %.3f); centre %.3f -> %.3f m, drift %+.4f m in the last 0.5 s; "
      "lowest corner %.3f m above the floor, top %.3f m under the visible surface (minima over the run)\n",
      particle_radius, 2.0f * kBoxHalf, kBoxHalf / particle_radius, rho, f.fraction, f.level, f.visible_fraction,
      f.visible_level, std::min(rho / 1000.0f, 1.0f), f.start_y, f.end_y, f.drift, f.lowest, f.top_gap);
}

}  // namespace archimedes_tank
