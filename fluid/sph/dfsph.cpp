// Divergence-Free SPH, Bender & Koschier 2015 "Divergence-free smoothed particle hydrodynamics"
// (and the 2017 TVCG version): the divergence-free solver (§4.1) and the constant-density
// solver (§4.2) share the stiffness factor alpha_i (eq. 8-9); Algorithm 1 orders the step.
// The pair sums run in the eight-lane loops of pair_loops.hpp.
#include "fluid/sph/boundary.hpp"
#include "fluid/sph/pair_loops.hpp"
#include "fluid/sph/solvers.hpp"
#include "fluid/sph/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fluid::sph_step {
namespace {

// The 32-byte aligned view of `count` elements of v (a 4-byte type), resized to fit: the AVX2 pair
// loops load whole lane blocks with aligned loads that never straddle a cache line.
template <typename T>
T* alignedView(std::vector<T>& v, std::size_t count) {
  static_assert(sizeof(T) == 4);
  v.resize(count + 7);
  const auto address = reinterpret_cast<std::uintptr_t>(v.data());
  return v.data() + ((32 - address % 32) % 32) / sizeof(T);
}

class DfsphStep {
 public:
  explicit DfsphStep(StepContext& context)
      : context_(context),
        params_(context.params),
        scratch_(context.scratch),
        store_(context.particles),
        loops_(pairLoops(context.scratch.portable_pair_loops)),
        n_(context.count),
        rest_density_(context.rest_density),
        previous_dt_(context.previous_dt),
        divergence_(params_.divergence_solver && context.count > 0) {}

  void run();

 private:
  void densityPass();
  void viscosityAndFirstDivergenceError();
  void densityRates(std::size_t b, std::size_t e, float* rate) const;
  void divergenceError(std::size_t b, std::size_t e, double& acc) const;
  void applyKappa(float h, std::vector<float>& total);
  void capChange(std::size_t i) const;
  void divergenceSolve();
  void predictVelocities();
  void constantDensitySolve();
  void finalPass();

