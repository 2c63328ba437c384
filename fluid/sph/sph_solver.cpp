// The SPH step: neighbour search, boundary terms, WCSPH / DFSPH, collisions, coupling forces.
// See sph.hpp for the papers; equations are cited where they are implemented.
#include "fluid/core/finite.hpp"
#include "fluid/core/parallel.hpp"
#include "fluid/sph/sph.hpp"

#include <glm/gtc/quaternion.hpp>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace fluid {
namespace {

// Fixed grain: parallel_deterministic_reduce splits a range the same way for any thread count,
// so every floating-point sum below is bit-identical for 1 and N threads.
constexpr std::size_t kGrain = 256;
constexpr int kWallTable = 1024;
// Boundary pressure mirroring: the wall takes the particle's pressure (p_b = p_i, rho_b = rho_i),
// so its term in the symmetric pressure force has weight 2.
constexpr float kMirror = 2.0f;
// Share of the last step's summed stiffness that warm-starts the constant-density solve.
constexpr float kWarmShare = 0.2f;
// WCSPH Verlet-list skin as a fraction of the support H (see the neighbour search in stepSph).
constexpr float kWcsphSkin = 0.2f;

using Clock = std::chrono::steady_clock;
float msSince(Clock::time_point t0) { return std::chrono::duration<float, std::milli>(Clock::now() - t0).count(); }

template <typename F>
void forEach(std::size_t n, F&& f) {
  par::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

template <typename T, typename F, typename J>
T reduce(std::size_t n, T identity, F&& body, J&& join) {
  return par::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), identity,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) body(i, acc);
        return acc;
      },
      join);
}

// Chunked variants for loops whose per-particle work is batched: f(b, e) on consecutive
// blocks of at most kGrain particles (reduceChunks: in the same blocks and order as reduce, so
// sums are bit-identical for any thread count).
template <typename F>
void forChunks(std::size_t n, F&& f) {
  par::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); b += kGrain) f(b, std::min(r.end(), b + kGrain));
  });
}
template <typename T, typename F, typename J>
T reduceChunks(std::size_t n, T identity, F&& body, J&& join) {
  return par::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), identity,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t b = r.begin(); b < r.end(); b += kGrain) body(b, std::min(r.end(), b + kGrain), acc);
        return acc;
      },
      join);
}

struct SumMax {
  double sum = 0.0;
  float max = 0.0f;
};
SumMax joinSumMax(SumMax a, const SumMax& b) {
  a.sum += b.sum;
  a.max = std::max(a.max, b.max);
  return a;
}

// Boundary volume of a planar wall: the collider side of the kernel support treated as a filled
// half-space at signed distance s (s > 0: particle outside the solid). A(s) = integral of W over
// the plane at distance s = 2 pi int_{|s|}^{H} W(r) r dr; V(s) = int_s^H A(t) dt, so V(-H) = 1,
// V(0) = 1/2, V(H) = 0 and dV/ds = -A(s). The planar approximation of Koschier & Bender 2017's
// volume map, exact for planes, first order for curved colliders.
void tabulateWall(SphScratch& w) {
  const CubicSplineKernel& k = w.kernel;
  const double H = k.support;
  w.wall_area.resize(kWallTable + 1);
  w.wall_volume.resize(kWallTable + 1);
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
    w.wall_area[i] = static_cast<float>(2.0 * 3.14159265358979 * integral);
  }
  // V by trapezoid integration of A from H downwards.
  w.wall_volume[kWallTable] = 0.0f;
  double v = 0.0;
  const double ds = 2.0 * H / kWallTable;
  for (int i = kWallTable - 1; i >= 0; --i) {
    v += 0.5 * (w.wall_area[i] + w.wall_area[i + 1]) * ds;
    w.wall_volume[i] = static_cast<float>(v);
  }
}

inline float lookup(const std::vector<float>& table, float s, float H) {
  const float t = (s + H) / (2.0f * H) * kWallTable;
  if (!(t > 0.0f)) return table.front();
  if (t >= static_cast<float>(kWallTable)) return table.back();
  const int i = static_cast<int>(t);
  const float f = t - static_cast<float>(i);
  return table[i] + f * (table[i + 1] - table[i]);
}

// 1 - V_c: the part of a particle's support that collider c leaves to fluid (V_c = its boundary
// volume from the wall table at that distance; 1 when c does not push back or is out of reach).
// The union rule in stepSph multiplies these over the colliders.
inline float openFraction(const SphScratch& w, const SphCollider& c, const ColliderSample& s) {
  const float H = w.kernel.support;
  if (!c.boundary_pressure || !s.valid || s.distance >= H) return 1.0f;
  return 1.0f - lookup(w.wall_volume, s.distance + w.wall_shift, H);
}

// collider c's share of grad V at a particle (see the union rule in stepSph); product = prod_c (1 - V_c).
inline glm::vec3 boundaryShare(const SphScratch& w, const ColliderSample& s, float product) {
  const float H = w.kernel.support;
  if (!s.valid || s.distance >= H) return glm::vec3(0.0f);
  const float vc = lookup(w.wall_volume, s.distance + w.wall_shift, H);
  const float others = product / std::max(1.0f - vc, 1e-6f);
  return (-lookup(w.wall_area, s.distance + w.wall_shift, H) * others) * s.normal;  // grad V_c = -A(s) n
}

// Unit direction for a coincident pair, u(a, b) = -u(b, a), from a hash of the two ids.
glm::vec3 coincidentDirection(std::uint32_t a, std::uint32_t b) {
  const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
  std::uint32_t h = lo * 0x9E3779B1u ^ (hi + 0x7F4A7C15u) * 0x85EBCA77u;
  glm::vec3 u;
  for (int c = 0; c < 3; ++c) {
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    u[c] = static_cast<float>(h & 0xFFFFu) / 32767.5f - 1.0f;
  }
  const float len = glm::length(u);
  u = len > 1e-3f ? u / len : glm::vec3(1.0f, 0.0f, 0.0f);
  return a < b ? u : -u;
}

void ensureInit(SphWorld& world) {
  SphScratch& w = world.scratch;
  const float H = sphSupport(world.params);
  if (w.initialised && w.kernel.support == H && w.particle_mass == sphParticleMass(world.params)) return;
  w.kernel = CubicSplineKernel::make(H);
  w.particle_mass = sphParticleMass(world.params);
  tabulateWall(w);
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
          layer += w.kernel.value(len);
          grad += -w.kernel.derivative(len) * (-z * d) / len;
        }
    const float scale = w.particle_mass / world.params.rest_density;
    const float f = static_cast<float>(layer * scale), g = static_cast<float>(grad * scale);
    // V/A decreases with s on (0, H): bisection for V(r + delta) / A(r + delta) = f / g.
    float lo = 0.0f, hi = H - r;
    for (int it = 0; it < 60; ++it) {
      const float mid = 0.5f * (lo + hi);
      const float ratio = lookup(w.wall_volume, r + mid, H) / std::max(lookup(w.wall_area, r + mid, H), 1e-30f);
      if (ratio > f / g)
        lo = mid;
      else
        hi = mid;
    }
    w.wall_shift = 0.5f * (lo + hi);
    w.wall_neighbours = 9.0f / f;  // a flat wall stands in for 9 lattice neighbours (2 layers at H = 2d)
    const float beta = f / lookup(w.wall_volume, r + w.wall_shift, H);
    for (float& v : w.wall_volume) v *= beta;
    for (float& a : w.wall_area) a *= beta;
  }
  w.initialised = true;
}

ColliderPose advancedPose(const ColliderPose& pose, float dt) {
  ColliderPose out = pose;
  out.translation += pose.linear_velocity * dt;
  const float w = glm::length(pose.angular_velocity);
  if (w > 0.0f) out.rotation = glm::normalize(glm::angleAxis(w * dt, pose.angular_velocity / w) * pose.rotation);
  return out;
}

// Queries one collider at chosen particles, in chunks: which[0 .. q) are particle indices whose
// world points are transformed to collider space, queried as one batch and written (normals back in
// world space, a non-finite distance marked invalid) to out[which[k]]. At most kGrain points.
struct ColliderQuery {
  const SphCollider& col;
  ColliderPose pose;
  glm::quat inv;
  bool rotated;
  ColliderQuery(const SphCollider& c, const ColliderPose& p)
      : col(c),
        pose(p),
        inv(glm::inverse(p.rotation)),
        rotated(!(p.rotation.w == 1.0f && p.rotation.x == 0.0f && p.rotation.y == 0.0f && p.rotation.z == 0.0f)) {}
  void run(const std::vector<glm::vec3>& points, const std::uint32_t* which, std::uint32_t q,
           std::vector<ColliderSample>& out) const {
    if (q == 0) return;
    glm::vec3 local[kGrain];
    ColliderSample smp[kGrain];
    for (std::uint32_t k = 0; k < q; ++k)
      local[k] = rotated ? inv * (points[which[k]] - pose.translation) : points[which[k]] - pose.translation;
    col.shape->query(std::span<const glm::vec3>(local, q), std::span<ColliderSample>(smp, q));
    for (std::uint32_t k = 0; k < q; ++k) {
      if (rotated) smp[k].normal = pose.rotation * smp[k].normal;
      if (!std::isfinite(smp[k].distance)) smp[k].valid = false;  // never let a bad shape spread NaN
      out[which[k]] = smp[k];
    }
  }
};

// Where a still collider pushes a particle out (outward normal ns, by `need` along it) that a
// moving collider pushed out earlier in the same step (its face as the plane
// dot(plane.xyz, x) >= plane.w), the position nearest to p outside both tangent planes: the two
// projections one after the other only converge slowly in a narrow wedge (a tilted crate edge
// on the basin floor) and end wherever the last one put the particle. The planes' intersection,
// when the still projection alone would violate the moving face: x = p + l1 ns + l2 nm with both
// constraints active (a 2x2 system). `still_only` (the still projection) is kept where the faces
// are nearly parallel or the wedge's free side is more than `reach` away: there the moving
// collider overlaps the still one, no free position is near, and the still collider wins.
glm::vec3 wedgePosition(glm::vec3 p, glm::vec3 ns, float need, glm::vec4 plane, float reach, glm::vec3 still_only) {
  const glm::vec3 nm(plane);
  const float c = glm::dot(ns, nm);
  const float r1 = need, r2 = plane.w - glm::dot(nm, p);  // displacements required along ns and nm
  if (c * r1 >= r2) return still_only;                    // the still projection keeps the moving face
  const float det = 1.0f - c * c;
  if (det < 1e-3f) return still_only;
  const float l1 = (r1 - c * r2) / det, l2 = (r2 - c * r1) / det;
  if (l1 < 0.0f || l2 < 0.0f) return still_only;
  const glm::vec3 x = p + l1 * ns + l2 * nm;
  return glm::length(x - p) <= reach ? x : still_only;
}

// --- pair loops ------------------------------------------------------------------------------
// The per-pair gradients G[k] = m_j grad W_ij live in three float arrays (SoA, 12 bytes a pair).
// Every pair loop of the DFSPH step (density + gradients, viscosity, and the two loops of each
// solver iteration, Bender & Koschier 2015 eq. 9 / 13) runs "8 lanes wide": lane l of a
// particle's list [b, e) accumulates the pairs b + l, b + 8 + l, ... and the lanes are summed at
// the end in one fixed tree, hsum8 below. Where the CPU has AVX2 (checked at run time; the build
// targets baseline x86-64) the lanes are one 256-bit register; elsewhere a portable loop does
// the same IEEE operations in the same order (no FMA: the AVX2 target does not enable it, so
// nothing is contracted), so both give bit-identical results (tests/sph checks this through
// SphScratch::portable_pair_loops). The order does not depend on the thread count either.
// Neighbour positions and velocities are read from 16-byte copies (SphScratch::pos4 / vel4).
constexpr int kLanes = 8;

// The fixed lane tree: ((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7)).
inline float hsum8(const float* s) {
  const float t0 = s[0] + s[4], t1 = s[1] + s[5], t2 = s[2] + s[6], t3 = s[3] + s[7];
  return (t0 + t2) + (t1 + t3);
}

