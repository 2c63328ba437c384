// The SPH step driver: input checks, sinks and emitters, neighbour search, boundary sampling,
// the pressure solver (solvers.hpp), advection, coupling forces and collisions, in that order.
// See sph.hpp for the papers; each unit cites the equations it implements.
#include "fluid/core/finite.hpp"
#include "fluid/sph/boundary.hpp"
#include "fluid/sph/collisions.hpp"
#include "fluid/sph/emitters_sinks.hpp"
#include "fluid/sph/neighbor_step.hpp"
#include "fluid/sph/solvers.hpp"
#include "fluid/sph/spray.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace fluid {
namespace sph_step {
namespace {

// The parameters, colliders and emitters a step needs (particles are checked with the sinks).
SphStatus validateStepInput(const SphWorld& world) {
  if (SphStatus status = validateSphParams(world.params); !status.ok()) return status;
  for (std::size_t c = 0; c < world.colliders.size(); ++c) {
    const SphCollider& collider = world.colliders[c];
    if (!collider.shape) return {"sph collider " + std::to_string(c) + " has no shape"};
    const glm::quat q = collider.pose.rotation;
    if (!isFinite(collider.pose.translation) || !isFinite(collider.pose.linear_velocity) ||
        !isFinite(collider.pose.angular_velocity) || !std::isfinite(q.w + q.x + q.y + q.z) || !(glm::dot(q, q) > 0.0f))
      return {"sph collider " + std::to_string(c) + " has a non-finite or degenerate pose; step refused"};
  }
  for (std::size_t e = 0; e < world.emitters.size(); ++e) {
    const SphEmitter& emitter = world.emitters[e];
    if (!isFinite(emitter.position) || !isFinite(emitter.direction) || !std::isfinite(emitter.speed) ||
        !std::isfinite(emitter.radius) || !std::isfinite(emitter.rate) || !std::isfinite(emitter.spread) ||
        std::isnan(emitter.start_time) ||
        std::isnan(emitter.end_time))
      return {"sph emitter " + std::to_string(e) + " has a non-finite field; step refused"};
  }
  return {};
}

// Symplectic Euler advection x += dt v, with the XSPH-smoothed velocity (Monaghan 1989) when
// params.xsph > 0. Skipped when the solver already advected in its last pass.
void advect(StepContext& context) {
  if (context.advected) return;
  ParticleStore& store = context.particles;
  SphScratch& scratch = context.scratch;
  std::vector<glm::vec3>& positions = store.position;
  const std::vector<glm::vec3>& velocities = store.velocity;
  const std::size_t n = context.count;
  const float dt = context.dt;
  const float xsph = context.params.xsph;
  if (xsph > 0.0f) {
    const std::uint32_t* offsets = context.neighbor_offsets;
    const std::uint32_t* counts = context.neighbor_counts;
    const std::uint32_t* neighbors = context.neighbor_indices;
    const float mass = context.mass;
    scratch.vec_b.resize(n);
    forEach(n, [&](std::size_t i) {
      glm::vec3 correction(0.0f);
      for (std::uint32_t k = offsets[i]; k < offsets[i] + counts[i]; ++k) {
        const std::uint32_t j = neighbors[k];
        correction += (2.0f * mass / (store.density[i] + store.density[j]) *
                       scratch.kernel.value(glm::length(positions[i] - positions[j]))) *
                      (velocities[j] - velocities[i]);
      }
      scratch.vec_b[i] = velocities[i] + xsph * correction;
    });
    forEach(n, [&](std::size_t i) { positions[i] += dt * scratch.vec_b[i]; });
  } else {
    forEach(n, [&](std::size_t i) { positions[i] += dt * velocities[i]; });
  }
}

// Coupling forces from the boundary pressure terms: F_c = -sum_i m dv_ic / dt (summed in the
// solver's last pass when it set context.coupled, otherwise here). Overwrites each collider's
// force/torque; the collisions add their reactions after.
void storeCouplingForces(StepContext& context) {
  for (std::size_t c = 0; c < context.collider_count; ++c) {
    SphCollider& collider = context.world.colliders[c];
    ForceTorque sums{};
    if (context.coupled) {
      sums = context.coupling.per_collider[c];
    } else if (collider.boundary_pressure) {
      sums = reduce(
          context.count, ForceTorque{}, [&](std::size_t i, ForceTorque& acc) { addCouplingTerm(context, c, i, acc); },
          [](ForceTorque a, const ForceTorque& b) {
            a.force += b.force;
            a.torque += b.torque;
            return a;
          });
    }
    collider.force = sums.force;
    collider.torque = sums.torque;
  }
}

// Advances the clocks and poses, applies the speed clamp and fills the stats.
void finishStep(StepContext& context, float requested) {
  SphWorld& world = context.world;
  const SphParams& params = context.params;
  const float dt = context.dt;
  for (SphCollider& collider : world.colliders)
    if (collider.integrate_pose) collider.pose = advancedPose(collider.pose, dt);
  advanceEmitterClocks(world, dt);
  world.time += dt;
  world.last_dt = dt;
  ++world.step_count;

  SphStepStats& stats = context.stats;
  stats.dt = dt;
  stats.density_iterations = context.density_iterations;
  stats.divergence_iterations = context.divergence_iterations;
  stats.particles = context.total;
  stats.spray = context.total - context.count;
  stats.dt_limited_by_request = requested < params.max_time_step && dt >= requested;
  // The speed cap, the kinetic energy (of the capped velocities) and the health counts in one
  // pass. The energy sum is added in the same order as without the counts (same blocks, same
  // joins).
  ParticleStore& store = context.particles;
  std::vector<glm::vec3>& velocities = store.velocity;
  const std::size_t total = context.total;
  SphScratch::SampleCarry& carry = context.scratch.carry;
  carry.position.resize(total);
  carry.count = context.count;  // the spray's samples are not carried
  struct Pass {
    double sum_v2 = 0.0;
    std::size_t clamps = 0, nonfinite = 0;
  };
  const Pass pass = reduce(
      total, Pass{},
      [&](std::size_t i, Pass& acc) {
        if (params.max_speed > 0.0f) {
          const float speed = glm::length(velocities[i]);
          if (speed > params.max_speed) {
            velocities[i] *= params.max_speed / speed;
            ++acc.clamps;
          }
        }
        acc.sum_v2 += glm::dot(velocities[i], velocities[i]);
        const glm::vec3 x = store.position[i];
        carry.position[i] = x;  // where the last collision pass sampled the colliders
        acc.nonfinite += isFinite(x) && isFinite(velocities[i]) && std::isfinite(store.density[i]) ? 0 : 1;
      },
      [](Pass a, const Pass& b) {
        a.sum_v2 += b.sum_v2;
        a.clamps += b.clamps;
        a.nonfinite += b.nonfinite;
        return a;
      });
  stats.kinetic_energy = static_cast<float>(0.5 * context.mass * pass.sum_v2);
  stats.speed_clamps = pass.clamps;
  stats.nonfinite = pass.nonfinite;
  stats.dt_held_at_min = context.dt_held_at_min;
}

// The 99th percentile of the step-start density errors the solver just computed (store.density
// of the first n particles, the SPH water).
float densityErrorP99(const ParticleStore& store, std::size_t n, float rest_density, std::vector<float>& errors) {
  if (n == 0) return 0.0f;
  errors.resize(n);
  for (std::size_t i = 0; i < n; ++i) errors[i] = std::max(0.0f, store.density[i] / rest_density - 1.0f);
  const std::size_t k = (99 * (n - 1)) / 100;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(k), errors.end());
  return errors[k];
}

SphStatus stepImpl(SphWorld& world, float max_dt, double span, SphStepStats* stats_out) {
  const auto t_start = Clock::now();
  SphStepStats stats;
  if (SphStatus status = validateStepInput(world); !status.ok()) return status;
  std::size_t in_sinks = 0;
  if (SphStatus status = checkFiniteAndSinks(world, in_sinks, stats.nonfinite); !status.ok()) {
    if (stats_out) *stats_out = stats;  // dt = 0: no step; nonfinite says how many particles were refused
    return status;
  }
  ensureStepTables(world);
  const SphParams& params = world.params;
  SphScratch& scratch = world.scratch;
  ParticleStore& store = world.particles;
  if (!(max_dt > 0.0f) || !std::isfinite(max_dt)) max_dt = params.max_time_step;
  const float requested = max_dt;
  max_dt = std::min(max_dt, params.max_time_step);

  // Keep persistent per-particle solver state in step with the store.
  scratch.warm_kappa.resize(store.size(), 0.0f);
  scratch.last_neighbours.resize(store.size(), SphScratch::kUnknownNeighbours);
  store.spray_count = std::min(store.spray_count, store.size());
  stats.removed = applySinks(world, in_sinks, stats.pumped);
  stats.emitted = applyEmitters(world);
  const std::size_t n = store.size();
  scratch.warm_kappa.resize(n, 0.0f);
  scratch.carry.index.resize(n, SphScratch::SampleCarry::kNone);  // emitted: nothing carried
  store.density.resize(n);
  store.pressure.resize(n);
  const bool sprayed = applySprayTransitions(world, stats);

  StepContext context{world, params, scratch, store, stats};
  context.total = n;
  context.count = store.sphCount();
  context.collider_count = world.colliders.size();
  context.support = scratch.kernel.support;
  context.spacing = sphSpacing(params);
  context.mass = scratch.particle_mass;
  context.rest_density = params.rest_density;
  context.max_dt = max_dt;
  context.span = span;
  context.previous_dt = world.last_dt > 0.0f ? world.last_dt : max_dt;
  context.dt = max_dt;

  updateNeighbours(context, stats.emitted > 0 || stats.removed > 0 || stats.pumped > 0 || sprayed);
  sampleBoundary(context);
  if (params.solver == SphSolverKind::wcsph)
    stepWcsph(context);
  else
    stepDfsph(context);
  stats.p99_density_error = densityErrorP99(store, context.count, params.rest_density, scratch.density_error);
  advect(context);
  storeCouplingForces(context);
  resolveCollisions(context);
  advanceSpray(context);
  countCalmNeighbours(context);
  finishStep(context, requested);
  stats.step_ms = msSince(t_start);
  if (stats_out) *stats_out = stats;
  return {};
}

}  // namespace
}  // namespace sph_step

SphStatus stepSph(SphWorld& world, float max_dt, SphStepStats* stats_out) {
  return sph_step::stepImpl(world, max_dt, 0.0, stats_out);
}

SphStatus stepSphWithin(SphWorld& world, double remaining, SphStepStats* stats_out) {
  if (!(remaining > 0.0) || !std::isfinite(remaining)) return {"stepSphWithin: remaining time must be finite and > 0"};
  return sph_step::stepImpl(world, static_cast<float>(std::min<double>(remaining, world.params.max_time_step)),
                            remaining, stats_out);
}

}  // namespace fluid
