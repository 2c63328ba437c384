// World management for fluid/sph: parameters, particle insertion/removal, emitters, sinks,
// diagnostics and the substepping driver. The step is in sph_step.cpp.
#include "fluid/sph/sph.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fluid {

bool parseSphSolver(const std::string& name, SphSolverKind& out) {
  if (name == "wcsph") {
    out = SphSolverKind::wcsph;
    return true;
  }
  if (name == "dfsph") {
    out = SphSolverKind::dfsph;
    return true;
  }
  return false;
}

const char* sphSolverName(SphSolverKind kind) { return kind == SphSolverKind::wcsph ? "wcsph" : "dfsph"; }

float sphParticleMass(const SphParams& params) {
  // Mass such that a particle inside an infinite cubic lattice of spacing d has rho = rho_0
  // exactly: m = rho_0 / sum_j W(x_j). A plain m = rho_0 d^3 would leave the discrete density a
  // few per cent off rho_0 and the solvers would fight that bias forever.
  const CubicSplineKernel kernel = CubicSplineKernel::make(sphSupport(params));
  const float d = sphSpacing(params);
  const int reach = 2;  // H = 2d
  double sum = 0.0;
  for (int z = -reach; z <= reach; ++z)
    for (int y = -reach; y <= reach; ++y)
      for (int x = -reach; x <= reach; ++x)
        sum += kernel.value(d * std::sqrt(static_cast<float>(x * x + y * y + z * z)));
  return static_cast<float>(params.rest_density / sum);
}

namespace {

std::string fieldError(const char* field, float value, const char* range) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "sph parameter %s = %g is out of range (%s)", field, static_cast<double>(value),
                range);
  return buf;
}

}  // namespace

SphStatus validateSphParams(const SphParams& p) {
  struct Check {
    const char* name;
    float value;
    float lo, hi;
    const char* range;
  };
  const Check checks[] = {
      {"particle_radius", p.particle_radius, 1e-5f, 10.0f, "1e-5 .. 10 m"},
      {"rest_density", p.rest_density, 1e-3f, 1e6f, "1e-3 .. 1e6 kg/m^3"},
      {"viscosity", p.viscosity, 0.0f, 100.0f, "0 .. 100"},
      {"xsph", p.xsph, 0.0f, 1.0f, "0 .. 1"},
      {"cfl", p.cfl, 0.01f, 1.0f, "0.01 .. 1"},
      {"force_bound", p.force_bound, 0.0f, 1.0f, "0 (off) .. 1"},
      {"max_time_step", p.max_time_step, 1e-7f, 1.0f, "1e-7 .. 1 s"},
      {"min_time_step", p.min_time_step, 1e-9f, p.max_time_step, "1e-9 s .. max_time_step"},
      {"max_speed", p.max_speed, 0.0f, 1e6f, "0 (off) .. 1e6 m/s"},
      {"sound_speed", p.sound_speed, 1e-3f, 1e5f, "1e-3 .. 1e5 m/s"},
      {"tait_exponent", p.tait_exponent, 1.0f, 10.0f, "1 .. 10"},
      {"artificial_viscosity", p.artificial_viscosity, 0.0f, 10.0f, "0 .. 10"},
      {"max_density_error", p.max_density_error, 1e-7f, 1.0f, "1e-7 .. 1"},
      {"max_divergence_error", p.max_divergence_error, 1e-7f, 1.0f, "1e-7 .. 1"},
      {"collision_skin", p.collision_skin, 0.0f, 10.0f, "0 .. 10 m"},
      {"spray_speed", p.spray_speed, 0.0f, 1e6f, "0 (off) .. 1e6 m/s"},
      {"spray_terminal_speed", p.spray_terminal_speed, 0.0f, 1e6f, "0 (no drag) .. 1e6 m/s"},
      {"contact_standoff", p.contact_standoff, 0.0f, 4.0f, "0 .. 4 (x particle_radius)"},
      {"spray_water_drag", p.spray_water_drag, 0.0f, 1e3f, "0 (none) .. 1000"},
      {"spray_neighbours", static_cast<float>(p.spray_neighbours), 1.0f, 1000.0f, "1 .. 1000"},
      {"warm_start_share", p.warm_start_share, 0.0f, 1.0f, "0 .. 1"},
  };
  for (const Check& c : checks) {
    if (!std::isfinite(c.value) || c.value < c.lo || c.value > c.hi) return {fieldError(c.name, c.value, c.range)};
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(p.gravity[a])) return {fieldError("gravity", p.gravity[a], "finite")};
    if (std::isnan(p.domain_min[a]) || std::isnan(p.domain_max[a]) || p.domain_min[a] > p.domain_max[a])
      return {fieldError("domain_min/domain_max", p.domain_min[a], "finite, min <= max")};
  }
  // The DFSPH pair loops address neighbours by 32-bit byte offsets 16 j.
  if (p.max_particles >= (std::size_t{1} << 28))
    return {fieldError("max_particles", static_cast<float>(p.max_particles), "< 2^28 = 268435456")};
  if (p.min_iterations < 0 || p.max_iterations < 1 || p.min_iterations > p.max_iterations)
    return {
        fieldError("min_iterations/max_iterations", static_cast<float>(p.max_iterations), "0 <= min <= max, max >= 1")};
  return {};
}