// Constants of the DFSPH density pass (cubic spline, kernels.hpp, in the same operation order as
// CubicSplineKernel::evaluateInside, both branches evaluated and one selected per lane).
struct DensityConsts {
  float inv_support, sigma, sigma2, c_inner, c_outer;  // sigma2 = 2 sigma, c_inner = sigma/H, c_outer = -sigma/H * 6
  float mass, r_min, steepest_mass;                     // m, coincidence radius, m W'(H/3)
  static DensityConsts make(const CubicSplineKernel& k, float m, float r_min, float steepest) {
    DensityConsts c;
    c.inv_support = k.inv_support;
    c.sigma = k.sigma;
    c.sigma2 = k.sigma * 2.0f;
    c.c_inner = k.sigma * k.inv_support;
    c.c_outer = -k.sigma * k.inv_support * 6.0f;
    c.mass = m;
    c.r_min = r_min;
    c.steepest_mass = m * steepest;
    return c;
  }
};

// Per-particle results of the density pass: sum_j W_ij, sum_j m grad W_ij, sum_j |m grad W_ij|^2.
struct DensitySums {
  float w = 0.0f;
  glm::vec3 grad{0.0f};
  float sq = 0.0f;
};

// One lane of the density pass for x = x_i - x_j: W and m grad W_ij. Coincident particles
// (r <= r_min) have grad W = 0 between them and could never separate; they get the kernel's
// steepest slope along a direction fixed by the two ids (odd in i <-> j, so momentum is still
// conserved), which pushes stacked particles apart deterministically.
inline void densityLane(const DensityConsts& c, glm::vec3 x, std::uint32_t id_i, std::uint32_t id_j, float& w,
                        glm::vec3& g) {
  const float r = std::sqrt((x.x * x.x + x.y * x.y) + x.z * x.z);
  const float q = r * c.inv_support;
  const float t = 1.0f - q;
  float dw;
  if (q <= 0.5f) {
    w = c.sigma * ((6.0f * q * q * q - 6.0f * q * q) + 1.0f);
    dw = c.c_inner * (18.0f * q * q - 12.0f * q);
  } else {
    w = c.sigma2 * t * t * t;
    dw = c.c_outer * t * t;
  }
  if (r > c.r_min) {
    const float dr = dw / r;
    g = glm::vec3(c.mass * (dr * x.x), c.mass * (dr * x.y), c.mass * (dr * x.z));
  } else {
    g = c.steepest_mass * coincidentDirection(id_i, id_j);
  }
}

// What the solver iterations read: neighbour lists (i's pairs are [off[i], off[i] + cnt[i])),
// the same neighbours as byte offsets 16 j (so the AVX2 loops address 16-byte records without a
// shift per neighbour), per-pair gradients and the 16-byte velocity copy.
struct IterationArgs {
  const glm::vec4* vel4;
  const float *gx, *gy, *gz;
  const std::uint32_t *nbr, *nb16, *off, *cnt;
};

struct PairLoops {
  // DFSPH density pass of particle i: fills gx/gy/gz[b, e) and nb16[b, e) = 16 nbr[b, e) (see
  // IterationArgs) and returns the sums.
  DensitySums (*density)(const DensityConsts& c, const glm::vec4* X, const std::uint32_t* id, const std::uint32_t* nbr,
                         std::uint32_t b, std::uint32_t e, std::uint32_t i, float* gx, float* gy, float* gz,
                         std::uint32_t* nb16);
  // sum_k c_j (v_ij . x_ij) / (|x_ij|^2 + eps) G[k] (Laplacian viscosity, see stepSph), with
  // c_j = 10 nu / rho_j in V[j].w.
  glm::vec3 (*viscosity)(const glm::vec4* X, const glm::vec4* V, const float* gx, const float* gy,
                         const float* gz, const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, std::uint32_t i,
                         float eps);
  // The two solver-iteration loops for the particles [i0, i1) (i1 - i0 <= kGrain): out[i - i0].
  void (*divergence_range)(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out);
  // kr4[j].x = kappa_j / rho_j (16-byte records, addressed like vel4).
  void (*kappa_range)(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1,
                      glm::vec3* out);
};

// Portable lanes.
DensitySums densityPortable(const DensityConsts& c, const glm::vec4* X, const std::uint32_t* id,
                            const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, std::uint32_t i, float* gx,
                            float* gy, float* gz, std::uint32_t* nb16) {
  float sw[kLanes] = {}, sx[kLanes] = {}, sy[kLanes] = {}, sz[kLanes] = {}, sq[kLanes] = {};
  const glm::vec4 xi = X[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const std::uint32_t j = nbr[k];
    nb16[k] = j << 4;
    const glm::vec4 xj = X[j];
    float wv;
    glm::vec3 g;
    densityLane(c, glm::vec3(xi.x - xj.x, xi.y - xj.y, xi.z - xj.z), id[i], id[j], wv, g);
    gx[k] = g.x;
    gy[k] = g.y;
    gz[k] = g.z;
    sw[l] += wv;
    sx[l] += g.x;
    sy[l] += g.y;
    sz[l] += g.z;
    sq[l] += (g.x * g.x + g.y * g.y) + g.z * g.z;
  }
  DensitySums out;
  out.w = hsum8(sw);
  out.grad = glm::vec3(hsum8(sx), hsum8(sy), hsum8(sz));
  out.sq = hsum8(sq);
  return out;
}

glm::vec3 viscosityPortable(const glm::vec4* X, const glm::vec4* V, const float* gx, const float* gy,
                            const float* gz, const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e,
                            std::uint32_t i, float eps) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  const glm::vec4 xi = X[i], vi = V[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const std::uint32_t j = nbr[k];
    const float x = xi.x - X[j].x, y = xi.y - X[j].y, z = xi.z - X[j].z;
    const float vx = ((vi.x - V[j].x) * x + (vi.y - V[j].y) * y) + (vi.z - V[j].z) * z;
    const float denom = ((x * x + y * y) + z * z) + eps;
    const float coef = V[j].w * (vx / denom);
    ax[l] += coef * gx[k];
    ay[l] += coef * gy[k];
    az[l] += coef * gz[k];
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}

inline float divergencePortable(const glm::vec4* V, const float* gx, const float* gy, const float* gz,
                         const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, glm::vec3 vi) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const glm::vec4 vj = V[nbr[k]];
    ax[l] += (vi.x - vj.x) * gx[k];
    ay[l] += (vi.y - vj.y) * gy[k];
    az[l] += (vi.z - vj.z) * gz[k];
  }
  float s[kLanes];
  for (int l = 0; l < kLanes; ++l) s[l] = (ax[l] + ay[l]) + az[l];
  return hsum8(s);
}

inline glm::vec3 kappaSumPortable(const glm::vec4* kr4, const float* gx, const float* gy, const float* gz,
                                  const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, float ki) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const float s = ki + kr4[nbr[k]].x;
    ax[l] += s * gx[k];
    ay[l] += s * gy[k];
    az[l] += s * gz[k];
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}

void divergenceRangePortable(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out) {
  for (std::uint32_t i = i0; i < i1; ++i)
    out[i - i0] = divergencePortable(a.vel4, a.gx, a.gy, a.gz, a.nbr, a.off[i], a.off[i] + a.cnt[i], glm::vec3(a.vel4[i]));
}
void kappaRangePortable(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1,
                        glm::vec3* out) {
  for (std::uint32_t i = i0; i < i1; ++i)
    out[i - i0] = kappaSumPortable(kr4, a.gx, a.gy, a.gz, a.nbr, a.off[i], a.off[i] + a.cnt[i], kr4[i].x);
}

constexpr PairLoops kPortableLoops{&densityPortable, &viscosityPortable, &divergenceRangePortable, &kappaRangePortable};

#if defined(__x86_64__) && defined(__GNUC__)
#define FLUID_SPH_AVX2_PAIRS 1
// AVX2 lanes. Neighbour data come in by one 16-byte load per neighbour (pos4 / vel4) or
// scalar loads (load8): on the Zen 3 machine we measure on, vgatherdps was slower than the
// SSE2 loop it replaced. In the last block of a list (fewer than 8 pairs) the lanes past the
// end read particle 0 (valid data) and are zeroed by a lane mask (masked loads of the
// gradients, or an and with the mask), so they add exact zeros: an accumulator that starts at +0
// is never -0, so adding +-0 leaves it unchanged, and the sums equal the portable loop's, which
// skips those lanes.
#define FLUID_AVX2 __attribute__((target("avx2")))
FLUID_AVX2 inline __m256i laneMask(std::uint32_t left) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(std::min<std::uint32_t>(left, 8))),
                            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}
// hsum8's tree in registers: t_l = s_l + s_(l+4), then (t0 + t2) + (t1 + t3).
FLUID_AVX2 inline float hsum8(__m256 v) {
  const __m128 t = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 u = _mm_add_ps(t, _mm_movehl_ps(t, t));
  return _mm_cvtss_f32(_mm_add_ss(u, _mm_shuffle_ps(u, u, 1)));
}
FLUID_AVX2 inline __m256 loadPair(const glm::vec4* base, std::uint32_t a, std::uint32_t b) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&base[a].x)), _mm_loadu_ps(&base[b].x), 1);
}
// Rows r0..r3 hold records (0, 4), (1, 5), (2, 6), (3, 7) in their low | high halves; writes
// the components of the eight records in lane order (w only when asked for).
FLUID_AVX2 inline void transposeRows(__m256 r0, __m256 r1, __m256 r2, __m256 r3, __m256& x, __m256& y, __m256& z,
                                     __m256* w) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);  // x0 x1 y0 y1 | x4 x5 y4 y5; z.. w..
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  x = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  y = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  z = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  if (w != nullptr) *w = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
FLUID_AVX2 inline void load8xyz(const glm::vec4* base, const std::uint32_t* idx, __m256& x, __m256& y, __m256& z) {
  transposeRows(loadPair(base, idx[0], idx[4]), loadPair(base, idx[1], idx[5]), loadPair(base, idx[2], idx[6]),
                loadPair(base, idx[3], idx[7]), x, y, z, nullptr);
}
// The same with the 4th component.
FLUID_AVX2 inline void load8xyzw(const glm::vec4* base, const std::uint32_t* idx, __m256& x, __m256& y, __m256& z,
                                 __m256& w) {
  transposeRows(loadPair(base, idx[0], idx[4]), loadPair(base, idx[1], idx[5]), loadPair(base, idx[2], idx[6]),
                loadPair(base, idx[3], idx[7]), x, y, z, &w);
}
// The last block of a list: lanes past `left` read particle 0 (valid data; their gradient
// lanes are masked to 0, so they add exact zeros).
FLUID_AVX2 inline const std::uint32_t* tailIndices(const std::uint32_t* nbr, std::uint32_t left, std::uint32_t* buf) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(buf),
                      _mm256_maskload_epi32(reinterpret_cast<const int*>(nbr), laneMask(left)));
  return buf;
}

// load8xyz with byte offsets o[l] = 16 idx[l].
FLUID_AVX2 inline __m256 loadPair16(const glm::vec4* base, std::uint32_t a, std::uint32_t b) {
  const char* p = reinterpret_cast<const char*>(base);
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(reinterpret_cast<const float*>(p + a))),
                              _mm_loadu_ps(reinterpret_cast<const float*>(p + b)), 1);
}
FLUID_AVX2 inline void load8xyz16(const glm::vec4* base, const std::uint32_t* o, __m256& x, __m256& y, __m256& z) {
  transposeRows(loadPair16(base, o[0], o[4]), loadPair16(base, o[1], o[5]), loadPair16(base, o[2], o[6]),
                loadPair16(base, o[3], o[7]), x, y, z, nullptr);
}
// base[idx[l]].x for byte offsets o[l] = 16 idx[l], by scalar loads (Zen 3 runs these faster
// than vgatherdps).
FLUID_AVX2 inline __m256 load8x16(const glm::vec4* base, const std::uint32_t* o) {
  const char* p = reinterpret_cast<const char*>(base);
  auto at = [p](std::uint32_t off) { return reinterpret_cast<const float*>(p + off); };
  const __m128 lo = _mm_insert_ps(
      _mm_insert_ps(_mm_insert_ps(_mm_load_ss(at(o[0])), _mm_load_ss(at(o[1])), 0x10), _mm_load_ss(at(o[2])), 0x20),
      _mm_load_ss(at(o[3])), 0x30);
  const __m128 hi = _mm_insert_ps(
      _mm_insert_ps(_mm_insert_ps(_mm_load_ss(at(o[4])), _mm_load_ss(at(o[5])), 0x10), _mm_load_ss(at(o[6])), 0x20),
      _mm_load_ss(at(o[7])), 0x30);
  return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}


