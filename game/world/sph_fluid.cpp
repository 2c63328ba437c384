#include "game/world/sph_fluid.hpp"

#include "fluid/core/finite.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace game {

// Simulated seconds the pool settles at load, jet off (fillSphPool).
constexpr double kPoolSettleSeconds = 1.0;

void applySolverKnobs(const SphFluidParams& params, fluid::SphParams& solver) {
  solver.viscosity = params.viscosity;
  solver.cfl = params.cfl;
  solver.max_time_step = params.max_time_step;
  solver.min_time_step = std::min(solver.min_time_step, solver.max_time_step);
  solver.max_density_error = params.density_error;
  solver.force_bound = params.force_bound;
  solver.warm_start = params.warm_start;
  solver.warm_start_share = params.warm_start_share;
  solver.spray_speed = params.spray_speed;
  solver.spray_terminal_speed = params.spray_terminal_speed;
  solver.speculative_contacts = params.speculative_contacts;
}

void deriveSphFluid(const SphFluidParams& params, const FountainGeometry& g, glm::vec3 gravity,
                    fluid::SphWorld& world) {
  fluid::SphParams& sp = world.params;
  sp.gravity = gravity;
  applySolverKnobs(params, sp);
  // A cap well above the jet speed: a stray fast particle cannot force tiny CFL steps.
  sp.max_speed = 3.0f * params.jet_speed + 5.0f;
  // WCSPH: the sound speed must stay ~10x the fastest flow (Becker & Teschner 2007 §4).
  sp.sound_speed = std::max(20.0f, 10.0f * params.jet_speed);
  for (fluid::SphEmitter& e : world.emitters) {
    e.speed = params.jet_speed;
    e.rate = params.rate;
  }
  world.sinks.clear();
  // Everything that leaves the basin onto the ground (below the wall top outside it) and the strays
  // (a particle flung off the rim at the speed cap) once they leave the fountain's neighbourhood:
  // above the jet's reach or 0.8 m beyond the basin on any side. With the pump they are the gutter:
  // into the pump; without it they leave the world.
  const fluid::SphSinkKind gutter = params.pump ? fluid::SphSinkKind::pump : fluid::SphSinkKind::remove;
  world.sinks.push_back({{-100.0f, -1.0f, -100.0f}, {100.0f, 0.12f, 100.0f}, gutter});
  const float reach = g.basin_outer_radius + 0.8f, far = 1000.0f;
  const float top =
      g.nozzle.y + params.jet_speed * params.jet_speed / (2.0f * std::max(glm::length(gravity), 0.1f)) + 1.0f;
  world.sinks.push_back({{-far, top, -far}, {far, far, far}, gutter});
  world.sinks.push_back({{reach, -far, -far}, {far, far, far}, gutter});
  world.sinks.push_back({{-far, -far, -far}, {-reach, far, far}, gutter});
  world.sinks.push_back({{-far, -far, reach}, {far, far, far}, gutter});
  world.sinks.push_back({{-far, -far, -far}, {far, far, -reach}, gutter});
  world.pump.feeds_emitters = params.pump;
  world.pump.delay = params.pump_delay;
  if (params.pump) {
    // The intake: a grate 0.4 m square in the basin floor against the wall at +x, one particle
    // layer deep. It takes what the nozzle gives back in the pipe's delay, plus a few layers
    // (the pump's capacity), so it draws at the jet's rate, not at the pool's head.
    const float inner = g.basin_inner_radius, half = 0.2f, d = 2.0f * params.particle_radius;
    world.sinks.push_back({{inner - 0.6f, g.basin_floor - 0.05f, -half},
                           {inner - 0.2f, g.basin_floor + 1.5f * d, half},
                           fluid::SphSinkKind::intake});
    world.pump.capacity = static_cast<std::size_t>(std::ceil(params.rate * params.pump_delay)) + 64;
  }
}