bool addSphParticle(SphWorld& world, glm::vec3 position, glm::vec3 velocity) {
  if (world.particles.size() >= world.params.max_particles) return false;
  return addSphParticleWithId(world, world.next_id++, position, velocity);
}

bool addSphParticleWithId(SphWorld& world, std::uint32_t id, glm::vec3 position, glm::vec3 velocity) {
  ParticleStore& s = world.particles;
  std::vector<std::uint32_t>& last = world.scratch.last_neighbours;
  last.resize(s.size(), SphScratch::kUnknownNeighbours);
  s.position.push_back(position);
  s.velocity.push_back(velocity);
  s.density.push_back(world.params.rest_density);
  s.pressure.push_back(0.0f);
  s.id.push_back(id);
  last.push_back(SphScratch::kUnknownNeighbours);
  // A new particle is SPH water: it goes in front of the spray, which stays last in the store.
  const std::size_t spray = std::min(s.spray_count, s.size() - 1);
  if (spray > 0) {
    const auto toFront = [spray](auto& v) { std::rotate(v.end() - 1 - static_cast<std::ptrdiff_t>(spray), v.end() - 1, v.end()); };
    toFront(s.position);
    toFront(s.velocity);
    toFront(s.density);
    toFront(s.pressure);
    toFront(s.id);
    toFront(last);
  }
  return true;
}

bool sphNearCollider(const SphWorld& world, glm::vec3 p, float radius) {
  for (const SphCollider& c : world.colliders) {
    const glm::vec3 local = toColliderSpace(c.pose, p);
    ColliderSample sample;
    c.shape->query(std::span<const glm::vec3>(&local, 1), std::span<ColliderSample>(&sample, 1));
    if (sample.valid && sample.distance < radius) return true;
  }
  return false;
}

std::size_t addSphBlock(SphWorld& world, glm::vec3 lo, glm::vec3 hi, glm::vec3 velocity) {
  const float d = sphSpacing(world.params);
  const float r = world.params.particle_radius;
  std::size_t added = 0;
  const glm::ivec3 count = glm::max(glm::ivec3(glm::floor((hi - lo) / d + 1e-4f)), glm::ivec3(0));
  for (int z = 0; z < count.z; ++z)
    for (int y = 0; y < count.y; ++y)
      for (int x = 0; x < count.x; ++x) {
        if (!addSphParticle(world, lo + glm::vec3(r) + d * glm::vec3(x, y, z), velocity)) return added;
        ++added;
      }
  return added;
}