FLUID_AVX2 DensitySums densityAvx2(const DensityConsts& c, const glm::vec4* X, const std::uint32_t* id,
                                   const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, std::uint32_t i,
                                   float* gx, float* gy, float* gz, std::uint32_t* nb16) {
  const glm::vec4 xi = X[i];
  const __m256 pix = _mm256_set1_ps(xi.x), piy = _mm256_set1_ps(xi.y), piz = _mm256_set1_ps(xi.z);
  const __m256 inv_h = _mm256_set1_ps(c.inv_support), sigma = _mm256_set1_ps(c.sigma),
               sigma2 = _mm256_set1_ps(c.sigma2), c_in = _mm256_set1_ps(c.c_inner), c_out = _mm256_set1_ps(c.c_outer),
               mass = _mm256_set1_ps(c.mass), r_min = _mm256_set1_ps(c.r_min), one = _mm256_set1_ps(1.0f),
               half = _mm256_set1_ps(0.5f), six = _mm256_set1_ps(6.0f), c18 = _mm256_set1_ps(18.0f),
               c12 = _mm256_set1_ps(12.0f);
  __m256 sw = _mm256_setzero_ps(), sx = sw, sy = sw, sz = sw, sq = sw;
  std::uint32_t buf[kLanes];
  for (std::uint32_t k = b; k < e; k += kLanes) {
    const __m256i mi = laneMask(e - k);
    const __m256 m = _mm256_castsi256_ps(mi);
    __m256 x, y, z;
    load8xyz(X, e - k >= kLanes ? nbr + k : tailIndices(nbr + k, e - k, buf), x, y, z);
    x = _mm256_sub_ps(pix, x);
    y = _mm256_sub_ps(piy, y);
    z = _mm256_sub_ps(piz, z);
    const __m256 r =
        _mm256_sqrt_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)));
    const __m256 q = _mm256_mul_ps(r, inv_h);
    const __m256 t = _mm256_sub_ps(one, q);
    const __m256 q6q = _mm256_mul_ps(_mm256_mul_ps(six, q), q);
    const __m256 w_in = _mm256_mul_ps(sigma, _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(q6q, q), q6q), one));
    const __m256 dw_in = _mm256_mul_ps(
        c_in, _mm256_sub_ps(_mm256_mul_ps(_mm256_mul_ps(c18, q), q), _mm256_mul_ps(c12, q)));
    const __m256 tt = _mm256_mul_ps(_mm256_mul_ps(sigma2, t), t);
    const __m256 w_out = _mm256_mul_ps(tt, t);
    const __m256 dw_out = _mm256_mul_ps(_mm256_mul_ps(c_out, t), t);
    const __m256 inner = _mm256_cmp_ps(q, half, _CMP_LE_OQ);
    // Masked lanes have x = x_i, so they are inside or outside the support: their W is zeroed.
    const __m256 wv = _mm256_and_ps(_mm256_blendv_ps(w_out, w_in, inner), m);
    const __m256 dr = _mm256_div_ps(_mm256_blendv_ps(dw_out, dw_in, inner), r);
    __m256 g0 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, x));
    __m256 g1 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, y));
    __m256 g2 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, z));
    const __m256 close = _mm256_and_ps(_mm256_cmp_ps(r, r_min, _CMP_LE_OQ), m);
    if (_mm256_movemask_ps(close) != 0) {  // rare: coincident particles, lane by lane
      alignas(32) float a0[kLanes], a1[kLanes], a2[kLanes];
      _mm256_store_ps(a0, g0);
      _mm256_store_ps(a1, g1);
      _mm256_store_ps(a2, g2);
      const int bits = _mm256_movemask_ps(close);
      for (int l = 0; l < kLanes; ++l)
        if (bits & (1 << l)) {
          const glm::vec3 g = c.steepest_mass * coincidentDirection(id[i], id[nbr[k + l]]);
          a0[l] = g.x;
          a1[l] = g.y;
          a2[l] = g.z;
        }
      g0 = _mm256_load_ps(a0);
      g1 = _mm256_load_ps(a1);
      g2 = _mm256_load_ps(a2);
    }
    g0 = _mm256_and_ps(g0, m);
    g1 = _mm256_and_ps(g1, m);
    g2 = _mm256_and_ps(g2, m);
    // Full blocks use plain stores; only the last (partial) block goes through a buffer, since
    // masked stores (vmaskmovps) are microcoded and slow on the AMD machines we measure on.
    if (e - k >= kLanes) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(nb16 + k),
                          _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(nbr + k)), 4));
      _mm256_storeu_ps(gx + k, g0);
      _mm256_storeu_ps(gy + k, g1);
      _mm256_storeu_ps(gz + k, g2);
    } else {
      alignas(32) float t0[kLanes], t1[kLanes], t2[kLanes];
      _mm256_store_ps(t0, g0);
      _mm256_store_ps(t1, g1);
      _mm256_store_ps(t2, g2);
      for (std::uint32_t l = 0; l < e - k; ++l) {
        nb16[k + l] = nbr[k + l] << 4;
        gx[k + l] = t0[l];
        gy[k + l] = t1[l];
        gz[k + l] = t2[l];
      }
    }
    sw = _mm256_add_ps(sw, wv);
    sx = _mm256_add_ps(sx, g0);
    sy = _mm256_add_ps(sy, g1);
    sz = _mm256_add_ps(sz, g2);
    sq = _mm256_add_ps(sq, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(g0, g0), _mm256_mul_ps(g1, g1)),
                                         _mm256_mul_ps(g2, g2)));
  }
  DensitySums out;
  out.w = hsum8(sw);
  out.grad = glm::vec3(hsum8(sx), hsum8(sy), hsum8(sz));
  out.sq = hsum8(sq);
  return out;
}

FLUID_AVX2 glm::vec3 viscosityAvx2(const glm::vec4* X, const glm::vec4* V, const float* gx,
                                   const float* gy, const float* gz, const std::uint32_t* nbr, std::uint32_t b,
                                   std::uint32_t e, std::uint32_t i, float eps) {
  const __m256 pix = _mm256_set1_ps(X[i].x), piy = _mm256_set1_ps(X[i].y), piz = _mm256_set1_ps(X[i].z);
  const __m256 vix = _mm256_set1_ps(V[i].x), viy = _mm256_set1_ps(V[i].y), viz = _mm256_set1_ps(V[i].z);
  const __m256 ve = _mm256_set1_ps(eps);
  __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
  std::uint32_t buf[kLanes];
  for (std::uint32_t k = b; k < e; k += kLanes) {
    const __m256i mi = laneMask(e - k);
    const std::uint32_t* idx = e - k >= kLanes ? nbr + k : tailIndices(nbr + k, e - k, buf);
    __m256 xj, yj, zj, vcj, uj, vj, wj;
    load8xyz(X, idx, xj, yj, zj);
    load8xyzw(V, idx, uj, vj, wj, vcj);
    const __m256 x = _mm256_sub_ps(pix, xj), y = _mm256_sub_ps(piy, yj), z = _mm256_sub_ps(piz, zj);
    const __m256 vx = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(vix, uj), x), _mm256_mul_ps(_mm256_sub_ps(viy, vj), y)),
        _mm256_mul_ps(_mm256_sub_ps(viz, wj), z));
    const __m256 denom =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)), ve);
    const __m256 coef = _mm256_mul_ps(vcj, _mm256_div_ps(vx, denom));
    ax = _mm256_add_ps(ax, _mm256_mul_ps(coef, _mm256_maskload_ps(gx + k, mi)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(coef, _mm256_maskload_ps(gy + k, mi)));
    az = _mm256_add_ps(az, _mm256_mul_ps(coef, _mm256_maskload_ps(gz + k, mi)));
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}

