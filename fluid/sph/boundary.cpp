// Boundary tables and the step-start boundary samples (boundary.hpp).
#include "fluid/sph/boundary.hpp"

#include <cmath>

namespace fluid::sph_step {
namespace {

// Boundary volume of a planar wall: the collider side of the kernel support treated as a filled
// half-space at signed distance s (s > 0: particle outside the solid). A(s) = integral of W over
// the plane at distance s = 2 pi int_{|s|}^{H} W(r) r dr; V(s) = int_s^H A(t) dt, so V(-H) = 1,
// V(0) = 1/2, V(H) = 0 and dV/ds = -A(s). The planar approximation of Koschier & Bender 2017's
// volume map, exact for planes, first order for curved colliders.
void tabulateWall(SphScratch& scratch) {
  const CubicSplineKernel& k = scratch.kernel;
  const double H = k.support;
  scratch.wall_area.resize(kWallTable + 1);
  scratch.wall_volume.resize(kWallTable + 1);
  const int sub = 64;
  for (int i = 0; i <= kWallTable; ++i) {
    const double s = -H + 2.0 * H * i / kWallTable;
    const double a = std::abs(s);
    double integral = 0.0;  // Simpson on [a, H] of W(r) r
    const int m = 2 * sub;
    const double hstep = (H - a) / m;
    for (int j = 0; j <= m; ++j) {
      const double r = a + j * hstep;
      const double f = k.value(static_cast<float>(r)) * r;
      integral += f * ((j == 0 || j == m) ? 1.0 : (j % 2 ? 4.0 : 2.0));
    }
    integral *= hstep / 3.0;
    scratch.wall_area[i] = static_cast<float>(2.0 * 3.14159265358979 * integral);
  }
  // V by trapezoid integration of A from H downwards.
  scratch.wall_volume[kWallTable] = 0.0f;
  double v = 0.0;
  const double ds = 2.0 * H / kWallTable;
  for (int i = kWallTable - 1; i >= 0; --i) {
    v += 0.5 * (scratch.wall_area[i] + scratch.wall_area[i + 1]) * ds;
    scratch.wall_volume[i] = static_cast<float>(v);
  }
}

}  // namespace

void ensureStepTables(SphWorld& world) {
  SphScratch& scratch = world.scratch;
  const float H = sphSupport(world.params);
  if (scratch.initialised && scratch.kernel.support == H && scratch.particle_mass == sphParticleMass(world.params))
    return;
  scratch.kernel = CubicSplineKernel::make(H);
  scratch.particle_mass = sphParticleMass(world.params);
  tabulateWall(scratch);
  // Calibration: a particle of a resting lattice at distance r from a plane wall misses exactly the
  // lattice layers beyond the wall: volume share f and normal gradient g_miss (lattice sums, same
  // lattice as the mass). The continuous half-space gives V(r) = 0.188 > f = 0.150 and
  // A(r) = 0.49 < g_miss = 0.51 (H = 2d, in units of d): walls would be over-dense and, worse,
  // pull wall particles in. We use beta V(s + delta) with beta, delta solving
  // beta V(r + delta) = f and beta A(r + delta) = g_miss, so a resting lattice at a wall has
  // exactly rho_0 and a balanced gradient.
  {
    const float d = sphSpacing(world.params);
    const float r = world.params.particle_radius;
    double layer = 0.0, grad = 0.0;
    for (int z = -2; z <= -1; ++z)
      for (int y = -2; y <= 2; ++y)
        for (int x = -2; x <= 2; ++x) {
          const float len = d * std::sqrt(static_cast<float>(x * x + y * y + z * z));
          layer += scratch.kernel.value(len);
          grad += -scratch.kernel.derivative(len) * (-z * d) / len;
        }
    const float scale = scratch.particle_mass / world.params.rest_density;
    const float f = static_cast<float>(layer * scale), g = static_cast<float>(grad * scale);
    // V/A decreases with s on (0, H): bisection for V(r + delta) / A(r + delta) = f / g.
    float lo = 0.0f, hi = H - r;
    for (int it = 0; it < 60; ++it) {
      const float mid = 0.5f * (lo + hi);
      const float ratio = lookupWallTable(scratch.wall_volume, r + mid, H) /
                          std::max(lookupWallTable(scratch.wall_area, r + mid, H), 1e-30f);
      if (ratio > f / g)
        lo = mid;
      else
        hi = mid;
    }
    scratch.wall_shift = 0.5f * (lo + hi);
    scratch.wall_neighbours = 9.0f / f;  // a flat wall stands in for 9 lattice neighbours (2 layers at H = 2d)
    const float beta = f / lookupWallTable(scratch.wall_volume, r + scratch.wall_shift, H);
    for (float& v : scratch.wall_volume) v *= beta;
    for (float& a : scratch.wall_area) a *= beta;
  }
  scratch.initialised = true;
}

void sampleBoundary(StepContext& context) {
  SphWorld& world = context.world;
  SphScratch& scratch = context.scratch;
  const std::vector<glm::vec3>& positions = context.particles.position;
  const std::size_t n = context.count, collider_count = context.collider_count;
  const float support = context.support, max_time_step = context.params.max_time_step;
  // Several colliders: the solid is the union of their solid sides. Summing the volumes would count
  // the overlap twice at edges and corners (17 % density error at a box corner). We combine them as
  // V = 1 - prod_c (1 - V_c), exact for one plane and for orthogonal planes under a separable kernel,
  // close for the cubic spline; collider c's share of grad V is grad V_c prod_{c' != c} (1 - V_c').
  // One parallel region: each chunk queries every collider, then combines the samples.
  scratch.start_samples.resize(collider_count);
  for (auto& samples : scratch.start_samples) samples.resize(n);
  scratch.boundary_volume.resize(n);
  scratch.boundary_gradient.resize(n);
  scratch.boundary_flux.resize(n);
  scratch.boundary_product.resize(n);
  // Whether collider c moves (its wall velocity enters the flux and the speed bound): once per
  // step, not per particle.
  scratch.collider_moving.resize(collider_count);
  for (std::size_t c = 0; c < collider_count; ++c) {
    const ColliderPose& pose = world.colliders[c].pose;
    scratch.collider_moving[c] = glm::dot(pose.linear_velocity, pose.linear_velocity) > 0.0f ||
                                 glm::dot(pose.angular_velocity, pose.angular_velocity) > 0.0f;
  }
  context.collider_speed = reduceChunks(
      n, 0.0f,
      [&](std::size_t b, std::size_t e, float& acc) {
        std::uint32_t which[kGrain];
        for (std::size_t i = b; i < e; ++i) which[i - b] = static_cast<std::uint32_t>(i);
        for (std::size_t c = 0; c < collider_count; ++c)
          ColliderQuery(world.colliders[c], world.colliders[c].pose)
              .run(positions, which, static_cast<std::uint32_t>(e - b), scratch.start_samples[c]);
        for (std::size_t i = b; i < e; ++i) {
          float product = 1.0f;  // prod_c (1 - V_c)
          for (std::size_t c = 0; c < collider_count; ++c)
            product *= openFraction(scratch, world.colliders[c], scratch.start_samples[c][i]);
          glm::vec3 gradient(0.0f);
          float flux = 0.0f;
          for (std::size_t c = 0; c < collider_count; ++c) {
            const SphCollider& collider = world.colliders[c];
            const ColliderSample& sample = scratch.start_samples[c][i];
            const bool moving = scratch.collider_moving[c] != 0;
            if (collider.boundary_pressure) {
              const glm::vec3 grad = boundaryShare(scratch, sample, product);
              gradient += grad;
              if (moving) flux += glm::dot(colliderVelocityAt(collider.pose, positions[i]), grad);
            }
            // Fastest collider material that could reach a particle within one maximal step: the
            // step is limited so a moving wall advances at most cfl * d per step and cannot jump
            // over a particle.
            if (moving && sample.valid) {
              const float speed = glm::length(colliderVelocityAt(collider.pose, positions[i]));
              if (sample.distance < support + speed * max_time_step) acc = std::max(acc, speed);
            }
          }
          scratch.boundary_gradient[i] = gradient;
          scratch.boundary_flux[i] = flux;
          scratch.boundary_volume[i] = 1.0f - product;
          scratch.boundary_product[i] = product;
        }
      },
      maxOf);
}

}  // namespace fluid::sph_step
