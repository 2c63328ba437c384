// Weakly compressible SPH, Becker & Teschner 2007 "Weakly compressible SPH for free surface
// flows": Tait equation (eq. 7), symmetric pressure force (eq. 6), artificial viscosity
// (eq. 10-11), time step from the CFL and force conditions (§4, eq. 12-13).
#include "fluid/sph/boundary.hpp"
#include "fluid/sph/pair_loops.hpp"
#include "fluid/sph/solvers.hpp"
#include "fluid/sph/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace fluid::sph_step {
namespace {

// Tait equation (eq. 7) with B = rho_0 c_s^2 / gamma. Negative pressures are clamped to zero so
// the free surface does not clump (tensile instability). The ratio is clamped to 1.5: real flows
// stay within a few per cent, and degenerate input (particles stacked on one point) would
// otherwise produce pressures of 1e12 B.
inline float taitPressure(float density, float rest_density, float tait_b, float exponent, bool gamma7) {
  const float ratio = std::min(density / rest_density, 1.5f);
  float power;
  if (gamma7) {  // the default gamma = 7 by products (a powf call cost more than the rest of the loop)
    const float r2 = ratio * ratio, r4 = r2 * r2;
    power = r4 * r2 * ratio;
  } else {
    power = std::pow(ratio, exponent);
  }
  return std::max(0.0f, tait_b * (power - 1.0f));
}

// One pass over the Verlet candidates: filters them to the exact list (|x_ij| < H, written to the
// front of i's range), the density (eq. 4, plus the boundary volume's share), the per-pair
// m grad W_ij, and the per-particle terms that need only the particle's own density: the Tait
// pressure, p_i / rho_i^2 and the viscosity coefficient 10 nu / rho_i.
void densityPass(StepContext& context) {
  SphScratch& scratch = context.scratch;
  ParticleStore& store = context.particles;
  const SphParams& params = context.params;
  const std::size_t n = context.count;
  const float support = context.support, mass = context.mass, rest_density = context.rest_density;
  const std::size_t pair_count = scratch.neighbors.indices.size();
  scratch.grad_x.resize(pair_count);
  scratch.grad_y.resize(pair_count);
  scratch.grad_z.resize(pair_count);
  scratch.accel.resize(n);
  scratch.float_tmp.resize(n);    // 10 nu / rho_i
  scratch.density_adv.resize(n);  // p_i / rho_i^2
  scratch.kappa.resize(n);        // boundary impulse per unit of grad V (coupling forces)
  scratch.old_position.resize(n);
  float* const grad_x = scratch.grad_x.data();
  float* const grad_y = scratch.grad_y.data();
  float* const grad_z = scratch.grad_z.data();
  float* const viscosity_coef = scratch.float_tmp.data();
  float* const pressure_over_rho2 = scratch.density_adv.data();
  const float self_weight = scratch.kernel.value(0.0f);
  const float steepest = scratch.kernel.derivative(support / 3.0f);
  const float support2 = support * support;
  const float r_min = 1e-6f * support;
  const float tait_b = rest_density * params.sound_speed * params.sound_speed / params.tait_exponent;
  const bool gamma7 = params.tait_exponent == 7.0f;
  const float nu = params.viscosity;
  const glm::vec3* __restrict positions = store.position.data();
  std::uint32_t* __restrict counts = scratch.neighbors.counts.data();
  std::uint32_t* const neighbors = context.neighbor_indices;
  const std::uint32_t* candidates = context.verlet_candidates;
  const std::uint32_t* offsets = context.neighbor_offsets;
  const std::uint32_t* candidate_end = context.candidate_end;
  const CubicSplineKernel kernel = scratch.kernel;
  const SumMax error = reduceChunks(
      n, SumMax{},
      [&](std::size_t b, std::size_t end, SumMax& acc) {
        for (std::size_t i = b; i < end; ++i) {
          float sum = self_weight;
          const glm::vec3 xi = positions[i];
          const std::uint32_t first = offsets[i], last = candidate_end[i];
          std::uint32_t out = first;
          for (std::uint32_t k = first; k < last; ++k) {
            const std::uint32_t j = candidates[k];
            const glm::vec3 x = xi - positions[j];
            // The same float test as the search (dot(x_ij, x_ij) < H^2), so the filtered list is
            // exactly a fresh search's.
            if (!(glm::dot(x, x) < support2)) continue;
            neighbors[out] = j;
            const float r = glm::length(x);
            float wr, dr;
            kernel.evaluateInside(r, wr, dr);  // r <= H: the pair is in the list
            sum += wr;
            // Coincident particles: the steepest slope along an id-fixed direction (densityLane).
            const glm::vec3 g =
                r > r_min ? mass * (dr * x) : (mass * steepest) * coincidentDirection(store.id[i], store.id[j]);
            grad_x[out] = g.x;
            grad_y[out] = g.y;
            grad_z[out] = g.z;
            ++out;
          }
          counts[i] = out - first;
          const float rho = mass * sum + rest_density * scratch.boundary_volume[i];
          store.density[i] = rho;
          store.pressure[i] = taitPressure(rho, rest_density, tait_b, params.tait_exponent, gamma7);
          pressure_over_rho2[i] = store.pressure[i] / (rho * rho);
          viscosity_coef[i] = 10.0f * nu / rho;
          scratch.kappa[i] = 0.0f;
          scratch.old_position[i] = positions[i];
          const float err = std::max(0.0f, store.density[i] / rest_density - 1.0f);
          acc.sum += err;
          acc.max = std::max(acc.max, err);
        }
      },
      joinSumMax);
  context.stats.avg_density_error = n ? static_cast<float>(error.sum / static_cast<double>(n)) : 0.0f;
  context.stats.max_density_error = error.max;
}

// Accelerations: gravity, the symmetric pressure force (eq. 6), the Laplacian viscosity
// (Monaghan 2005 eq. 6.3 form, a_i = 2(d+2) nu sum_j m_j/rho_j (v_ij . x_ij)/(|x_ij|^2 + 0.01 H^2)
// grad W_ij, d = 3) and the artificial viscosity Pi_ij (eq. 10-11), in one pass over the pairs.
template <bool kViscosity>
void accelerations(StepContext& context) {
  SphScratch& scratch = context.scratch;
  const ParticleStore& store = context.particles;
  const SphParams& params = context.params;
  const float support = context.support, rest_density = context.rest_density;
  const float alpha = params.artificial_viscosity, sound_speed = params.sound_speed;
  const float h = context.spacing;  // B&T's smoothing length h (support 2h = H)
  const glm::vec3* __restrict positions = store.position.data();
  const glm::vec3* __restrict velocities = store.velocity.data();
  const float* __restrict viscosity_coef = scratch.float_tmp.data();
  const float* __restrict pressure_over_rho2 = scratch.density_adv.data();
  const float* const grad_x = scratch.grad_x.data();
  const float* const grad_y = scratch.grad_y.data();
  const float* const grad_z = scratch.grad_z.data();
  const std::uint32_t* offsets = context.neighbor_offsets;
  const std::uint32_t* counts = context.neighbor_counts;
  const std::uint32_t* neighbors = context.neighbor_indices;
  const float eps = 0.01f * support * support;
  forEach(context.count, [&](std::size_t i) {
    glm::vec3 a = params.gravity;
    const float pi = pressure_over_rho2[i];
    const glm::vec3 xi = positions[i], vi = velocities[i];
    const std::uint32_t first = offsets[i], last = offsets[i] + counts[i];
    for (std::uint32_t k = first; k < last; ++k) {
      const std::uint32_t j = neighbors[k];
      const glm::vec3 xij = xi - positions[j];
      const float vx = glm::dot(vi - velocities[j], xij);
      const float denom = glm::dot(xij, xij) + eps;
      float coef = 0.0f;
      if constexpr (kViscosity) coef = viscosity_coef[j] * (vx / denom);
      if (alpha > 0.0f && vx < 0.0f) {
        const float nu_ij = 2.0f * alpha * h * sound_speed / (store.density[i] + store.density[j]);
        coef += nu_ij * vx / denom;  // - Pi_ij, Pi_ij = -nu_ij vx / denom
      }
      coef -= pi + pressure_over_rho2[j];  // symmetric pressure force (eq. 6)
      a += coef * glm::vec3(grad_x[k], grad_y[k], grad_z[k]);
    }
    // Boundary: the same symmetric pressure term against the wall volume with the mirrored
    // pressure p_b = p_i, rho_b = rho_i.
    a -= 2.0f * rest_density * pi * scratch.boundary_gradient[i];
    scratch.accel[i] = a;
  });
}

}  // namespace

void stepWcsph(StepContext& context) {
  densityPass(context);
  if (context.params.viscosity > 0.0f)
    accelerations<true>(context);
  else
    accelerations<false>(context);
  SphScratch& scratch = context.scratch;
  std::vector<glm::vec3>& velocities = context.particles.velocity;
  const std::size_t n = context.count;
  const float max_speed = reduce(
      n, 0.0f, [&](std::size_t i, float& acc) { acc = std::max(acc, glm::length(velocities[i])); }, maxOf);
  const float max_acceleration = reduce(
      n, 0.0f, [&](std::size_t i, float& acc) { acc = std::max(acc, glm::length(scratch.accel[i])); }, maxOf);
  context.stats.max_acceleration = max_acceleration;
  const float dt = chooseTimeStep(context, max_speed, max_acceleration, true, true, &context.dt_held_at_min);
  context.dt = dt;
  forEach(n, [&](std::size_t i) {
    velocities[i] += dt * scratch.accel[i];
    scratch.kappa[i] = dt * scratch.density_adv[i];
  });
}

}  // namespace fluid::sph_step