  StepContext& context_;
  const SphParams& params_;
  SphScratch& scratch_;
  ParticleStore& store_;
  const PairLoops& loops_;
  const std::size_t n_;
  const float rest_density_;
  const float previous_dt_;
  const bool divergence_;  // run the divergence-free solve (§4.1)
  IterationArgs iteration_args_{};
  float max_non_pressure_acceleration_ = 0.0f;
  double first_divergence_error_ = 0.0;  // the divergence solve's first error pass, from the viscosity pass
  float velocity_change_cap_ = 0.0f;     // m/s per solve (capChange)
};

// One pass over the pairs: density (the SPH sum, Becker & Teschner 2007 eq. 4, plus the
// boundary volume's share), the per-pair m grad W_ij reused by every solver iteration, and the
// sums alpha_i needs, then the per-particle terms that need only the particle's own density.
void DfsphStep::densityPass() {
  const std::uint32_t* neighbors = context_.neighbor_indices;
  const std::uint32_t* offsets = context_.neighbor_offsets;
  const std::uint32_t* candidate_end = context_.candidate_end;
  // The lane blocks (pair_loops.hpp): i's pairs from pair_start[i], padded to a multiple of 8.
  scratch_.pair_start.resize(n_ + 1);
  std::uint32_t* start = scratch_.pair_start.data();
  start[0] = 0;
  for (std::size_t i = 0; i < n_; ++i) start[i + 1] = start[i] + roundUpToBlock(candidate_end[i] - offsets[i]);
  const std::size_t slots = start[n_];  // n < 2^28 (validateSphParams), so 16 j fits in 32 bits
  const PairBlocks blocks{start, alignedView(scratch_.grad_x, slots), alignedView(scratch_.grad_y, slots),
                          alignedView(scratch_.grad_z, slots), alignedView(scratch_.pair_offset, slots)};
  for (auto* v : {&scratch_.vec_b, &scratch_.accel, &scratch_.old_position, &scratch_.vec_a}) v->resize(n_);
  for (auto* v : {&scratch_.factor, &scratch_.float_tmp, &scratch_.kappa, &scratch_.kappa_scale, &scratch_.kappa_v})
    v->resize(n_);
  const float support = context_.support, mass = context_.mass, rho0 = rest_density_;
  const float self_weight = scratch_.kernel.value(0.0f);
  const DensityConsts consts =
      DensityConsts::make(scratch_.kernel, mass, 1e-6f * support, scratch_.kernel.derivative(support / 3.0f));
  const float nu = params_.viscosity, previous_dt = previous_dt_;
  const float min_denominator = 1e-9f * rho0 * rho0 / (support * support);
  const SumMax error = reduceChunks(
      n_, SumMax{},
      [&](std::size_t b, std::size_t end, SumMax& acc) {
        DensitySums chunk_sums[kGrain];
        loops_.density_range(consts, scratch_.pos4.data(), store_.id.data(), neighbors, offsets, candidate_end,
                             static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(end), blocks, chunk_sums);
        for (std::size_t i = b; i < end; ++i) {
          const DensitySums& sums = chunk_sums[i - b];
          store_.density[i] = mass * (self_weight + sums.w) + rho0 * scratch_.boundary_volume[i];
          const float rho = store_.density[i];
          scratch_.vel4[i].w = 10.0f * nu / rho;  // read with the neighbour's velocity by the viscosity loop
          // alpha_i = rho_i / (|sum_j m_j grad W_ij|^2 + sum_j |m_j grad W_ij|^2) (2015 eq. 9). The
          // boundary mirrors the particle's pressure (p_b = p_i, so its term has weight 2 in the
          // velocity update of applyKappa); it does not move, so it adds
          // (S + rho_0 g) . (S + 2 rho_0 g) instead of |S|^2 where S = sum_j m_j grad W_ij.
          const glm::vec3 boundary_gradient = scratch_.boundary_gradient[i];
          const glm::vec3 sum = sums.grad + rho0 * boundary_gradient;
          const float denom = glm::dot(sum, sum + (kMirror - 1.0f) * rho0 * boundary_gradient) + sums.sq;
          scratch_.factor[i] = denom > min_denominator ? rho / denom : 0.0f;
          // kappa^v_i / rho_i = (Drho/Dt)_i alpha_i / (dt rho_i) (2015 eq. 9 with the factor of
          // §4.1): the per-particle part once per solve, a product per iteration.
          scratch_.kappa_scale[i] = scratch_.factor[i] / (previous_dt * rho);
          scratch_.vec_a[i] = store_.velocity[i];  // velocities before the divergence solve (capChange)
          scratch_.kappa_v[i] = 0.0f;              // sum over the divergence iterations of kappa^v_i / rho_i
          scratch_.float_tmp[i] = 0.0f;            // same for the density iterations
          scratch_.kappa[i] = 0.0f;
          scratch_.old_position[i] = store_.position[i];
          const float err = std::max(0.0f, store_.density[i] / rho0 - 1.0f);
          acc.sum += err;
          acc.max = std::max(acc.max, err);
        }
      },
      joinSumMax);
  context_.stats.avg_density_error = n_ ? static_cast<float>(error.sum / static_cast<double>(n_)) : 0.0f;
  context_.stats.max_density_error = error.max;
  const std::uint32_t* counts = context_.neighbor_counts;
  iteration_args_ = IterationArgs{scratch_.vel4.data(), blocks.gx, blocks.gy, blocks.gz, blocks.nb16, start, counts};
}

// Non-pressure accelerations: gravity + the Laplacian viscosity (Monaghan 2005 eq. 6.3 form,
// a_i = 2(d+2) nu sum_j m_j/rho_j (v_ij . x_ij)/(|x_ij|^2 + 0.01 H^2) grad W_ij, d = 3). The
// divergence solve's first error pass only reads the step-start velocities, so it runs in the
// same region (in the same chunks and order as a pass of its own: the same sum).
void DfsphStep::viscosityAndFirstDivergenceError() {
  const float eps = 0.01f * context_.support * context_.support;
  const bool viscous = params_.viscosity > 0.0f;
  const IterationArgs& a = iteration_args_;
  struct AccelError {
    float amax = 0.0f;
    double err = 0.0;
  };
  const AccelError result = reduceChunks(
      n_, AccelError{},
      [&](std::size_t b, std::size_t e, AccelError& acc) {
        glm::vec3 viscous_sums[kGrain];
        if (viscous)
          loops_.viscosity_range(scratch_.pos4.data(), a, static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e),
                                 eps, viscous_sums);
        for (std::size_t i = b; i < e; ++i) {
          scratch_.accel[i] = viscous ? params_.gravity + viscous_sums[i - b] : params_.gravity;
          acc.amax = std::max(acc.amax, glm::length(scratch_.accel[i]));
        }
        if (divergence_) divergenceError(b, e, acc.err);
      },
      [](AccelError x, const AccelError& y) {
        x.amax = std::max(x.amax, y.amax);
        x.err += y.err;
        return x;
      });
  max_non_pressure_acceleration_ = result.amax;
  first_divergence_error_ = result.err;
}