void reserveSph(SphWorld& world, std::size_t capacity) {
  ParticleStore& s = world.particles;
  s.position.reserve(capacity);
  s.velocity.reserve(capacity);
  s.density.reserve(capacity);
  s.pressure.reserve(capacity);
  s.id.reserve(capacity);
  SphScratch& w = world.scratch;
  for (auto* v : {&w.vec_a, &w.vec_b, &w.boundary_gradient, &w.old_position, &w.accel}) v->reserve(capacity);
  for (auto* v : {&w.factor, &w.kappa, &w.kappa_v, &w.warm_kappa, &w.density_adv, &w.kappa_scale, &w.boundary_volume,
                  &w.boundary_flux, &w.float_tmp, &w.density_error})
    v->reserve(capacity);
  w.vel4.reserve(capacity);
  w.kappa4.reserve(capacity);
  w.pos4.reserve(capacity);
  w.u32_tmp.reserve(capacity);
  w.sorted_keys.reserve(capacity);
  w.keep.reserve(capacity);
  w.last_neighbours.reserve(capacity);
  w.spray_order.reserve(capacity);
  w.collide_stale.reserve(capacity);
  w.carry.position.reserve(capacity);
  w.carry.index.reserve(capacity);
  w.carry.index_tmp.reserve(capacity);
  reserveNeighborLists(w.neighbors, capacity);
  reserveNeighborLists(w.verlet, capacity);
  w.verlet_position.reserve(capacity);
  w.grid.order.reserve(capacity);
  w.grid.particle_key.reserve(capacity);
}

namespace {
constexpr std::size_t kGrain = 512;
}

double sphKineticEnergy(const SphWorld& world) {
  const auto& v = world.particles.velocity;
  const double m = sphParticleMass(world.params);
  return 0.5 * m *
         par::parallelDeterministicReduce(
             tbb::blocked_range<std::size_t>(0, v.size(), kGrain), 0.0,
             [&](const tbb::blocked_range<std::size_t>& r, double acc) {
               for (std::size_t i = r.begin(); i != r.end(); ++i) acc += static_cast<double>(glm::dot(v[i], v[i]));
               return acc;
             },
             [](double a, double b) { return a + b; });
}

double sphPotentialEnergy(const SphWorld& world) {
  const auto& x = world.particles.position;
  const double m = sphParticleMass(world.params);
  const glm::vec3 g = world.params.gravity;
  return m * par::parallelDeterministicReduce(
                 tbb::blocked_range<std::size_t>(0, x.size(), kGrain), 0.0,
                 [&](const tbb::blocked_range<std::size_t>& r, double acc) {
                   for (std::size_t i = r.begin(); i != r.end(); ++i) acc -= static_cast<double>(glm::dot(g, x[i]));
                   return acc;
                 },
                 [](double a, double b) { return a + b; });
}

void sphDensityError(const SphWorld& world, float& mean, float& max) {
  const auto& rho = world.particles.density;
  const float rho0 = world.params.rest_density;
  struct Acc {
    double sum = 0.0;
    float max = 0.0f;
  };
  const Acc a = par::parallelDeterministicReduce(
      tbb::blocked_range<std::size_t>(0, rho.size(), kGrain), Acc{},
      [&](const tbb::blocked_range<std::size_t>& r, Acc acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const float e = std::max(0.0f, rho[i] / rho0 - 1.0f);
          acc.sum += e;
          acc.max = std::max(acc.max, e);
        }
        return acc;
      },
      [](Acc x, const Acc& y) {
        x.sum += y.sum;
        x.max = std::max(x.max, y.max);
        return x;
      });
  mean = rho.empty() ? 0.0f : static_cast<float>(a.sum / static_cast<double>(rho.size()));
  max = a.max;
}

double sphCompressedVolume(const SphWorld& world) {
  const auto& rho = world.particles.density;
  const double m = sphParticleMass(world.params);
  const float rho0 = world.params.rest_density;
  return m * par::parallelDeterministicReduce(
                 tbb::blocked_range<std::size_t>(0, rho.size(), kGrain), 0.0,
                 [&](const tbb::blocked_range<std::size_t>& r, double acc) {
                   for (std::size_t i = r.begin(); i != r.end(); ++i) acc += 1.0 / std::max(rho[i], rho0);
                   return acc;
                 },
                 [](double a, double b) { return a + b; });
}

