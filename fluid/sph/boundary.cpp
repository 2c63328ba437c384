// Boundary tables and the step-start boundary samples (boundary.hpp).
#include "fluid/sph/boundary.hpp"

#include "fluid/sph/analytic_colliders.hpp"

#include <cmath>
#include <cstring>

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

// The octant integral of the kernel, G(a) = int_{z > a} W(|z|) dz (z > a per component), and
// its slope D(a) = dG/da_x = -int_{z_y > a_y, z_z > a_z} W(|(a_x, z_y, z_z)|) dz_y dz_z, on the
// nodes a = -H + (i, j, k) H / 24 (index (k n + j) n + i, n = kOctantCells + 1). G by suffix sums
// of the kernel's cell averages (midpoint rule), D by 2-D suffix sums on each node plane; both
// normalised so that G(-H, -H, -H) = 1 and scaled by the wall calibration `beta`.
void tabulateOctant(SphScratch& scratch, float beta) {
  const CubicSplineKernel& k = scratch.kernel;
  const int cells = kOctantCells, n = kOctantCells + 1;
  const double H = k.support, c = 2.0 * H / cells;
  std::vector<double> g(static_cast<std::size_t>(n) * n * n, 0.0), d(g.size(), 0.0);
  auto at = [n](int i, int j, int l) { return (static_cast<std::size_t>(l) * n + j) * n + i; };
  auto centre = [&](int i) { return -H + (i + 0.5) * c; };
  auto kernelAt = [&](double x, double y, double z) {
    return static_cast<double>(k.value(static_cast<float>(std::sqrt(x * x + y * y + z * z))));
  };
  for (int l = cells - 1; l >= 0; --l)
    for (int j = cells - 1; j >= 0; --j)
      for (int i = cells - 1; i >= 0; --i)  // 3-D suffix sum: G(node) = sum of the cells beyond it
        g[at(i, j, l)] = kernelAt(centre(i), centre(j), centre(l)) * c * c * c + g[at(i + 1, j, l)] +
                         g[at(i, j + 1, l)] + g[at(i, j, l + 1)] - g[at(i + 1, j + 1, l)] - g[at(i + 1, j, l + 1)] -
                         g[at(i, j + 1, l + 1)] + g[at(i + 1, j + 1, l + 1)];
  for (int i = 0; i < n; ++i) {
    const double ax = -H + i * c;
    for (int l = cells - 1; l >= 0; --l)
      for (int j = cells - 1; j >= 0; --j)
        d[at(i, j, l)] = -kernelAt(ax, centre(j), centre(l)) * c * c + d[at(i, j + 1, l)] + d[at(i, j, l + 1)] -
                         d[at(i, j + 1, l + 1)];
  }
  const double scale = beta / g[at(0, 0, 0)];
  scratch.octant_volume.resize(g.size());
  scratch.octant_slope.resize(g.size());
  for (std::size_t e = 0; e < g.size(); ++e) {
    scratch.octant_volume[e] = static_cast<float>(g[e] * scale);
    scratch.octant_slope[e] = static_cast<float>(d[e] * scale);
  }
}

// Trilinear lookup of an octant table at a (each component clamped to [-H, H]: beyond -H the
// constraint is void, beyond H the octant misses the support).
inline float lookupOctant(const std::vector<float>& table, glm::vec3 a, float inv_node) {
  const int n = kOctantCells + 1;
  int idx[3];
  float f[3];
  for (int k = 0; k < 3; ++k) {
    const float t = std::clamp((a[k] * inv_node) + 0.5f * kOctantCells, 0.0f, static_cast<float>(kOctantCells));
    idx[k] = std::min(static_cast<int>(t), kOctantCells - 1);
    f[k] = t - static_cast<float>(idx[k]);
  }
  const float* p = table.data() + (static_cast<std::size_t>(idx[2]) * n + idx[1]) * n + idx[0];
  const std::size_t sy = n, sz = static_cast<std::size_t>(n) * n;
  auto lerp = [](float x, float y, float t) { return x + t * (y - x); };
  const float c00 = lerp(p[0], p[1], f[0]), c10 = lerp(p[sy], p[sy + 1], f[0]);
  const float c01 = lerp(p[sz], p[sz + 1], f[0]), c11 = lerp(p[sz + sy], p[sz + sy + 1], f[0]);
  return lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
}

// Bit-for-bit equality (positions, poses): a collider sample is a pure function of its inputs'
// bits, and == would equate -0 and +0.
template <typename T>
bool sameBits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

}  // namespace