// Density rates Drho/Dt_i = sum_j m_j (v_i - v_j) . grad W_ij + rho_0 (v_i - v_b) . grad V_i
// (continuity equation) for the particles [b, e) (at most kGrain) into rate[0 .. e - b).
void DfsphStep::densityRates(std::size_t b, std::size_t e, float* rate) const {
  loops_.divergence_range(iteration_args_, static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e), rate);
  const std::vector<glm::vec3>& velocities = store_.velocity;
  for (std::size_t i = b; i < e; ++i)
    rate[i - b] += rest_density_ * (glm::dot(velocities[i], scratch_.boundary_gradient[i]) - scratch_.boundary_flux[i]);
}

// One error pass of the divergence-free solve: kappa^v_i / rho_i into kappa4 and the summed
// divergence error.
void DfsphStep::divergenceError(std::size_t b, std::size_t e, double& acc) const {
  float rates[kGrain];
  densityRates(b, e, rates);
  const std::uint32_t* counts = context_.neighbor_counts;
  for (std::size_t i = b; i < e; ++i) {
    // Only compression is corrected, and only for particles with a full enough neighbourhood
    // (2017 paper §4.1: >= 20 neighbours in 3D; the wall counts as the 9 lattice neighbours a
    // flat wall replaces per wall_share of volume), otherwise the free surface is pushed outward
    // every step and the fluid creeps apart.
    const float neighbours = static_cast<float>(counts[i]) + scratch_.boundary_volume[i] * scratch_.wall_neighbours;
    const float rate = neighbours >= 20.0f ? std::max(0.0f, rates[i - b]) : 0.0f;
    scratch_.kappa4[i].x = rate * scratch_.kappa_scale[i];
    acc += rate * previous_dt_ / rest_density_;
  }
}

// v_i -= h (sum_j m_j (k_i + k_j) grad W_ij + 2 rho_0 k_i grad V_i)   (2015 eq. 13 / 15), with
// k_i = kappa4[i].x; adds k_i to total[i]. Jacobi: all updates read the old velocities, so the new
// ones go to a second buffer that is swapped in (both buffers are kept).
void DfsphStep::applyKappa(float h, std::vector<float>& total) {
  const glm::vec4* kappa4 = scratch_.kappa4.data();
  forChunks(n_, [&](std::size_t b, std::size_t e) {
    glm::vec3 sums[kGrain];
    loops_.kappa_range(iteration_args_, kappa4, static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e), sums);
    for (std::size_t i = b; i < e; ++i) {
      const glm::vec3 dv = kMirror * rest_density_ * kappa4[i].x * scratch_.boundary_gradient[i] + sums[i - b];
      scratch_.vec_b[i] = store_.velocity[i] - h * dv;
      scratch_.vel4[i] = glm::vec4(scratch_.vec_b[i], 0.0f);  // the copy the next divergence pass reads
      total[i] += kappa4[i].x;
    }
  });
  // The spray after the water (spray.hpp) keeps its velocities.
  scratch_.vec_b.resize(store_.velocity.size());
  std::copy(store_.velocity.begin() + static_cast<std::ptrdiff_t>(n_), store_.velocity.end(),
            scratch_.vec_b.begin() + static_cast<std::ptrdiff_t>(n_));
  store_.velocity.swap(scratch_.vec_b);
}