SphStatus advanceSphImpl(SphWorld& world, double duration, void (*cb)(void*, const SphStepStats&), void* ctx,
                         std::size_t max_steps) {
  if (!(duration >= 0.0) || !std::isfinite(duration)) return {"advanceSph: duration must be finite and >= 0"};
  const double target = world.time + duration;
  const std::size_t nc = world.colliders.size();
  auto& force = world.scratch.reduce_force;
  auto& torque = world.scratch.reduce_torque;
  force.assign(nc, glm::vec3(0.0f));
  torque.assign(nc, glm::vec3(0.0f));
  double elapsed = 0.0;
  std::size_t steps = 0;
  // Tolerance: float time steps cannot hit a double target exactly.
  while (target - world.time > 1e-7) {
    if (steps++ >= max_steps) return {"advanceSph: more than max_steps steps needed"};
    SphStepStats stats;
    // The remaining time is spread over equal steps (stepSphWithin): a step cut to land on the
    // target could be a sliver, which DFSPH turns into a velocity kick (time_step.cpp).
    SphStatus status = stepSphWithin(world, target - world.time, &stats);
    if (!status.ok()) {
      if (cb && stats.nonfinite > 0) cb(ctx, stats);  // the refused step's count (sph.hpp)
      return status;
    }
    for (std::size_t c = 0; c < nc && c < world.colliders.size(); ++c) {
      force[c] += world.colliders[c].force * stats.dt;
      torque[c] += world.colliders[c].torque * stats.dt;
    }
    elapsed += stats.dt;
    if (cb) cb(ctx, stats);
  }
  if (elapsed > 0.0) {
    for (std::size_t c = 0; c < nc && c < world.colliders.size(); ++c) {
      world.colliders[c].force = force[c] / static_cast<float>(elapsed);
      world.colliders[c].torque = torque[c] / static_cast<float>(elapsed);
    }
  }
  return {};
}

void sphPositionsAt(const SphWorld& world, double t, std::vector<glm::vec3>& out) {
  const auto& x = world.particles.position;
  const auto& x0 = world.scratch.old_position;  // the last step's start positions, in today's order
  out.resize(x.size());
  const double start = world.time - world.last_dt;
  const double f = world.last_dt > 0.0f ? std::clamp((t - start) / world.last_dt, 0.0, 1.0) : 1.0;
  if (f >= 1.0 || x0.size() != x.size()) {  // exactly the end state (x0 + 1 (x - x0) may round)
    std::copy(x.begin(), x.end(), out.begin());
    return;
  }
  const float s = static_cast<float>(f);
  par::parallelFor(tbb::blocked_range<std::size_t>(0, x.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = x0[i] + s * (x[i] - x0[i]);
  });
}

void addStepTotals(SphStepTotals& totals, const SphStepStats& step) {
  totals.steps += step.dt > 0.0f ? 1 : 0;  // a refused step (dt = 0) adds only its non-finite count
  if (step.dt > 0.0f) {
    totals.density_error_sum += step.avg_density_error;
    totals.max_density_error = std::max(totals.max_density_error, step.max_density_error);
    totals.p99_density_error = std::max(totals.p99_density_error, step.p99_density_error);
  }
  totals.pushed_out += step.pushed_out;
  totals.max_push_depth = std::max(totals.max_push_depth, step.max_push_depth);
  totals.speed_clamps += step.speed_clamps;
  totals.dt_min_clamps += step.dt_held_at_min ? 1 : 0;
  totals.dt_request_cuts += step.dt_limited_by_request ? 1 : 0;
  totals.nonfinite += step.nonfinite;
  totals.solver_iterations += static_cast<std::size_t>(std::max(0, step.density_iterations)) +
                              static_cast<std::size_t>(std::max(0, step.divergence_iterations));
}

void addStepTotals(SphStepTotals& totals, const SphStepTotals& more) {
  totals.steps += more.steps;
  totals.density_error_sum += more.density_error_sum;
  totals.max_density_error = std::max(totals.max_density_error, more.max_density_error);
  totals.p99_density_error = std::max(totals.p99_density_error, more.p99_density_error);
  totals.pushed_out += more.pushed_out;
  totals.max_push_depth = std::max(totals.max_push_depth, more.max_push_depth);
  totals.speed_clamps += more.speed_clamps;
  totals.dt_min_clamps += more.dt_min_clamps;
  totals.dt_request_cuts += more.dt_request_cuts;
  totals.nonfinite += more.nonfinite;
  totals.solver_iterations += more.solver_iterations;
}

bool sphTotalsWarn(const SphStepTotals& totals, float deep_push) {
  return totals.speed_clamps > 0 || totals.dt_min_clamps > 0 || totals.nonfinite > 0 ||
         totals.max_push_depth > deep_push;
}

}  // namespace fluid