// Why a box is not a plane: the tangent-plane volume fills the whole half-space beyond the
// nearest point, so around a convex edge or corner it counts solid where the box has none (at a
// box edge, half of the half-space's share is missing). The water is then kept out of a band
// along the box's edges, and a floating crate displaces that band too: measured with a 0.14 m
// box held still half submerged in a tank (r = 12.5 mm, 5.6 spacings per edge), the force was
// 1.24x rho g V_submerged below the visible water level with the tangent plane, 1.14x with the
// exact volume (the rest is mostly the water's own level offset, see docs/engine.md). For a box, V is exact: the indicator of [-h, h] along each axis is step(y + h) -
// step(y - h), so the box's integral of W(x - y) is the signed sum over its 8 corners of the
// octant integral G(a) with a_k = -h_k - x_k or h_k - x_k (Koschier & Bender 2017 define the
// boundary volume as this integral, their eq. 7, and tabulate it in a volume map per shape; a
// box only needs the one octant table). A face far from edges gets 1 - G(-s, -H, -H) = V_wall(s),
// so with the half extents less wall_shift and the table scaled by beta, a box face is exactly
// the calibrated wall.
// Thin boxes keep the tangent plane (sampleBoundary): seen from one side, a wall thinner than the
// support would leave most of a particle's support empty, and the water beside it would meet
// only the collision constraint (measured with the exact volume on the 6 mm basin walls of
// tests/sph: SphBlast's overflowing basin stopped draining). The tangent plane treats such a wall
// as the solid behind its face, which is what the fluid on one side needs. A box at least H/2
// thick in every axis (a crate) has no far face within the support of a particle outside it.
BoundaryVolume boxBoundaryVolume(const SphScratch& scratch, glm::vec3 half, const ColliderPose& pose, glm::vec3 x) {
  const float H = scratch.kernel.support, inv_node = 0.5f * kOctantCells / H;
  const glm::vec3 local = glm::inverse(pose.rotation) * (x - pose.translation);
  float a[3][2], sign[3][2];
  int count[3];
  for (int k = 0; k < 3; ++k) {
    const float lo = -half[k] - local[k], hi = half[k] - local[k];
    count[k] = 0;
    if (lo >= H) return {};  // beyond the support on the -k side (then hi >= H too)
    a[k][count[k]] = lo;
    sign[k][count[k]++] = 1.0f;
    if (hi < H) {  // at hi >= H the corner term is 0
      a[k][count[k]] = hi;
      sign[k][count[k]++] = -1.0f;
    }
  }
  BoundaryVolume out;
  glm::vec3 slope(0.0f);  // dV/da summed as -dV/dx (a = corner - x)
  for (int i = 0; i < count[0]; ++i)
    for (int j = 0; j < count[1]; ++j)
      for (int l = 0; l < count[2]; ++l) {
        const float s = sign[0][i] * sign[1][j] * sign[2][l];
        const glm::vec3 c(a[0][i], a[1][j], a[2][l]);
        out.volume += s * lookupOctant(scratch.octant_volume, c, inv_node);
        // G is symmetric in its arguments, so dG/da_y (a) = D(a_y, a_x, a_z), dG/da_z = D(a_z, a_y, a_x).
        slope.x += s * lookupOctant(scratch.octant_slope, c, inv_node);
        slope.y += s * lookupOctant(scratch.octant_slope, glm::vec3(c.y, c.x, c.z), inv_node);
        slope.z += s * lookupOctant(scratch.octant_slope, glm::vec3(c.z, c.y, c.x), inv_node);
      }
  out.volume = std::clamp(out.volume, 0.0f, 1.0f);
  const glm::vec3 gradient = pose.rotation * -slope;
  out.area = glm::length(gradient);
  if (out.area > 0.0f) out.normal = gradient / -out.area;
  return out;
}

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
    scratch.wall_beta = beta;
  }
  scratch.octant_volume.clear();  // rebuilt for the new kernel when a box needs it
  scratch.octant_slope.clear();
  scratch.initialised = true;
}