// Each solve may change a particle's velocity by at most d / (2 dt_nominal) per step (scratch
// vec_a holds the velocities before the solve). Legit flows stay far below (the CFL bound keeps
// v dt <= cfl d); heavily overlapped input (stacked particles, a grid at half spacing) is then
// separated over a few steps at a bounded speed instead of being fired apart in one.
void DfsphStep::capChange(std::size_t i) const {
  glm::vec3& v = store_.velocity[i];
  const glm::vec3 dv = v - scratch_.vec_a[i];
  const float len = glm::length(dv);
  if (len > velocity_change_cap_) v = scratch_.vec_a[i] + dv * (velocity_change_cap_ / len);
}

// Divergence-free solver (§4.1) on the step-start velocities: Drho/Dt -> 0, at least one
// iteration (2017 paper). Not warm-started: a share of the last step's kappa^v pushes particles
// the solve never pulls back (it corrects compression only), which adds energy to a jet hitting
// a collider.
void DfsphStep::divergenceSolve() {
  const double eta = params_.max_divergence_error;
  int& iterations = context_.divergence_iterations;
  for (;;) {
    const double err =
        (iterations == 0
             ? first_divergence_error_
             : reduceChunks(
                   n_, 0.0, [this](std::size_t b, std::size_t e, double& acc) { divergenceError(b, e, acc); },
                   [](double a, double b) { return a + b; })) /
        static_cast<double>(n_);
    if ((iterations >= 1 && err <= eta) || iterations >= params_.max_iterations) break;
    applyKappa(previous_dt_, scratch_.kappa_v);
    ++iterations;
  }
}

// The time step, then the predicted velocities v* = v + dt a_nonpressure (Algorithm 1). The
// divergence solve's velocity cap runs in the same pass as the speed bound.
void DfsphStep::predictVelocities() {
  std::vector<glm::vec3>& velocities = store_.velocity;
  const float max_dt = context_.max_dt;
  const float vmax = reduce(
      n_, 0.0f,
      [&](std::size_t i, float& acc) {
        if (divergence_) capChange(i);
        acc = std::max(acc, glm::length(velocities[i] + max_dt * scratch_.accel[i]));
      },
      maxOf);
  context_.stats.max_acceleration = max_non_pressure_acceleration_;
  const float dt =
      chooseTimeStep(context_, vmax, max_non_pressure_acceleration_, false, true, &context_.dt_held_at_min);
  context_.dt = dt;
  forEach(n_, [&](std::size_t i) {
    velocities[i] += dt * scratch_.accel[i];
    scratch_.vel4[i] = glm::vec4(velocities[i], 0.0f);
    scratch_.vec_a[i] = velocities[i];
    // kappa_i / rho_i = (rho*_i - rho_0) alpha_i / (dt^2 rho_i) (2015 eq. 8-9).
    scratch_.kappa_scale[i] = scratch_.factor[i] / (dt * dt * store_.density[i]);
  });
}