namespace {

// Fills the basin with all the water (the annulus between the plinth and the basin wall, from the
// floor up), then lets it settle for a second with the jet and the intake off: a lattice at rest is
// at the rest density and a radius off the walls, so the pass only smooths the round walls' edges.
// (The pool does not come to rest: the basin's floor-wall corner keeps kicking particles at up to
// 1.5-2 m/s, the baked maps' concave corner of issue 33 item 6, and the pool's v_rms stays near
// 0.2 m/s with or without the pass; tests/game/test_fountain_pump.cpp reports it.)
bool fillSphPool(SphFluid& out, const FountainGeometry& g, std::string& error) {
  fluid::SphWorld& w = out.world;
  const float r = w.params.particle_radius;
  const glm::vec3 lo(-g.basin_inner_radius, g.basin_floor, -g.basin_inner_radius);
  const glm::vec3 hi(g.basin_inner_radius, g.basin_wall_top, g.basin_inner_radius);
  const auto inBasin = [&](glm::vec3 p) {
    const float radial = std::sqrt(p.x * p.x + p.z * p.z);
    return radial < g.basin_inner_radius - r && radial > g.plinth_radius + r;
  };
  const std::size_t want = out.params.max_particles;
  const std::size_t filled = fluid::addSphPool(w, lo, hi, want, inBasin);
  if (filled < want) {
    error = "sph_fluid: max_particles = " + std::to_string(want) + " does not fit in the basin below its wall top (" +
            std::to_string(filled) + " do at particle_radius " + std::to_string(r) + ")";
    return false;
  }
  // Jet and intake off while it settles: the intake would start a flow towards it.
  std::vector<float> rates;
  for (fluid::SphEmitter& e : w.emitters) rates.push_back(std::exchange(e.rate, 0.0f));
  std::vector<fluid::SphSink> sinks;
  sinks.swap(w.sinks);
  const fluid::SphStatus st = fluid::advanceSph(
      w, kPoolSettleSeconds, [](const fluid::SphStepStats&) {}, 100000);
  sinks.swap(w.sinks);
  for (std::size_t k = 0; k < w.emitters.size(); ++k) w.emitters[k].rate = rates[k];
  for (fluid::SphEmitter& e : w.emitters) e.accumulator = 0.0;
  if (!st.ok()) {
    error = "sph_fluid: settling the pool: " + st.error;
    return false;
  }
  return true;
}

}  // namespace

bool initSphFluid(SphFluid& out, const SphFluidParams& params, const FountainGeometry& g,
                  const std::shared_ptr<const LevelColliders>& colliders, glm::vec3 gravity, std::string& error) {
  out = SphFluid{};
  out.params = params;
  fluid::SphParams& sp = out.world.params;
  sp.solver = params.solver;
  sp.particle_radius = params.particle_radius;
  sp.max_particles = params.max_particles;
  // The neighbour grid only needs to cover the fountain (strays are clamped into border cells).
  sp.domain_min = glm::vec3(-g.basin_outer_radius - 1.0f, -0.5f, -g.basin_outer_radius - 1.0f);
  sp.domain_max = glm::vec3(g.basin_outer_radius + 1.0f, g.nozzle.y + 4.0f, g.basin_outer_radius + 1.0f);
  fluid::SphEmitter nozzle;
  // Start one spacing above the spire top so the first layer is not inside the collider.
  nozzle.position = g.nozzle + glm::vec3(0.0f, 2.0f * params.particle_radius, 0.0f);
  nozzle.direction = glm::vec3(0.0f, 1.0f, 0.0f);
  nozzle.radius = params.nozzle_radius;
  // In the fountain's scene the jet leaves the nozzle as drops (faster than its spray_speed):
  // without a spread they rise and fall back as one column onto the spire's top and run down the
  // spire at 4 m/s; scattered by 8 degrees they fan out into the dish round it, as a jet that
  // breaks up does.
  nozzle.spread = glm::radians(8.0f);
  out.world.emitters.push_back(nozzle);
  deriveSphFluid(params, g, gravity, out.world);
  if (const fluid::SphStatus st = fluid::validateSphParams(sp); !st.ok()) {
    error = "sph_fluid: " + st.error;
    return false;
  }
  if (!colliders || colliders->parts.empty()) {
    error = "sph_fluid: the level has no colliders (content/colliders/fountain.colliders)";
    return false;
  }
  // The level's baked depth-map colliders (Kolb et al. 2004 §4), one SPH collider per part, each
  // queried only by particles within the support of its reach box. Static: collider space =
  // world space. Depth-map distances are measured along the map axes (not 1-Lipschitz), so the
  // end-of-step check queries every particle in reach (SphCollider::lipschitz_distance off).
  for (std::size_t k = 0; k < colliders->parts.size(); ++k) {
    fluid::SphCollider collider;
    collider.shape = culledPart(colliders, k, fluid::sphSupport(sp));
    collider.integrate_pose = false;
    collider.lipschitz_distance = false;
    collider.material.resilience = 0.0f;  // water does not bounce (Kolb 2004 §3.3.2 ε)
    out.world.colliders.push_back(collider);
  }
  fluid::reserveSph(out.world, params.max_particles);
  if (params.pump && !fillSphPool(out, g, error)) return false;
  return true;
}

