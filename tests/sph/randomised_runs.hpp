#pragma once
// The randomised stability scenario of issue 4 ("many short runs with random emitters, colliders
// and parameters within documented ranges"), shared by tests/sph (one fixed seed: every run must
// pass) and `bench_sph seeds` (a sweep over seeds that lists every run breaking a bound).
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <cmath>
#include <memory>
#include <random>
#include <string>

namespace fluid::randomised {

// One seed's sweep: this many drawn runs, each stepped this many times.
constexpr int kRunsPerSeed = 16;
constexpr int kStepsPerRun = 200;

// A closed box [0, size]^3 with six planes, no particles.
inline SphScene emptyBox(SphSolverKind solver, float size, float radius) {
  SphScene s;
  s.name = "box";
  s.world.params.solver = solver;
  s.world.params.particle_radius = radius;
  s.world.params.sound_speed = 20.0f;
  s.box_min = glm::vec3(0.0f);
  s.box_max = glm::vec3(size);
  s.world.params.domain_min = glm::vec3(-0.1f);
  s.world.params.domain_max = glm::vec3(size + 0.1f);
  CollisionMaterial m;
  m.resilience = 0.0f;
  addSphContainer(s, s.box_min, s.box_max, m);
  return s;
}

inline bool finiteState(const SphWorld& w) {
  for (std::size_t i = 0; i < w.particles.size(); ++i) {
    const glm::vec3 x = w.particles.position[i], v = w.particles.velocity[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z)) return false;
  }
  return true;
}

inline bool inside(const SphScene& s, float tol = 1e-5f) {
  for (const glm::vec3& p : s.world.particles.position)
    for (int a = 0; a < 3; ++a)
      if (!(p[a] >= s.box_min[a] - tol && p[a] <= s.box_max[a] + tol)) return false;
  return true;
}

// Run `run` (0, 1, ...; even = DFSPH, odd = WCSPH) drawn from the two streams. Documented ranges:
// radius 5..20 mm, viscosity 0..0.05, cfl 0.1..0.6 for WCSPH and 0.1..1.0 for DFSPH (the game's
// fountain and the dambreak_box bench run it at 0.9), and for DFSPH a longest step of 5..16.7 ms,
// a tolerance of 0.02..0.5 % and every other run without the force condition; emitter speed
// 0.5..4 m/s, rate 200..3000 /s, static sphere/box colliders of 3..10 cm inside a 0.5 m box. The
// DFSPH-only knobs come from the second stream, so widening them leaves the WCSPH runs' draws
// unchanged.
inline SphScene drawRun(int run, std::mt19937& rng, std::mt19937& dfsph_rng) {
  auto uni = [&](float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng); };
  auto dfsphUni = [&](float a, float b) { return std::uniform_real_distribution<float>(a, b)(dfsph_rng); };
  const SphSolverKind solver = run % 2 ? SphSolverKind::wcsph : SphSolverKind::dfsph;
  const float r = uni(0.005f, 0.02f);
  SphScene s = emptyBox(solver, 0.5f, r);
  SphParams& p = s.world.params;
  p.viscosity = uni(0.0f, 0.05f);
  p.cfl = uni(0.1f, solver == SphSolverKind::dfsph ? 1.0f : 0.6f);
  if (solver == SphSolverKind::dfsph) {
    p.max_time_step = dfsphUni(0.005f, 1.0f / 60.0f);
    p.max_density_error = dfsphUni(0.0002f, 0.005f);
    if (run % 4 == 0) p.force_bound = 0.0f;
  }
  p.max_particles = 1500;
  SphEmitter e;
  e.position = glm::vec3(uni(0.1f, 0.4f), uni(0.1f, 0.4f), uni(0.1f, 0.4f));
  e.direction = glm::vec3(uni(-1, 1), uni(-1, 1), uni(-1, 1));
  e.speed = uni(0.5f, 4.0f);
  e.radius = uni(0.0f, 3.0f * r);
  e.rate = uni(200.0f, 3000.0f);
  s.world.emitters.push_back(e);
  auto shape = run % 3 ? std::shared_ptr<const SignedDistanceShape>(std::make_shared<SphereShape>(uni(0.03f, 0.1f)))
                       : std::make_shared<BoxShape>(glm::vec3(uni(0.03f, 0.1f)));
  SphCollider c;
  c.shape = shape;
  c.pose.translation = glm::vec3(uni(0.1f, 0.4f), uni(0.05f, 0.3f), uni(0.1f, 0.4f));
  s.world.colliders.push_back(c);
  return s;
}

struct RunOutcome {
  bool ok = true;
  int step = -1;     // the first step that broke a bound
  std::string what;  // which bound, with the figures
};

// Steps a drawn run `steps` times and stops at the first step that is refused, leaves a
// non-finite state, ends with total energy above what the emitter brought in (kinetic +
// potential at the nozzle + 0.1 m, + 1 %) or leaves a particle outside the box.
inline RunOutcome stepRun(SphScene& s, int steps) {
  const SphEmitter e = s.world.emitters.front();
  const double m = sphParticleMass(s.world.params);
  double injected = 0.0;
  for (int step = 0; step < steps; ++step) {
    SphStepStats st;
    const SphStatus status = stepSph(s.world, 0.0f, &st);
    if (!status.ok()) return {false, step, "refused: " + status.error};
    injected += st.emitted * m * (0.5 * e.speed * e.speed + 9.81 * (e.position.y + 0.1));
    if (!finiteState(s.world)) return {false, step, "non-finite state"};
    const double energy = st.kinetic_energy + sphPotentialEnergy(s.world);
    if (!(energy <= injected * 1.01 + 1e-9))
      return {false, step, "energy " + std::to_string(energy) + " J > injected " + std::to_string(injected) + " J"};
    if (!inside(s)) return {false, step, "a particle left the box"};
  }
  return {};
}

}  // namespace fluid::randomised