FLUID_AVX2 inline float divergenceAvx2(const glm::vec4* V, const float* gx, const float* gy, const float* gz,
                                       const std::uint32_t* nb16, std::uint32_t b, std::uint32_t e, glm::vec3 vi) {
  const __m256 vix = _mm256_set1_ps(vi.x), viy = _mm256_set1_ps(vi.y), viz = _mm256_set1_ps(vi.z);
  __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
  std::uint32_t k = b;
  __m256 vx, vy, vz;
  for (; k + kLanes <= e; k += kLanes) {
    load8xyz16(V, nb16 + k, vx, vy, vz);
    ax = _mm256_add_ps(ax, _mm256_mul_ps(_mm256_sub_ps(vix, vx), _mm256_loadu_ps(gx + k)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(_mm256_sub_ps(viy, vy), _mm256_loadu_ps(gy + k)));
    az = _mm256_add_ps(az, _mm256_mul_ps(_mm256_sub_ps(viz, vz), _mm256_loadu_ps(gz + k)));
  }
  if (k < e) {
    const __m256i mi = laneMask(e - k);
    std::uint32_t buf[kLanes];
    load8xyz16(V, tailIndices(nb16 + k, e - k, buf), vx, vy, vz);
    ax = _mm256_add_ps(ax, _mm256_mul_ps(_mm256_sub_ps(vix, vx), _mm256_maskload_ps(gx + k, mi)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(_mm256_sub_ps(viy, vy), _mm256_maskload_ps(gy + k, mi)));
    az = _mm256_add_ps(az, _mm256_mul_ps(_mm256_sub_ps(viz, vz), _mm256_maskload_ps(gz + k, mi)));
  }
  return hsum8(_mm256_add_ps(_mm256_add_ps(ax, ay), az));
}

FLUID_AVX2 inline glm::vec3 kappaSumAvx2(const glm::vec4* kr4, const float* gx, const float* gy, const float* gz,
                                         const std::uint32_t* nb16, std::uint32_t b, std::uint32_t e, float ki) {
  const __m256 vk = _mm256_set1_ps(ki);
  __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
  std::uint32_t k = b;
  for (; k + kLanes <= e; k += kLanes) {
    const __m256 s = _mm256_add_ps(vk, load8x16(kr4, nb16 + k));
    ax = _mm256_add_ps(ax, _mm256_mul_ps(s, _mm256_loadu_ps(gx + k)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(s, _mm256_loadu_ps(gy + k)));
    az = _mm256_add_ps(az, _mm256_mul_ps(s, _mm256_loadu_ps(gz + k)));
  }
  if (k < e) {
    const __m256i mi = laneMask(e - k);
    std::uint32_t buf[kLanes];
    const __m256 s = _mm256_add_ps(vk, load8x16(kr4, tailIndices(nb16 + k, e - k, buf)));
    ax = _mm256_add_ps(ax, _mm256_mul_ps(s, _mm256_maskload_ps(gx + k, mi)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(s, _mm256_maskload_ps(gy + k, mi)));
    az = _mm256_add_ps(az, _mm256_mul_ps(s, _mm256_maskload_ps(gz + k, mi)));
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}
FLUID_AVX2 void divergenceRangeAvx2(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out) {
  for (std::uint32_t i = i0; i < i1; ++i)
    out[i - i0] = divergenceAvx2(a.vel4, a.gx, a.gy, a.gz, a.nb16, a.off[i], a.off[i] + a.cnt[i], glm::vec3(a.vel4[i]));
}
FLUID_AVX2 void kappaRangeAvx2(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1,
                               glm::vec3* out) {
  for (std::uint32_t i = i0; i < i1; ++i)
    out[i - i0] = kappaSumAvx2(kr4, a.gx, a.gy, a.gz, a.nb16, a.off[i], a.off[i] + a.cnt[i], kr4[i].x);
}
#undef FLUID_AVX2

constexpr PairLoops kAvx2Loops{&densityAvx2, &viscosityAvx2, &divergenceRangeAvx2, &kappaRangeAvx2};
#endif

const PairLoops& pairLoops(bool portable) {
#if defined(FLUID_SPH_AVX2_PAIRS)
  if (!portable && __builtin_cpu_supports("avx2")) return kAvx2Loops;
#endif
  (void)portable;
  return kPortableLoops;
}

// --- validation, sinks, emitters -------------------------------------------------------------

// Validation and the sink test in one parallel pass. Returns the refusal naming the first
// particle with a non-finite position or velocity (the world is left untouched), otherwise
// marks scratch.keep[i] = 0 for the particles inside a sink box and returns their count in
// `in_sinks` (applySinks removes them).
SphStatus checkFiniteAndSinks(SphWorld& world, std::size_t& in_sinks) {
  const auto& x = world.particles.position;
  const auto& v = world.particles.velocity;
  auto& keep = world.scratch.keep;
  keep.resize(x.size());
  const std::size_t none = std::numeric_limits<std::size_t>::max();
  struct Scan {
    std::size_t bad;
    std::size_t inside = 0;
  };
  const Scan scan = reduce(
      x.size(), Scan{none},
      [&](std::size_t i, Scan& acc) {
        const glm::vec3 p = x[i];
        const bool ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(v[i].x) &&
                        std::isfinite(v[i].y) && std::isfinite(v[i].z);
        if (!ok && i < acc.bad) acc.bad = i;
        bool inside = false;
        for (const SphSink& k : world.sinks)
          inside = inside || (p.x >= k.min.x && p.y >= k.min.y && p.z >= k.min.z && p.x <= k.max.x &&
                              p.y <= k.max.y && p.z <= k.max.z);
        keep[i] = inside ? 0u : 1u;
        acc.inside += inside ? 1 : 0;
      },
      [](Scan a, const Scan& b) {
        a.bad = std::min(a.bad, b.bad);
        a.inside += b.inside;
        return a;
      });
  in_sinks = scan.inside;
  const std::size_t bad = scan.bad;
  if (bad == none) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "sph step %llu (t = %.6f s): particle id %u (index %zu) has a non-finite state: position (%g, %g, %g), "
                "velocity (%g, %g, %g); step refused",
                static_cast<unsigned long long>(world.step_count), world.time, world.particles.id[bad], bad,
                static_cast<double>(x[bad].x), static_cast<double>(x[bad].y), static_cast<double>(x[bad].z),
                static_cast<double>(v[bad].x), static_cast<double>(v[bad].y), static_cast<double>(v[bad].z));
  return {buf};
}

// Removes the particles checkFiniteAndSinks marked (`in_sinks` of them); nothing to do (and no
// pass over the data) when none is inside a sink.
std::size_t applySinks(SphWorld& world, std::size_t in_sinks) {
  if (in_sinks == 0) return 0;
  ParticleStore& s = world.particles;
  SphScratch& w = world.scratch;
  const std::size_t n = s.size();
  std::size_t out = 0;
  // Stable compaction: survivors keep their relative order, so the result is deterministic.
  for (std::size_t i = 0; i < n; ++i) {
    if (!w.keep[i]) continue;
    if (out != i) {
      s.position[out] = s.position[i];
      s.velocity[out] = s.velocity[i];
      s.density[out] = s.density[i];
      s.pressure[out] = s.pressure[i];
      s.id[out] = s.id[i];
      w.warm_kappa[out] = w.warm_kappa[i];
    }
    ++out;
  }
  const std::size_t removed = n - out;
  s.position.resize(out);
  s.velocity.resize(out);
  s.density.resize(out);
  s.pressure.resize(out);
  s.id.resize(out);
  w.warm_kappa.resize(out);
  return removed;
}

// Calls f(offset) for each point of the emitter's disc lattice (offset in world units).
template <typename F>
void forDiscLattice(const SphEmitter& e, float d, glm::vec3 dir, F&& f) {
  const glm::vec3 helper = std::abs(dir.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 u = glm::normalize(glm::cross(dir, helper));
  const glm::vec3 w = glm::cross(dir, u);
  const int reach = static_cast<int>(std::floor(std::max(e.radius, 0.0f) / d));
  const float r2 = e.radius * e.radius + 1e-6f * d * d;
  for (int j = -reach; j <= reach; ++j)
    for (int i = -reach; i <= reach; ++i) {
      const glm::vec3 o = d * (static_cast<float>(i) * u + static_cast<float>(j) * w);
      if (glm::dot(o, o) <= r2) f(o);
    }
}

// True when a sphere of radius `room` around p overlaps a collider (its signed distance at p is
// below `room`). Emitters skip such lattice points: a nozzle placed in or against a solid cannot
// emit there, and a particle created inside the boundary's filled half-space would start at up to
// twice the rest density (WCSPH's Tait pressure then fires it off at km/s). One query per
// collider serves both tests: otherwise `volume` is the boundary volume at p, combined over the
// colliders as in the step (section 2 of stepSph); when it returns true, `volume` is 0.
bool overlapsCollider(const SphWorld& world, glm::vec3 p, float room, float& volume) {
  float product = 1.0f;  // prod_c (1 - V_c)
  volume = 0.0f;
  for (const SphCollider& col : world.colliders) {
    const glm::vec3 local = toColliderSpace(col.pose, p);
    ColliderSample sample;
    col.shape->query(std::span<const glm::vec3>(&local, 1), std::span<ColliderSample>(&sample, 1));
    if (sample.valid && sample.distance < room) return true;
    product *= openFraction(world.scratch, col, sample);
  }
  volume = 1.0f - product;
  return false;
}

// The boundary volume at p alone (no overlap test: no distance is below -infinity).
float boundaryVolumeAt(const SphWorld& world, glm::vec3 p) {
  float volume = 0.0f;
  overlapsCollider(world, p, -std::numeric_limits<float>::infinity(), volume);
  return volume;
}

// Emitters also skip lattice points closer than the lattice spacing d (less 1 % for rounding) to an
// existing particle: in a resting lattice no neighbour is nearer than d, so a point that close sits
// in fluid already there (a slow upward jet falling back onto its nozzle, a nozzle buried in a
// pile). A particle inserted there is compressed from its first step, and the pressure solve then
// turns that stored compression into kinetic energy the emitter never supplied (the randomised
// runs of tests/sph broke their energy bound this way). The point is simply not emitted: a blocked
// nozzle emits less.
constexpr float kEmitterRoom = 0.99f;  // x d

// Compression the density test below lets through, relative to rho_0. It has to be well above the
// float rounding of a density sum: sphParticleMass makes a full lattice neighbourhood sum to exactly
// rho_0, so a free jet whose layers are exactly d apart completes neighbourhoods at rho_0 up to the
// last bit, and without slack rounding alone dropped every third layer's last point. 0.1 % is about
// a hundred times that rounding and ninety times below the 8.9 % squeeze described below.
constexpr float kEmitterDensitySlack = 1e-3f;

// The distance test alone is not enough where an existing particle is pressed against a collider
// closer than the rest distance r (a jet running onto a solid: the Kolb 2004 §3.3.2 reaction leaves
// it at the surface, and the boundary volume already gives it nearly rho_0). A point d from it on
// the far side squeezes it between the new particle and the wall (randomised seed 177 run 10: a
// nozzle 1 cm above a sphere, a particle 1.3 mm off the sphere at 968 kg/m^3 went to 1089, and
// DFSPH removed the 9 % in one 0.1 ms step at 9.6-15 m/s). So the point is tested by what it does
// to the fluid: the SPH density (Becker & Teschner 2007 eq. 4, plus rho_0 times the boundary volume
// as in the step) of the new particle and of every existing particle within its support must stay
// at or below rho_0 (1 + kEmitterDensitySlack) with it added. Creating compression is creating
// energy the emitter does not supply; density below rho_0 is free (the solvers only correct
// compression).
// The particles near a layer are gathered once per layer: those within the support of a point
// (disc radius + H) need their own density, which needs their neighbours (disc radius + 2H).
void gatherCrowd(const SphWorld& world, glm::vec3 centre, float reach, std::vector<glm::vec3>& crowd) {
  crowd.clear();
  const float reach2 = reach * reach;
  for (const glm::vec3& x : world.particles.position) {
    const glm::vec3 q = x - centre;
    if (glm::dot(q, q) <= reach2) crowd.push_back(x);
  }
}

// density[k] = SPH density of crowd[k] at the current positions, for the members within `inner`
// of the centre (the others are never within H of a lattice point: 0, unused). Every neighbour of
// such a member is in the crowd (it was gathered to inner + H).
void crowdDensities(const SphWorld& world, glm::vec3 centre, float inner, std::span<const glm::vec3> crowd,
                    std::vector<float>& density) {
  const SphScratch& w = world.scratch;
  const float H = w.kernel.support, h2 = H * H, m = w.particle_mass, rho0 = world.params.rest_density;
  const float inner2 = inner * inner;
  density.assign(crowd.size(), 0.0f);
  for (std::size_t a = 0; a < crowd.size(); ++a) {
    const glm::vec3 xa = crowd[a];
    const glm::vec3 c = xa - centre;
    if (glm::dot(c, c) > inner2) continue;
    float sum = w.kernel.value(0.0f);
    for (std::size_t b = 0; b < crowd.size(); ++b) {
      const glm::vec3 q = xa - crowd[b];
      const float q2 = glm::dot(q, q);
      if (b != a && q2 < h2) sum += w.kernel.value(std::sqrt(q2));
    }
    density[a] = m * sum + rho0 * boundaryVolumeAt(world, xa);
  }
}

bool crowded(std::span<const glm::vec3> crowd, glm::vec3 p, float room2) {
  for (const glm::vec3& x : crowd) {
    const glm::vec3 q = x - p;
    if (glm::dot(q, q) < room2) return true;
  }
  return false;
}

std::size_t applyEmitters(SphWorld& world) {
  const float d = sphSpacing(world.params);
  const float room = kEmitterRoom * d;
  SphScratch& sw = world.scratch;
  std::vector<glm::vec3>& crowd = sw.emitter_crowd;
  std::vector<float>& crowd_density = sw.emitter_crowd_density;
  const float H = sw.kernel.support, h2 = H * H, m = sw.particle_mass, rho0 = world.params.rest_density;
  const float rhoLimit = rho0 * (1.0f + kEmitterDensitySlack);
  const float self = m * sw.kernel.value(0.0f);
  std::size_t emitted = 0;
  for (SphEmitter& e : world.emitters) {
    if (!(e.rate > 0.0f) || !(e.speed > 0.0f) || !std::isfinite(e.rate) || !std::isfinite(e.speed)) continue;
    glm::vec3 dir = e.direction;
    const float len = glm::length(dir);
    dir = (len > 0.0f && std::isfinite(len)) ? dir / len : glm::vec3(0, 1, 0);
    std::size_t layer = 0;
    forDiscLattice(e, d, dir, [&](glm::vec3) { ++layer; });
    // Layers closer than d along the jet would overlap (compressed fluid = stored energy), so the
    // rate is clamped to speed * layer / d particles per second.
    const double interval = std::max(static_cast<double>(layer) / e.rate, static_cast<double>(d) / e.speed);
    while (e.accumulator >= interval) {
      e.accumulator -= interval;
      if (world.particles.size() + layer > world.params.max_particles) continue;  // over budget: layer dropped
      // The layer was due `accumulator` seconds ago and has travelled that far.
      const glm::vec3 base = e.position + dir * (e.speed * static_cast<float>(e.accumulator));
      // Layers placed earlier in this loop are existing particles here (d apart along the jet:
      // interval >= d / speed). The points of this layer join the crowd as they are placed, so
      // the density test sees them; they are d apart, so they do not block each other by distance.
      const float disc = std::max(e.radius, 0.0f) + 1e-3f * d;  // a lattice point is at most this far from base
      gatherCrowd(world, base, disc + 2.0f * H + 1e-3f * d, crowd);
      bool densities = false;  // crowd_density is filled when the first point passes the cheaper tests
      forDiscLattice(e, d, dir, [&](glm::vec3 o) {
        const glm::vec3 p = base + o;
        // The crowd test first: a few distances, where the collider test is a query per collider.
        if (crowded(crowd, p, room * room)) return;
        float volume = 0.0f;
        if (overlapsCollider(world, p, world.params.particle_radius, volume)) return;
        if (!densities) {
          crowdDensities(world, base, disc + H + 1e-3f * d, crowd, crowd_density);
          densities = true;
        }
        // f(k, m W(|p - crowd[k]|)) for the crowd members within the support of p, in crowd order;
        // stops early when f returns false.
        auto forSupport = [&](auto&& f) {
          for (std::size_t k = 0; k < crowd.size(); ++k) {
            const glm::vec3 q = p - crowd[k];
            const float q2 = glm::dot(q, q);
            if (q2 < h2 && !f(k, m * sw.kernel.value(std::sqrt(q2)))) return false;
          }
          return true;
        };
        float rho = self + rho0 * volume;
        const bool room_left = forSupport([&](std::size_t k, float wk) {
          rho += wk;
          return crowd_density[k] + wk <= rhoLimit;  // else it would compress an existing particle
        });
        if (!room_left || rho > rhoLimit) return;  // (rho > limit: it would start compressed)
        if (!addSphParticle(world, p, dir * e.speed)) return;
        ++emitted;
        forSupport([&](std::size_t k, float wk) {
          crowd_density[k] += wk;
          return true;
        });
        crowd.push_back(p);
        crowd_density.push_back(rho);
      });
    }
  }
  return emitted;
}

void advanceEmitterClocks(SphWorld& world, float dt) {
  for (SphEmitter& e : world.emitters) {
    const double t0 = world.time, t1 = world.time + dt;
    const double active =
        std::max(0.0, std::min(t1, static_cast<double>(e.end_time)) - std::max(t0, static_cast<double>(e.start_time)));
    e.accumulator += active;
  }
}

}  // namespace

// --- the step ------------------------------------------------------------------------------------

namespace {
SphStatus stepImpl(SphWorld& world, float max_dt, double span, SphStepStats* stats_out);
}

SphStatus stepSph(SphWorld& world, float max_dt, SphStepStats* stats_out) {
  return stepImpl(world, max_dt, 0.0, stats_out);
}

SphStatus stepSphWithin(SphWorld& world, double remaining, SphStepStats* stats_out) {
  if (!(remaining > 0.0) || !std::isfinite(remaining)) return {"stepSphWithin: remaining time must be finite and > 0"};
  return stepImpl(world, static_cast<float>(std::min<double>(remaining, world.params.max_time_step)), remaining,
                  stats_out);
}

namespace {

SphStatus stepImpl(SphWorld& world, float max_dt, double span, SphStepStats* stats_out) {
  const auto t_start = Clock::now();
  SphStepStats stats;
  const SphParams& P = world.params;
  if (SphStatus s = validateSphParams(P); !s.ok()) return s;
  for (std::size_t c = 0; c < world.colliders.size(); ++c) {
    const SphCollider& col = world.colliders[c];
    if (!col.shape) return {"sph collider " + std::to_string(c) + " has no shape"};
    const glm::quat q = col.pose.rotation;
    if (!isFinite(col.pose.translation) || !isFinite(col.pose.linear_velocity) ||
        !isFinite(col.pose.angular_velocity) || !std::isfinite(q.w + q.x + q.y + q.z) || !(glm::dot(q, q) > 0.0f))
      return {"sph collider " + std::to_string(c) + " has a non-finite or degenerate pose; step refused"};
  }
  for (std::size_t e = 0; e < world.emitters.size(); ++e) {
    const SphEmitter& em = world.emitters[e];
    if (!isFinite(em.position) || !isFinite(em.direction) || !std::isfinite(em.speed) || !std::isfinite(em.radius) ||
        !std::isfinite(em.rate) || std::isnan(em.start_time) || std::isnan(em.end_time))
      return {"sph emitter " + std::to_string(e) + " has a non-finite field; step refused"};
  }
  std::size_t in_sinks = 0;
  if (SphStatus s = checkFiniteAndSinks(world, in_sinks); !s.ok()) return s;
  ensureInit(world);
  SphScratch& w = world.scratch;
  ParticleStore& S = world.particles;
  if (!(max_dt > 0.0f) || !std::isfinite(max_dt)) max_dt = P.max_time_step;
  const float requested = max_dt;
  max_dt = std::min(max_dt, P.max_time_step);

  // Keep persistent per-particle solver state in step with the store.
  w.warm_kappa.resize(S.size(), 0.0f);
  stats.removed = applySinks(world, in_sinks);
  stats.emitted = applyEmitters(world);
  const std::size_t n = S.size();
  w.warm_kappa.resize(n, 0.0f);
  S.density.resize(n);
  S.pressure.resize(n);

  const float H = w.kernel.support;
  const float d = sphSpacing(P);
  const float m = w.particle_mass;
  const float rho0 = P.rest_density;
  const std::size_t nc = world.colliders.size();

  // 1. Neighbour grid, re-sort of the particle data by cell (locality), neighbour lists.
  // WCSPH keeps a Verlet list (Verlet 1967; radius H + skin) over several steps: its step is
  // bounded by the sound speed, so a particle moves about 0.4 d v/c_s <= 0.04 d per step (Mach 0.1),
  // and the lists (and the data order) are rebuilt only once some particle has moved skin/2 since
  // the last build: no pair within H can be missing before that. Each step filters the Verlet list
  // to the exact list (|x_ij| < H), so the solver sees the same pairs as with a fresh search, in a
  // fixed order. DFSPH moves up to cfl d per step and rebuilds every step (skin 0).
  const auto t_nb = Clock::now();
  const float verlet_skin = P.solver == SphSolverKind::wcsph ? kWcsphSkin * H : 0.0f;
  bool rebuild = verlet_skin == 0.0f || !w.verlet_valid || stats.emitted > 0 || stats.removed > 0 ||
                 w.verlet_position.size() != n || w.verlet_radius != H + verlet_skin;
  if (!rebuild) {
    const float moved = reduce(
        n, 0.0f,
        [&](std::size_t i, float& acc) { acc = std::max(acc, glm::length(S.position[i] - w.verlet_position[i])); },
        [](float a, float b) { return std::max(a, b); });
    rebuild = !(2.0f * moved < verlet_skin);
  }
  bool copies_made = false;  // pos4 / vel4
  if (rebuild) {
    // Cells 0.2 % wider than the search radius: the query then reaches one cell on each side
    // (neighborReach), with room for float slack at coordinates up to ~400 H from the origin.
    buildNeighborGrid(w.grid, S.position, 1.002f * (H + verlet_skin), P.domain_min, P.domain_max);
    // Re-sort by cell in one pass, which also writes the 16-byte copies the pair loops read and
    // the grid's keys in the new order (markGridReordered below).
    std::uint32_t* const order = w.grid.order.data();
    const std::uint32_t* const old_keys = w.grid.particle_key.data();
    w.sorted_keys.resize(n);
    // The search's SoA copies of the sorted positions (findNeighbors with positions_copied).
    NeighborLists& lists = verlet_skin > 0.0f ? w.verlet : w.neighbors;
    for (auto* v : {&lists.sx, &lists.sy, &lists.sz}) v->resize(n + NeighborLists::kPad);
    float* const soa_x = lists.sx.data();
    float* const soa_y = lists.sy.data();
    float* const soa_z = lists.sz.data();
    w.vec_a.resize(n);
    w.vec_b.resize(n);
    w.u32_tmp.resize(n);
    w.float_tmp.resize(n);
    w.pos4.resize(n);
    w.vel4.resize(n);
    forEach(n, [&](std::size_t e) {
      const std::uint32_t o = order[e];
      const glm::vec3 x = S.position[o], v = S.velocity[o];
      w.vec_a[e] = x;
      w.vec_b[e] = v;
      w.u32_tmp[e] = S.id[o];
      w.float_tmp[e] = w.warm_kappa[o];
      w.pos4[e] = glm::vec4(x, 0.0f);
      w.vel4[e] = glm::vec4(v, 0.0f);
      w.sorted_keys[e] = old_keys[o];
      soa_x[e] = x.x;
      soa_y[e] = x.y;
      soa_z[e] = x.z;
      order[e] = static_cast<std::uint32_t>(e);  // only this iteration reads order[e]
    });
    S.position.swap(w.vec_a);
    S.velocity.swap(w.vec_b);
    S.id.swap(w.u32_tmp);
    w.warm_kappa.swap(w.float_tmp);
    copies_made = true;
    markGridReordered(w.grid, w.sorted_keys);
    if (verlet_skin > 0.0f) {
      findNeighbors(w.grid, S.position, H + verlet_skin, w.verlet, true);
      w.verlet_position.resize(n);
      forEach(n, [&](std::size_t i) { w.verlet_position[i] = S.position[i]; });
      w.verlet_radius = H + verlet_skin;
      w.verlet_valid = true;
    } else {
      findNeighbors(w.grid, S.position, H, w.neighbors, true);
      w.verlet_valid = false;
    }
  }
  stats.neighbor_ms = msSince(t_nb);
  // Exact lists: the neighbours of i are nbr[off[i] .. off[i] + cnt[i]). DFSPH: the fresh search
  // (off[i] + cnt[i] = off[i + 1]). WCSPH: the density pass below filters each particle's Verlet
  // candidates vi[vo[i] .. vo[i + 1]) to |x_ij| < H and writes them to the front of the same range
  // of neighbors.indices (counts in neighbors.counts), so no separate filter pass runs.
  const bool filter_verlet = verlet_skin > 0.0f;
  if (filter_verlet) {
    w.neighbors.offsets.assign(w.verlet.offsets.begin(), w.verlet.offsets.end());
    w.neighbors.counts.resize(n);
    w.neighbors.indices.resize(w.verlet.indices.size());
  }
  const std::uint32_t* off = w.neighbors.offsets.data();
  const std::uint32_t* cnt = w.neighbors.counts.data();
  std::uint32_t* const nbr_out = w.neighbors.indices.data();
  const std::uint32_t* nbr = nbr_out;
  const std::uint32_t* cand = filter_verlet ? w.verlet.indices.data() : nbr;
  const std::uint32_t* cand_end = filter_verlet ? w.verlet.offsets.data() + 1 : off + 1;
  const auto& X = S.position;
  auto& V = S.velocity;
  // 16-byte copies of the step-start positions and velocities for the pair loops.
  if (!copies_made) {
    w.pos4.resize(n);
    w.vel4.resize(n);
    forEach(n, [&](std::size_t i) {
      w.pos4[i] = glm::vec4(X[i], 0.0f);
      w.vel4[i] = glm::vec4(V[i], 0.0f);
    });
  }

  // 2. Collider samples at the step-start positions; boundary volume, its gradient and flux.
  // Several colliders: the solid is the union of their solid sides. Summing the volumes would count
  // the overlap twice at edges and corners (17 % density error at a box corner). We combine them as
  // V = 1 - prod_c (1 - V_c), exact for one plane and for orthogonal planes under a separable kernel,
  // close for the cubic spline; collider c's share of grad V is grad V_c prod_{c' != c} (1 - V_c').
  // One parallel region: each chunk queries every collider, then combines the samples.
  w.start_samples.resize(nc);
  for (auto& smp : w.start_samples) smp.resize(n);
  w.boundary_volume.resize(n);
  w.boundary_gradient.resize(n);
  w.boundary_flux.resize(n);
  w.boundary_product.resize(n);
  // Whether collider c moves (its wall velocity enters the flux and the speed bound): once per
  // step, not per particle.
  w.collider_moving.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    const ColliderPose& pose = world.colliders[c].pose;
    w.collider_moving[c] = glm::dot(pose.linear_velocity, pose.linear_velocity) > 0.0f ||
                           glm::dot(pose.angular_velocity, pose.angular_velocity) > 0.0f;
  }
  const float collider_speed = reduceChunks(
      n, 0.0f,
      [&](std::size_t b, std::size_t e, float& acc) {
        std::uint32_t which[kGrain];
        for (std::size_t i = b; i < e; ++i) which[i - b] = static_cast<std::uint32_t>(i);
        for (std::size_t c = 0; c < nc; ++c)
          ColliderQuery(world.colliders[c], world.colliders[c].pose)
              .run(X, which, static_cast<std::uint32_t>(e - b), w.start_samples[c]);
        for (std::size_t i = b; i < e; ++i) {
          float product = 1.0f;  // prod_c (1 - V_c)
          for (std::size_t c = 0; c < nc; ++c) product *= openFraction(w, world.colliders[c], w.start_samples[c][i]);
          glm::vec3 gradient(0.0f);
          float flux = 0.0f;
          for (std::size_t c = 0; c < nc; ++c) {
            const SphCollider& col = world.colliders[c];
            const ColliderSample& s = w.start_samples[c][i];
            const bool moving = w.collider_moving[c] != 0;
            if (col.boundary_pressure) {
              const glm::vec3 grad = boundaryShare(w, s, product);
              gradient += grad;
              if (moving) flux += glm::dot(colliderVelocityAt(col.pose, X[i]), grad);
            }
            // Fastest collider material that could reach a particle within one maximal step: the
            // step is limited so a moving wall advances at most cfl * d per step and cannot jump
            // over a particle.
            if (moving && s.valid) {
              const float sp = glm::length(colliderVelocityAt(col.pose, X[i]));
              if (s.distance < H + sp * P.max_time_step) acc = std::max(acc, sp);
            }
          }
          w.boundary_gradient[i] = gradient;
          w.boundary_flux[i] = flux;
          w.boundary_volume[i] = 1.0f - product;
          w.boundary_product[i] = product;
        }
      },
      [](float x, float y) { return std::max(x, y); });

  // 3. One pass over the pairs: density (the SPH sum, Becker & Teschner 2007 eq. 4, plus the
  // boundary volume's share), the per-pair m grad W_ij reused by every solver iteration, and the
  // sums DFSPH's factor alpha_i needs (S_i = sum_j m grad W_ij, Q_i = sum_j |m grad W_ij|^2).
  // Coincident particles (r below 1e-6 H) get the steepest slope along an id-fixed direction
  // (densityLane). DFSPH runs the eight-lane pair loop (see PairLoops); WCSPH filters its Verlet
  // candidates here and stays scalar.
  const PairLoops& loops = pairLoops(w.portable_pair_loops);
  const float w0 = w.kernel.value(0.0f);
  const float steepest = w.kernel.derivative(H / 3.0f);
  const std::size_t pair_count = w.neighbors.indices.size();
  w.grad_x.resize(pair_count);
  w.grad_y.resize(pair_count);
  w.grad_z.resize(pair_count);
  float* const gx_out = w.grad_x.data();
  float* const gy_out = w.grad_y.data();
  float* const gz_out = w.grad_z.data();
  w.vec_b.resize(n);   // WCSPH: S_i (unused)
  w.factor.resize(n);  // DFSPH: alpha_i
  const float h2 = H * H;
  const float r_min = 1e-6f * H;

  // Per-particle terms that need only the particle's own density are computed in the same pass
  // (one parallel region instead of one per term): WCSPH's Tait pressure, the viscosity
  // coefficient 10 nu / rho_i, DFSPH's factor alpha_i and the divergence solve's kappa scale, and
  // the copies and clears the later passes start from.
  w.accel.resize(n);
  const float nu = P.viscosity;
  const float alpha_av = P.solver == SphSolverKind::wcsph ? P.artificial_viscosity : 0.0f;
  const float cs = P.sound_speed;
  const float h_bt = d;  // B&T's smoothing length h (support 2h = H)
  const bool wcsph = P.solver == SphSolverKind::wcsph;
  auto& visc_coef = w.float_tmp;  // WCSPH: 10 nu / rho_j per particle (no division per pair)
  auto& pr = w.density_adv;       // WCSPH: p_j / rho_j^2 per particle
  visc_coef.resize(n);
  pr.resize(n);
  // Tait equation (B&T eq. 7) with B = rho_0 c_s^2 / gamma; negative pressures are clamped to
  // zero so the free surface does not clump (tensile instability). Computed before the pair pass
  // so the pressure force (eq. 6) joins the viscosity terms in one pass over the pairs.
  const float tait_b = rho0 * cs * cs / P.tait_exponent;
  const bool gamma7 = P.tait_exponent == 7.0f;
  // Boundary pressure impulse per particle (for the coupling forces): the velocity change the
  // boundary term gave particle i during this step is -impulse_i * rho_0 * grad V_ic.
  w.kappa.resize(n);  // impulse_i
  w.old_position.resize(n);
  const float dt_prev = world.last_dt > 0.0f ? world.last_dt : max_dt;
  auto& kscale = w.kappa_scale;  // DFSPH: kr_i per unit of compression (or of density rate), per solve
  kscale.resize(n);
  w.vec_a.resize(n);
  w.kappa_v.resize(n);
  auto ownTerms = [&](std::size_t i, glm::vec3 grad_sum, float grad_sq) {
    const float rho = S.density[i];
    if (wcsph) {
      // The ratio is clamped to 1.5: real flows stay within a few per cent, and degenerate input
      // (particles stacked on one point) would otherwise produce pressures of 1e12 B.
      const float ratio = std::min(rho / rho0, 1.5f);
      float power;
      if (gamma7) {  // the default gamma = 7 by products (a powf call cost more than the rest of the loop)
        const float r2 = ratio * ratio, r4 = r2 * r2;
        power = r4 * r2 * ratio;
      } else {
        power = std::pow(ratio, P.tait_exponent);
      }
      S.pressure[i] = std::max(0.0f, tait_b * (power - 1.0f));
      pr[i] = S.pressure[i] / (rho * rho);
      visc_coef[i] = 10.0f * nu / rho;
    } else {
      w.vel4[i].w = 10.0f * nu / rho;  // read with the neighbour's velocity by the viscosity loop
      // alpha_i = rho_i / (|sum_j m_j grad W_ij|^2 + sum_j |m_j grad W_ij|^2) (Bender & Koschier
      // 2015 eq. 9). The boundary mirrors the particle's pressure (p_b = p_i, so its term has
      // weight 2 in the velocity update below); it does not move, so it adds
      // (S + rho_0 g) . (S + 2 rho_0 g) instead of |S|^2 where S = sum_j m_j grad W_ij.
      const glm::vec3 sum = grad_sum + rho0 * w.boundary_gradient[i];
      const float denom = glm::dot(sum, sum + (kMirror - 1.0f) * rho0 * w.boundary_gradient[i]) + grad_sq;
      w.factor[i] = denom > 1e-9f * rho0 * rho0 / (H * H) ? rho / denom : 0.0f;
      // kappa^v_i / rho_i = (Drho/Dt)_i alpha_i / (dt rho_i) (2015 eq. 9 with the factor of
      // §4.1): the per-particle part once per solve, a product per iteration.
      kscale[i] = w.factor[i] / (dt_prev * rho);
      w.vec_a[i] = V[i];       // velocities before the divergence solve (capChange)
      w.kappa_v[i] = 0.0f;     // sum over the divergence iterations of kappa^v_i / rho_i
      w.float_tmp[i] = 0.0f;   // same for the density iterations
    }
    w.kappa[i] = 0.0f;
    w.old_position[i] = X[i];
  };
  const glm::vec3* __restrict Xp = X.data();
  std::uint32_t* __restrict verlet_counts = w.neighbors.counts.data();
  const CubicSplineKernel kernel = w.kernel;
  const DensityConsts dc = DensityConsts::make(w.kernel, m, r_min, steepest);
  if (!filter_verlet) w.pair_offset.resize(pair_count);  // n < 2^28 (validateSphParams), so 16 j fits
  std::uint32_t* const nb16_out = w.pair_offset.data();
  {
    const SumMax e = reduceChunks(
        n, SumMax{},
        [&](std::size_t b, std::size_t end, SumMax& acc) {
          for (std::size_t i = b; i < end; ++i) {
            if (filter_verlet) {
              float sum = w0;
              const glm::vec3 xi = Xp[i];
              const std::uint32_t first = off[i], last = cand_end[i];
              std::uint32_t out = first;
              for (std::uint32_t k = first; k < last; ++k) {
                const std::uint32_t j = cand[k];
                const glm::vec3 x = xi - Xp[j];
                // The same float test as the search (dot(x_ij, x_ij) < H^2), so the filtered list is
                // exactly a fresh search's.
                if (!(glm::dot(x, x) < h2)) continue;
                nbr_out[out] = j;
                const float r = glm::length(x);
                float wr, dr;
                kernel.evaluateInside(r, wr, dr);  // r <= H: the pair is in the list
                sum += wr;
                const glm::vec3 g = r > r_min ? m * (dr * x) : (m * steepest) * coincidentDirection(S.id[i], S.id[j]);
                gx_out[out] = g.x;
                gy_out[out] = g.y;
                gz_out[out] = g.z;
                ++out;
              }
              verlet_counts[i] = out - first;
              S.density[i] = m * sum + rho0 * w.boundary_volume[i];
              w.vec_b[i] = glm::vec3(0.0f);
              w.factor[i] = 0.0f;
              ownTerms(i, glm::vec3(0.0f), 0.0f);
            } else {
              const DensitySums ds = loops.density(dc, w.pos4.data(), S.id.data(), nbr, off[i], cand_end[i],
                                                   static_cast<std::uint32_t>(i), gx_out, gy_out, gz_out, nb16_out);
              S.density[i] = m * (w0 + ds.w) + rho0 * w.boundary_volume[i];
              ownTerms(i, ds.grad, ds.sq);
            }
            const float err = std::max(0.0f, S.density[i] / rho0 - 1.0f);
            acc.sum += err;
            acc.max = std::max(acc.max, err);
          }
        },
        joinSumMax);
    stats.avg_density_error = n ? static_cast<float>(e.sum / static_cast<double>(n)) : 0.0f;
    stats.max_density_error = e.max;
  }
  const float* const gx = w.grad_x.data();
  const float* const gy = w.grad_y.data();
  const float* const gz = w.grad_z.data();

  // 4. Non-pressure accelerations: gravity + Laplacian viscosity (Monaghan 2005 eq. 6.3 form,
  // a_i = 2(d+2) nu sum_j m_j/rho_j (v_ij . x_ij)/(|x_ij|^2 + 0.01 H^2) grad W_ij, d = 3) and, for
  // WCSPH, Becker & Teschner's artificial viscosity Pi_ij (eq. 10-11).
  auto nonPressure = [&](auto with_pressure, auto with_viscosity) {
    constexpr bool kPressure = decltype(with_pressure)::value, kViscosity = decltype(with_viscosity)::value;
    const glm::vec3* __restrict Vp = V.data();
    const float* __restrict vc = visc_coef.data();
    const float* __restrict prp = pr.data();
    const float eps = 0.01f * H * H;
    forEach(n, [&](std::size_t i) {
      glm::vec3 a = P.gravity;
      if (kViscosity || kPressure || alpha_av > 0.0f) {
        const float pi = kPressure ? prp[i] : 0.0f;
        const glm::vec3 xi = Xp[i], vi = Vp[i];
        const std::uint32_t first = off[i], last = off[i] + cnt[i];
        for (std::uint32_t k = first; k < last; ++k) {
          const std::uint32_t j = nbr[k];
          const glm::vec3 xij = xi - Xp[j];
          const float vx = glm::dot(vi - Vp[j], xij);
          const float denom = glm::dot(xij, xij) + eps;
          float coef = 0.0f;
          if constexpr (kViscosity) coef = vc[j] * (vx / denom);
          if (alpha_av > 0.0f && vx < 0.0f) {
            const float nu_ij = 2.0f * alpha_av * h_bt * cs / (S.density[i] + S.density[j]);
            coef += nu_ij * vx / denom;  // - Pi_ij, Pi_ij = -nu_ij vx / denom
          }
          // Symmetric pressure force (B&T eq. 6).
          if constexpr (kPressure) coef -= pi + prp[j];
          a += coef * glm::vec3(gx[k], gy[k], gz[k]);
        }
        // Boundary: the same symmetric pressure term against the wall volume with the mirrored
        // pressure p_b = p_i, rho_b = rho_i.
        if constexpr (kPressure) a -= 2.0f * rho0 * pi * w.boundary_gradient[i];
      }
      w.accel[i] = a;
    });
  };
  auto maxLength = [](float x, float y) { return std::max(x, y); };
  // DFSPH's density rates Drho/Dt_i = sum_j m_j (v_i - v_j) . grad W_ij + rho_0 (v_i - v_b) . grad V_i
  // (continuity equation) for the particles [b, e) (at most kGrain) into rate[0 .. e - b).
  const IterationArgs ia{w.vel4.data(), gx, gy, gz, nbr, w.pair_offset.data(), off, cnt};
  auto densityRates = [&](std::size_t b, std::size_t e, float* rate) {
    loops.divergence_range(ia, static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e), rate);
    for (std::size_t i = b; i < e; ++i)
      rate[i - b] += rho0 * (glm::dot(V[i], w.boundary_gradient[i]) - w.boundary_flux[i]);
  };
  auto& kr4 = w.kappa4;  // kr4[i].x = kappa_i / rho_i of the current iteration
  kr4.resize(n);
  // One error pass of the divergence-free solve (section 4a): kappa^v_i / rho_i into kr4 and the
  // summed divergence error.
  auto divergenceError = [&](std::size_t b, std::size_t e, double& acc) {
    float rates[kGrain];
    densityRates(b, e, rates);
    for (std::size_t i = b; i < e; ++i) {
      // Only compression is corrected, and only for particles with a full enough neighbourhood
      // (2017 paper §4.1: >= 20 neighbours in 3D; the wall counts as the 9 lattice neighbours a
      // flat wall replaces per wall_share of volume), otherwise the free surface is pushed outward
      // every step and the fluid creeps apart.
      const float neighbours = static_cast<float>(cnt[i]) + w.boundary_volume[i] * w.wall_neighbours;
      const float rate = neighbours >= 20.0f ? std::max(0.0f, rates[i - b]) : 0.0f;
      kr4[i].x = rate * kscale[i];
      acc += rate * dt_prev / rho0;
    }
  };
  const bool divergence = !wcsph && P.divergence_solver && n > 0;
  float dfsph_amax = 0.0f;              // DFSPH: max |a| of the non-pressure accelerations, from the same pass
  double first_divergence_error = 0.0;  // DFSPH: the divergence solve's first error pass, from the same pass
  if (wcsph) {
    if (nu > 0.0f)
      nonPressure(std::true_type{}, std::true_type{});
    else
      nonPressure(std::true_type{}, std::false_type{});
  } else {
    // DFSPH: viscosity only (alpha_av is 0), in the eight-lane pair loop. The divergence solve's
    // first error pass only reads the step-start velocities, so it runs in the same region (in
    // the same chunks and order as a pass of its own: the same sum).
    const float eps = 0.01f * H * H;
    struct AccelError {
      float amax = 0.0f;
      double err = 0.0;
    };
    const AccelError ae = reduceChunks(
        n, AccelError{},
        [&](std::size_t b, std::size_t e, AccelError& acc) {
          for (std::size_t i = b; i < e; ++i) {
            if (nu > 0.0f)
              w.accel[i] = P.gravity + loops.viscosity(w.pos4.data(), w.vel4.data(), gx, gy, gz, nbr, off[i],
                                                       off[i] + cnt[i], static_cast<std::uint32_t>(i), eps);
            else
              w.accel[i] = P.gravity;
            acc.amax = std::max(acc.amax, glm::length(w.accel[i]));
          }
          if (divergence) divergenceError(b, e, acc.err);
        },
        [](AccelError a, const AccelError& b) {
          a.amax = std::max(a.amax, b.amax);
          a.err += b.err;
          return a;
        });
    dfsph_amax = ae.amax;
    first_divergence_error = ae.err;
  }

  float dt = max_dt;
  int iterations = 0, div_iterations = 0;

  auto maxSpeed = [&]() {
    return reduce(
        n, 0.0f, [&](std::size_t i, float& acc) { acc = std::max(acc, glm::length(V[i])); },
        [](float a, float b) { return std::max(a, b); });
  };
  auto maxAccel = [&]() {
    return reduce(
        n, 0.0f, [&](std::size_t i, float& acc) { acc = std::max(acc, glm::length(w.accel[i])); },
        [](float a, float b) { return std::max(a, b); });
  };
  auto chooseDt = [&](float vmax, float amax, bool wcsph_bounds, bool spread = true) {
    stats.max_acceleration = amax;
    float t = max_dt;
    const float v = std::max(vmax, collider_speed);
    if (v > 0.0f) t = std::min(t, P.cfl * d / v);
    // Force condition: a step may compress the fluid by at most ~0.1 % of d (at cfl = 0.4) from the
    // non-pressure acceleration alone (|a| dt^2 <= 0.0025 cfl d). The pressure solvers stop at a
    // mean density error tolerance, so a larger per-step compression (a resting column under
    // gravity, which the CFL velocity bound does not limit) is left partly unresolved every step and
    // builds up into noise.
    const float body = glm::length(P.gravity);
    if (body > 0.0f && P.force_bound > 0.0f) t = std::min(t, std::sqrt(P.force_bound * P.cfl * d / body));
    // Explicit viscosity stability (diffusion number): dt <= 0.125 d^2 / nu (Morris et al. 1997).
    if (P.viscosity > 0.0f) t = std::min(t, 0.125f * d * d / P.viscosity);
    if (wcsph_bounds) {
      // Becker & Teschner 2007 §4: dt <= 0.4 h / (c_s (1 + 0.6 alpha)), dt <= 0.25 sqrt(h / |a|max)
      // with the total acceleration (pressure included).
      t = std::min(t, 0.4f * h_bt / (cs * (1.0f + 0.6f * alpha_av)));
      if (amax > 0.0f) t = std::min(t, 0.25f * std::sqrt(h_bt / amax));
    }
    t = std::max(t, std::min(P.min_time_step, max_dt));  // the caller's bound wins over min_time_step
    // stepSphWithin: the time left to the caller's target is split into equal steps no longer
    // than t, and this step is one of them, so the last step of a frame is never a sliver (a cut
    // step could be 1e-7 s long). DFSPH's constant-density solve removes the whole predicted
    // compression within one step (Bender & Koschier 2015 §4.2, eq. 8-12: kappa ~ (rho* - rho_0)
    // / dt^2, a velocity change ~ (rho* - rho_0) / dt), so in a sliver the 0.05 % compression the
    // tolerance leaves standing becomes metres per second, and the sliver's stiffness then
    // warm-started the next full step (2017 §4.3). With equal steps each step is at least half
    // of t (the next bound may differ, then the rest is split again).
    // (The 1e-5 slack: max_dt is the float of span, which may round below it.)
    if (spread && span > static_cast<double>(t))
      t = static_cast<float>(span / std::ceil(span / static_cast<double>(t) * (1.0 - 1e-5)));
    return t;
  };

  auto& Xmut = S.position;
  bool advected = false;  // DFSPH without XSPH advects in its last per-particle pass
  // Coupling sums (section 6) per collider: force and torque about the pose's translation.
  struct FT {
    glm::vec3 f{0.0f}, t{0.0f};
  };
  auto couplingTerm = [&](std::size_t c, std::size_t i, FT& acc) {
    const ColliderSample& s = w.start_samples[c][i];
    if (!s.valid || s.distance >= H) return;
    const glm::vec3 grad = boundaryShare(w, s, w.boundary_product[i]);
    const glm::vec3 f = (2.0f * m * w.kappa[i] * rho0 / dt) * grad;  // = -m dv / dt, dv = -2 kappa rho_0 grad
    acc.f += f;
    acc.t += glm::cross(w.old_position[i] - world.colliders[c].pose.translation, f);
  };
  constexpr std::size_t kFusedColliders = 4;
  struct CouplingSums {
    FT c[kFusedColliders];
  };
  CouplingSums coupling{};
  bool coupled = false;  // coupling holds section 6's sums

  if (wcsph) {
    // The pressure force was added to w.accel in the pair pass above (section 4).
    dt = chooseDt(maxSpeed(), maxAccel(), true);
    forEach(n, [&](std::size_t i) {
      V[i] += dt * w.accel[i];
      w.kappa[i] = dt * pr[i];
    });
  } else {
    // DFSPH (alpha_i was computed in the density pass, densityRates is defined in section 4).
    // v_i -= dt (sum_j m_j (k_i + k_j) grad W_ij + 2 rho_0 k_i grad V_i)   (2015 eq. 13 / 15)
    auto applyKappa = [&](float h, std::vector<float>& total) {
      forChunks(n, [&](std::size_t b, std::size_t e) {
        glm::vec3 sums[kGrain];
        loops.kappa_range(ia, kr4.data(), static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e), sums);
        for (std::size_t i = b; i < e; ++i) {
          const glm::vec3 dv = kMirror * rho0 * kr4[i].x * w.boundary_gradient[i] + sums[i - b];
          w.vec_b[i] = V[i] - h * dv;
          w.vel4[i] = glm::vec4(w.vec_b[i], 0.0f);  // the copy the next divergence pass reads
          total[i] += kr4[i].x;
        }
      });
      V.swap(w.vec_b);  // Jacobi: all updates read the old velocities; swapping keeps both buffers
    };

    // Each solve may change a particle's velocity by at most d / (2 dt_nominal) per step.
    // Legit flows stay far below (the CFL bound keeps v dt <= cfl d); heavily overlapped input
    // (stacked particles, a grid at half spacing) is then separated over a few steps at a bounded
    // speed instead of being fired apart in one.
    // The cap uses the velocity-independent step bound, so it cannot grow as the CFL shrinks dt.
    // Applied to one particle in the pass that follows each solve.
    const float nominal_dt = chooseDt(0.0f, 0.0f, false, false);
    const float cap = 0.5f * d / nominal_dt;
    auto capChange = [&](std::size_t i) {
      const glm::vec3 dv = V[i] - w.vec_a[i];
      const float len = glm::length(dv);
      if (len > cap) V[i] = w.vec_a[i] + dv * (cap / len);
    };

    // 4a. Divergence-free solver (§4.1) on the current velocities: Drho/Dt -> 0. The density pass
    // set w.vec_a = V, kscale and kappa_v; vel4 holds V since the re-sort.
    if (divergence) {
      // No warm start here: starting the divergence solve from part of the last step's kappa^v
      // (2017 §4.3) let a jet hitting a collider gain energy in the randomised stability test
      // (tests/sph), since the solver never pulls particles back once pushed too far.
      const double eta_v = P.max_divergence_error;
      for (;;) {
        // The first error pass ran together with the viscosity pass (section 4).
        const double err = (div_iterations == 0 ? first_divergence_error
                                                : reduceChunks(n, 0.0, divergenceError,
                                                               [](double a, double b) { return a + b; })) /
                           static_cast<double>(n);
        if ((div_iterations >= 1 && err <= eta_v) || div_iterations >= P.max_iterations)
          break;  // 2017 paper: at least one
        applyKappa(dt_prev, w.kappa_v);
        ++div_iterations;
      }
    }

    // 4b. Time step, then predicted velocities v* = v + dt a_nonpressure (Algorithm 1). The
    // divergence solve's velocity cap runs in the same pass as the speed bound.
    const float vmax = reduce(
        n, 0.0f,
        [&](std::size_t i, float& acc) {
          if (divergence) capChange(i);
          acc = std::max(acc, glm::length(V[i] + max_dt * w.accel[i]));
        },
        maxLength);
    dt = chooseDt(vmax, dfsph_amax, false);
    forEach(n, [&](std::size_t i) {
      V[i] += dt * w.accel[i];
      w.vel4[i] = glm::vec4(V[i], 0.0f);
      w.vec_a[i] = V[i];
      // kappa_i / rho_i = (rho*_i - rho_0) alpha_i / (dt^2 rho_i) (2015 eq. 8-9): as above.
      kscale[i] = w.factor[i] / (dt * dt * S.density[i]);
    });

    // 4c. Constant-density solver (§4.2): rho*_i = rho_i + dt Drho/Dt_i -> rho_0.
    if (n > 0) {
      if (P.warm_start) {
        // Warm start (2017 §4.3): in steady flow (a resting column) kappa/rho is the same every
        // step and independent of dt (a pressure acceleration over a gradient), so a share of the
        // last step's sum is applied first, and only where the particle is compressing now: a
        // one-off push from the last step must not be repeated on a particle that already
        // expands, since the solver never pulls particles back (only compression is corrected).
        // The share is 0.2 rather than the paper's full kappa: a push repeated where it is no
        // longer needed is never taken back, so any share keeps a resting column moving (off by
        // default: SphParams::warm_start gives the figures) and with 0.5 the randomised stability
        // test (a jet against a collider) gains energy.
        // The stored sum was found for the last step's dt. Its steady part (the pressure that
        // holds a column up) does not depend on dt, but the part that removed a standing
        // compression does, as 1 / dt^2 (eq. 8-9: kappa = (rho* - rho_0) alpha / dt^2): applied over
        // a longer step it would displace particles further than the solve that found it. So
        // when dt grew, the share is scaled by (dt_prev / dt)^2 (the warm start then displaces no
        // further than the last step's solve did); when it shrank, the pressure is kept (its
        // displacement dt^2 kappa shrinks with dt). Constant steps: a factor of exactly 1.
        const float warm = dt > dt_prev ? kWarmShare * (dt_prev / dt) * (dt_prev / dt) : kWarmShare;
        forChunks(n, [&](std::size_t b, std::size_t e) {
          float rates[kGrain];
          densityRates(b, e, rates);
          for (std::size_t i = b; i < e; ++i)
            kr4[i].x = S.density[i] + dt * rates[i - b] > rho0 ? warm * w.warm_kappa[i] : 0.0f;
        });
        applyKappa(dt, w.float_tmp);
      }
      const double eta = P.max_density_error;
      for (;;) {
        const double err = reduceChunks(
                               n, 0.0,
                               [&](std::size_t b, std::size_t e, double& acc) {
                                 float rates[kGrain];
                                 densityRates(b, e, rates);
                                 for (std::size_t i = b; i < e; ++i) {
                                   const float excess = std::max(0.0f, S.density[i] + dt * rates[i - b] - rho0);
                                   kr4[i].x = excess * kscale[i];
                                   acc += excess / rho0;
                                 }
                               },
                               [](double a, double b) { return a + b; }) /
                           static_cast<double>(n);
        if ((iterations >= P.min_iterations && err <= eta) || iterations >= P.max_iterations) break;
        applyKappa(dt, w.float_tmp);
        ++iterations;
      }
      // The velocity cap, the solver outputs, (without XSPH) the advection of section 5 and (up
      // to kFusedColliders colliders) the coupling sums of section 6 in one pass.
      advected = P.xsph <= 0.0f;
      auto finalTerms = [&](std::size_t i) {
        capChange(i);
        w.warm_kappa[i] = w.float_tmp[i];
        // Effective pressure p_i = rho_i^2 (kappa_i / rho_i summed) for output; impulse for coupling.
        S.pressure[i] = S.density[i] * S.density[i] * (w.float_tmp[i] + w.kappa_v[i] * dt_prev / dt);
        w.kappa[i] = dt * w.float_tmp[i] + dt_prev * w.kappa_v[i];
        if (advected) Xmut[i] += dt * V[i];
      };
      if (nc <= kFusedColliders) {
        coupled = true;
        coupling = reduce(
            n, CouplingSums{},
            [&](std::size_t i, CouplingSums& acc) {
              finalTerms(i);
              for (std::size_t c = 0; c < nc; ++c)
                if (world.colliders[c].boundary_pressure) couplingTerm(c, i, acc.c[c]);
            },
            [](CouplingSums a, const CouplingSums& b) {
              for (std::size_t c = 0; c < kFusedColliders; ++c) {
                a.c[c].f += b.c[c].f;
                a.c[c].t += b.c[c].t;
              }
              return a;
            });
      } else {
        forEach(n, finalTerms);
      }
    }
  }

  // 5. Advection (symplectic Euler) with optional XSPH smoothing of the advection velocity.
  if (advected) {
    // done above
  } else if (P.xsph > 0.0f) {
    w.vec_b.resize(n);
    forEach(n, [&](std::size_t i) {
      glm::vec3 corr(0.0f);
      for (std::uint32_t k = off[i]; k < off[i] + cnt[i]; ++k) {
        const std::uint32_t j = nbr[k];
        corr += (2.0f * m / (S.density[i] + S.density[j]) * w.kernel.value(glm::length(X[i] - X[j]))) * (V[j] - V[i]);
      }
      w.vec_b[i] = V[i] + P.xsph * corr;
    });
    forEach(n, [&](std::size_t i) { Xmut[i] += dt * w.vec_b[i]; });
  } else {
    forEach(n, [&](std::size_t i) { Xmut[i] += dt * V[i]; });
  }

  // 6. Coupling forces from the boundary pressure terms: F_c = -sum_i m dv_ic / dt (summed in
  // DFSPH's last per-particle pass when there are few colliders, otherwise here).
  for (std::size_t c = 0; c < nc; ++c) {
    SphCollider& col = world.colliders[c];
    FT ft{};
    if (coupled) {
      ft = coupling.c[c];
    } else if (col.boundary_pressure) {
      ft = reduce(
          n, FT{}, [&](std::size_t i, FT& acc) { couplingTerm(c, i, acc); },
          [](FT a, const FT& b) {
            a.f += b.f;
            a.t += b.t;
            return a;
          });
    }
    col.force = ft.f;
    col.torque = ft.t;
  }

  // 7. Collisions: Kolb et al. 2004 §3.3.2 double check against the collider at its end-of-step
  // pose, with the step-start sample as "previous". Repeated (up to 4 passes) while a later
  // collider pushed a particle into an earlier one (corners), so no particle ends the step inside a
  // collider where a position outside all of them exists nearby.
  // One parallel region per (pass, collider): query, reaction and the reaction force/torque sums.
  // Queries that cannot change the outcome are skipped (bit-identical results):
  //  - in passes after the first, a particle that has not moved since collider c last queried it
  //    gets the same sample, so the same (no) reaction: only particles moved since are queried;
  //  - for a static collider with a 1-Lipschitz distance (SphCollider::lipschitz_distance), a
  //    particle that started at s0 and moved less than s0 (minus a margin) stayed outside along
  //    its whole step (every point of the segment is at least s0 - |displacement| > 0 away): no
  //    reaction and nothing tunnelled, so no query is needed. (The tunnelling test below could
  //    only fire there on a normal flip across a medial axis, e.g. between the fountain's spire
  //    and its dish wall, which is not a crossing for a collider that does not move.)
  // Order within a pass: the colliders that move during the step first, the still ones
  // (sphColliderMoves false) last, so a pass ends with the still colliders' projections. Where a
  // moving collider's end-of-step pose overlaps a still one (a crate, advanced by its velocities
  // through the step, reaching into the basin wall, which Bullet stops only afterwards), a particle
  // between them has no position outside both, and alternating projections would otherwise leave
  // it wherever the last collider put it: inside the wall, carried further by the crate every
  // step. Still colliders win: the particle ends outside them, inside the moving collider only
  // where that overlaps a still one, and the moving collider gets the reactions of its own
  // projections (its push on the particle) like any other contact.
  w.collide_order.resize(nc);
  w.push_plane.resize(n);
  {
    std::size_t k = 0;
    for (const bool moving_first : {true, false})
      for (std::size_t c = 0; c < nc; ++c)
        if (sphColliderMoves(world.colliders[c]) == moving_first) w.collide_order[k++] = static_cast<std::uint32_t>(c);
  }
  const float skin = P.collision_skin > 0.0f ? P.collision_skin : 0.01f * P.particle_radius;
  w.end_samples.resize(nc);
  w.collide_stale.resize(n);
  const bool track_stale = nc <= 32;
  const std::uint32_t all_colliders = nc >= 32 ? ~0u : (1u << nc) - 1u;
  struct Hits {
    std::size_t count = 0;
    FT ft{};
  };
  for (int pass = 0; pass < 4 && nc > 0; ++pass) {
    std::size_t inside_total = 0;
    for (std::size_t k = 0; k < nc; ++k) {
      const std::size_t c = w.collide_order[k];
      SphCollider& col = world.colliders[c];
      const ColliderPose pose = col.integrate_pose ? advancedPose(col.pose, dt) : col.pose;
      // Does not move during the step: the end pose is the start pose, so are the samples' distances.
      const bool still = !sphColliderMoves(col);
      const bool skip_far = still && col.lipschitz_distance;
      const std::uint32_t bit = track_stale ? 1u << c : 0u;
      const ColliderQuery query(col, pose);
      auto& es = w.end_samples[c];
      es.resize(n);
      const auto& s0s = w.start_samples[c];
      const Hits hits = reduceChunks(
          n, Hits{},
          [&](std::size_t b, std::size_t e, Hits& acc) {
            std::uint32_t which[kGrain];
            std::uint32_t q = 0;
            for (std::size_t i = b; i < e; ++i) {
              if (pass == 0 && k == 0) {
                w.collide_stale[i] = all_colliders;
                w.push_plane[i] = glm::vec4(0.0f);
              }
              if (track_stale && pass > 0 && !(w.collide_stale[i] & bit)) continue;  // unchanged: same sample
              w.collide_stale[i] &= ~bit;
              const ColliderSample& s0 = s0s[i];
              if (skip_far && s0.valid) {
                const glm::vec3 p = X[i], p0 = w.old_position[i];
                // Float slack of the distance evaluation, far above its rounding at these coordinates.
                const float slack = 1e-6f * (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), std::abs(p0.x),
                                                       std::abs(p0.y), std::abs(p0.z)}) +
                                             H);
                if (s0.distance > glm::length(p - p0) + skin + slack) {
                  es[i].valid = false;  // cannot have reached the surface: no reaction
                  continue;
                }
              }
              which[q++] = static_cast<std::uint32_t>(i);
            }
            query.run(X, which, q, es);
            for (std::size_t i = b; i < e; ++i) {
              const ColliderSample& s = es[i];
              const ColliderSample& s0 = s0s[i];
              // Tunnelling through a thin part: outside at both ends of the step but on opposite
              // sides (the outward normal flipped), e.g. a thin fast wall that moved past the particle.
              // The particle stays on its side: carried along by the collider, then the §3.3.2
              // reaction against the side it came from.
              const bool crossed = s.valid && s0.valid && s.distance >= 0.0f && s0.distance >= 0.0f && s.distance < H &&
                                   s0.distance < H && glm::dot(s.normal, s0.normal) < 0.0f;
              if (!crossed && (!s.valid || s.distance >= 0.0f)) continue;
              ++acc.count;
              CollisionResult res;
              if (crossed) {
                const glm::vec3 vc = colliderVelocityAt(col.pose, w.old_position[i]);
                res.position = w.old_position[i] + vc * dt + s0.normal * skin;
                res.velocity = collisionResponse(V[i] - vc, s0.normal, col.material) + vc;
              } else {
                res = resolveCollision(w.old_position[i], s0, X[i], V[i], s, colliderVelocityAt(pose, X[i]), dt, skin,
                                       col.material);
              }
              if (!still) {
                // The moving face the particle now rests on: n . x >= n . x_now (it sits skin outside).
                const glm::vec3 nm = crossed ? s0.normal : s.normal;
                w.push_plane[i] = glm::vec4(nm, glm::dot(nm, res.position));
              } else if (!crossed && w.push_plane[i] != glm::vec4(0.0f)) {
                res.position = wedgePosition(X[i], s.normal, skin - s.distance, w.push_plane[i], d, res.position);
              }
              const glm::vec3 reaction = -m * (res.velocity - V[i]) / dt;  // on the collider
              Xmut[i] = res.position;
              V[i] = res.velocity;
              w.collide_stale[i] = all_colliders;  // moved: every collider's sample is out of date
              // Particles without a reaction add exact zeros in a separate sum (an accumulator
              // starting at +0 never becomes -0), so skipping them gives the same sums.
              acc.ft.f += reaction;
              acc.ft.t += glm::cross(X[i] - pose.translation, reaction);
            }
          },
          [](Hits a, const Hits& b2) {
            a.count += b2.count;
            a.ft.f += b2.ft.f;
            a.ft.t += b2.ft.t;
            return a;
          });
      inside_total += hits.count;
      stats.collisions += hits.count;
      if (hits.count > 0) {
        col.force += hits.ft.f;
        col.torque += hits.ft.t;
      }
    }
    if (inside_total == 0) break;
  }
  for (SphCollider& col : world.colliders)
    if (col.integrate_pose) col.pose = advancedPose(col.pose, dt);

  advanceEmitterClocks(world, dt);
  world.time += dt;
  world.last_dt = dt;
  ++world.step_count;

  stats.dt = dt;
  stats.density_iterations = iterations;
  stats.divergence_iterations = div_iterations;
  stats.particles = n;
  stats.dt_limited_by_request = requested < P.max_time_step && dt >= requested;
  // The speed cap and the kinetic energy in one pass (the energy of the capped velocities).
  stats.kinetic_energy = static_cast<float>(0.5 * m *
                                            reduce(
                                                n, 0.0,
                                                [&](std::size_t i, double& acc) {
                                                  if (P.max_speed > 0.0f) {
                                                    const float sp = glm::length(V[i]);
                                                    if (sp > P.max_speed) V[i] *= P.max_speed / sp;
                                                  }
                                                  acc += glm::dot(V[i], V[i]);
                                                },
                                                [](double a, double b) { return a + b; }));
  stats.step_ms = msSince(t_start);
  if (stats_out) *stats_out = stats;
  return {};
}

}  // namespace

}  // namespace fluid