// The colliders (bit c) whose end-of-step samples of the last step can stand in for this step's
// queries (SphScratch::SampleCarry): the same shape object at the same pose, bit for bit, and
// samples the last collision passes took at every particle they did not skip.
std::uint32_t carriedColliders(const SphWorld& world) {
  const SphScratch& scratch = world.scratch;
  const SphScratch::SampleCarry& carry = scratch.carry;
  const std::size_t count = std::min(world.colliders.size(), carry.usable.size());
  if (carry.count == 0 || world.colliders.size() > 32 || carry.position.size() < carry.count ||
      scratch.collide_stale.size() < carry.count || carry.shape.size() < count || carry.pose.size() < count ||
      scratch.end_samples.size() < count)
    return 0;
  std::uint32_t bits = 0;
  for (std::size_t c = 0; c < count; ++c) {
    const SphCollider& collider = world.colliders[c];
    const ColliderPose& pose = carry.pose[c];
    if (carry.usable[c] && carry.shape[c] == collider.shape && scratch.end_samples[c].size() >= carry.count &&
        sameBits(pose.translation, collider.pose.translation) && sameBits(pose.rotation, collider.pose.rotation))
      bits |= 1u << c;
  }
  return bits;
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
  scratch.boundary_share.resize(collider_count);
  for (std::size_t c = 0; c < collider_count; ++c)
    scratch.boundary_share[c].resize(world.colliders[c].boundary_pressure ? n : 0);
  // Whether collider c moves (its wall velocity enters the flux and the speed bound): once per
  // step, not per particle.
  scratch.collider_moving.resize(collider_count);
  for (std::size_t c = 0; c < collider_count; ++c) {
    const ColliderPose& pose = world.colliders[c].pose;
    scratch.collider_moving[c] = glm::dot(pose.linear_velocity, pose.linear_velocity) > 0.0f ||
                                 glm::dot(pose.angular_velocity, pose.angular_velocity) > 0.0f;
  }
  // Solid boxes get their exact volume (boxBoundaryVolume); other shapes the tangent plane.
  scratch.collider_box.assign(collider_count, glm::vec4(0.0f));
  for (std::size_t c = 0; c < collider_count; ++c) {
    const auto* box = dynamic_cast<const BoxShape*>(world.colliders[c].shape.get());
    if (box == nullptr || box->inverted() || !world.colliders[c].boundary_pressure ||
        glm::any(glm::lessThan(box->halfExtents(), glm::vec3(0.5f * support))))
      continue;
    if (scratch.octant_volume.empty()) tabulateOctant(scratch, scratch.wall_beta);
    scratch.collider_box[c] = glm::vec4(glm::max(box->halfExtents() - scratch.wall_shift, glm::vec3(1e-6f)), 1.0f);
  }
  const std::uint32_t reuse = carriedColliders(world);
  const SphScratch::SampleCarry& carry = scratch.carry;
  context.wall_approach_speed = reduceChunks(
      n, 0.0f,
      [&](std::size_t b, std::size_t e, float& acc) {
        std::uint32_t which[kGrain];
        // Per particle, once for all colliders: the particle it was at the end of the last step,
        // if it is still where that step's collision passes sampled it (else kNone).
        std::uint32_t from[kGrain];
        if (reuse != 0)
          for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t p = carry.index[i];
            from[i - b] = p != SphScratch::SampleCarry::kNone && sameBits(carry.position[p], positions[i])
                              ? p
                              : SphScratch::SampleCarry::kNone;
          }
        const std::uint32_t* const stale = scratch.collide_stale.data();
        for (std::size_t c = 0; c < collider_count; ++c) {
          std::vector<ColliderSample>& samples = scratch.start_samples[c];
          std::uint32_t q = 0;
          const std::uint32_t bit = c < 32 ? 1u << c : 0u;
          if (reuse & bit) {
            const std::vector<ColliderSample>& carried = scratch.end_samples[c];
            for (std::size_t i = b; i < e; ++i) {
              const std::uint32_t p = from[i - b];
              if (p != SphScratch::SampleCarry::kNone && !(stale[p] & bit))
                samples[i] = carried[p];
              else
                which[q++] = static_cast<std::uint32_t>(i);
            }
          } else {
            for (std::size_t i = b; i < e; ++i) which[q++] = static_cast<std::uint32_t>(i);
          }
          ColliderQuery(world.colliders[c], world.colliders[c].pose).run(positions, which, q, samples);
        }
        // Each collider's V_c and grad V_c, kept for the second loop (recomputed beyond kKept colliders).
        constexpr std::size_t kKept = 16;
        BoundaryVolume kept[kKept];
        auto term = [&](std::size_t c, std::size_t i) {
          return colliderVolume(scratch, world.colliders[c], c, scratch.start_samples[c][i], positions[i]);
        };
        for (std::size_t i = b; i < e; ++i) {
          float product = 1.0f;  // prod_c (1 - V_c)
          for (std::size_t c = 0; c < collider_count; ++c) {
            const BoundaryVolume t = term(c, i);
            if (c < kKept) kept[c] = t;
            product *= 1.0f - t.volume;
          }
          glm::vec3 gradient(0.0f);
          float flux = 0.0f;
          for (std::size_t c = 0; c < collider_count; ++c) {
            const SphCollider& collider = world.colliders[c];
            const ColliderSample& sample = scratch.start_samples[c][i];
            const bool moving = scratch.collider_moving[c] != 0;
            // Out of reach, V_c = 0 and grad V_c = 0: the share would be a zero vector, which leaves
            // the gradient and flux sums unchanged, and addCouplingTerm does not read it.
            if (collider.boundary_pressure && withinSupport(sample, support)) {
              const glm::vec3 grad = boundaryShare(c < kKept ? kept[c] : term(c, i), product);
              scratch.boundary_share[c][i] = grad;
              gradient += grad;
              if (moving) flux += glm::dot(colliderVelocityAt(collider.pose, positions[i]), grad);
            }
            // Fastest approach of collider material that could reach a particle within one maximal
            // step: the step is limited so a moving wall advances at most half a spacing towards a
            // particle per step and cannot jump over it (chooseTimeStep). Only the velocity along
            // the wall's outward normal closes on the particle: a charge spinning, or a crate
            // sliding past, moves its surface along itself.
            if (moving && sample.valid) {
              const float approach = glm::dot(colliderVelocityAt(collider.pose, positions[i]), sample.normal);
              if (approach > 0.0f && sample.distance < support + approach * max_time_step) acc = std::max(acc, approach);
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