// Constant-density solver (§4.2): rho*_i = rho_i + dt Drho/Dt_i -> rho_0, compression only (an
// expansion is left to gravity, or the free surface would be pulled together).
void DfsphStep::constantDensitySolve() {
  const float dt = context_.dt, rho0 = rest_density_;
  if (params_.warm_start) {
    // Warm start (2017 §4.3), off by default (SphParams::warm_start says why): a share of the
    // last step's summed stiffness, applied only where the particle compresses now, since the
    // solver never pulls particles back. The stored sum was found for the last step's dt; the part
    // that removed a standing compression scales as 1 / dt^2 (eq. 8-9), so when dt grew the share
    // is scaled by (dt_prev / dt)^2 and the warm start displaces no further than the last solve.
    const float share = params_.warm_start_share;
    const float warm = dt > previous_dt_ ? share * (previous_dt_ / dt) * (previous_dt_ / dt) : share;
    forChunks(n_, [&](std::size_t b, std::size_t e) {
      float rates[kGrain];
      densityRates(b, e, rates);
      for (std::size_t i = b; i < e; ++i)
        scratch_.kappa4[i].x = store_.density[i] + dt * rates[i - b] > rho0 ? warm * scratch_.warm_kappa[i] : 0.0f;
    });
    applyKappa(dt, scratch_.float_tmp);
  }
  const double eta = params_.max_density_error;
  int& iterations = context_.density_iterations;
  for (;;) {
    const double err = reduceChunks(
                           n_, 0.0,
                           [&](std::size_t b, std::size_t e, double& acc) {
                             float rates[kGrain];
                             densityRates(b, e, rates);
                             for (std::size_t i = b; i < e; ++i) {
                               const float excess = std::max(0.0f, store_.density[i] + dt * rates[i - b] - rho0);
                               scratch_.kappa4[i].x = excess * scratch_.kappa_scale[i];
                               acc += excess / rho0;
                             }
                           },
                           [](double a, double b) { return a + b; }) /
                       static_cast<double>(n_);
    if ((iterations >= params_.min_iterations && err <= eta) || iterations >= params_.max_iterations) break;
    applyKappa(dt, scratch_.float_tmp);
    ++iterations;
  }
}

// The velocity cap, the solver outputs, (without XSPH) the advection and (up to kFusedColliders
// colliders) the boundary coupling sums in one pass.
void DfsphStep::finalPass() {
  const float dt = context_.dt, previous_dt = previous_dt_;
  const bool advect = params_.xsph <= 0.0f;
  context_.advected = advect;
  auto finalTerms = [&](std::size_t i) {
    capChange(i);
    scratch_.warm_kappa[i] = scratch_.float_tmp[i];
    // Effective pressure p_i = rho_i^2 (kappa_i / rho_i summed) for output; impulse for coupling.
    store_.pressure[i] =
        store_.density[i] * store_.density[i] * (scratch_.float_tmp[i] + scratch_.kappa_v[i] * previous_dt / dt);
    scratch_.kappa[i] = dt * scratch_.float_tmp[i] + previous_dt * scratch_.kappa_v[i];
    if (advect) store_.position[i] += dt * store_.velocity[i];
  };
  const std::size_t collider_count = context_.collider_count;
  if (collider_count <= kFusedColliders) {
    context_.coupled = true;
    context_.coupling = reduce(
        n_, CouplingSums{},
        [&](std::size_t i, CouplingSums& acc) {
          finalTerms(i);
          for (std::size_t c = 0; c < collider_count; ++c)
            if (context_.world.colliders[c].boundary_pressure) addCouplingTerm(context_, c, i, acc.per_collider[c]);
        },
        [](CouplingSums a, const CouplingSums& b) {
          for (std::size_t c = 0; c < kFusedColliders; ++c) {
            a.per_collider[c].force += b.per_collider[c].force;
            a.per_collider[c].torque += b.per_collider[c].torque;
          }
          return a;
        });
  } else {
    forEach(n_, finalTerms);
  }
}

void DfsphStep::run() {
  densityPass();
  scratch_.kappa4.resize(n_);
  viscosityAndFirstDivergenceError();
  // The cap uses the velocity-independent step bound, so it cannot grow as the CFL shrinks dt.
  velocity_change_cap_ = 0.5f * context_.spacing / chooseTimeStep(context_, 0.0f, 0.0f, false, false);
  context_.dt = context_.max_dt;
  if (divergence_) divergenceSolve();
  predictVelocities();
  if (n_ > 0) {
    constantDensitySolve();
    finalPass();
  }
}

}  // namespace

void stepDfsph(StepContext& context) { DfsphStep(context).run(); }

}  // namespace fluid::sph_step