WaterWhereabouts waterWhereabouts(const SphFluid& fluid, const FountainGeometry& g) {
  WaterWhereabouts out;
  const fluid::SphWorld& w = fluid.world;
  for (const glm::vec3& p : w.particles.position) {
    const float radial = std::sqrt(p.x * p.x + p.z * p.z);
    if (radial > g.basin_inner_radius)
      ++out.ground;
    else if (p.y < g.basin_wall_top)
      ++out.pool;
    else
      ++out.jet_and_air;
  }
  out.pump = w.pump.size();
  out.spray = w.particles.spray_count;
  const float d = fluid::sphSpacing(w.params);
  out.pool_level = static_cast<float>(out.pool) * d * d * d / basinFloorArea(g);
  return out;
}

float basinFloorArea(const FountainGeometry& g) {
  return 3.14159265f * (g.basin_inner_radius * g.basin_inner_radius - g.plinth_radius * g.plinth_radius);
}

bool stepSphFluid(SphFluid& f, double dt, const std::function<void(const fluid::SphStepStats&)>& on_step) {
  if (!f.error.empty()) return false;
  std::uint64_t sub = 0;
  f.last_totals = {};
  const fluid::SphStatus st = fluid::advanceSph(
      f.world, dt,
      [&](const fluid::SphStepStats& stats) {
        sub += stats.dt > 0.0f ? 1 : 0;
        fluid::addStepTotals(f.last_totals, stats);
        if (on_step) on_step(stats);
      },
      10000);
  fluid::addStepTotals(f.run_totals, f.last_totals);
  f.solver_steps += sub;
  ++f.steps;
  if (!st.ok()) {
    f.error = st.error;
    return false;
  }
  return true;
}

float sphDeepPush(const SphFluid& f) { return f.world.params.particle_radius; }

bool sphFluidWarns(const SphFluid& f, const fluid::SphStepTotals& totals) {
  return fluid::sphTotalsWarn(totals, sphDeepPush(f));
}

std::string findNonFiniteSph(const SphFluid& f) {
  const fluid::ParticleStore& p = f.world.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!fluid::isFinite(p.position[i])) return "sph_fluid particle id " + std::to_string(p.id[i]) + " position";
    if (!fluid::isFinite(p.velocity[i])) return "sph_fluid particle id " + std::to_string(p.id[i]) + " velocity";
    if (i < p.density.size() && !std::isfinite(p.density[i]))
      return "sph_fluid particle id " + std::to_string(p.id[i]) + " density";
  }
  return {};
}

}  // namespace game
