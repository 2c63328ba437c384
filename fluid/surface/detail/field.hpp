#pragma once
// Internal: the paper's field f(r) (§2) and the particle preparation shared by marching slices,
// the baselines and the dense oracle. Every extractor sums contributions in the same order
// (particles sorted by (z, input index)) with the same double expressions, so the corner values
// — and therefore the triangles — agree bit for bit between methods and block sizes.

#include "fluid/surface/marching_slices.hpp"

#include <glm/mat3x3.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace fluid::detail {

// One particle, prepared. Positions are doubles of the float input.
struct Particle {
  double x, y, z;
  double rc2;              // Rc_i^2: influence iff (dx*dx + dy*dy) + dz*dz < rc2 (in double)
  std::int64_t anchor[3];  // lattice index floor(p / S) per axis
  float rest[3];           // float(p - anchor * S) per axis, in [0, S)
  float k;                 // 1 / (2 Rc_i^2), so u = r^2 k = (r / (sqrt2 Rc_i))^2
  float strength;          // s_i
  std::uint32_t index;     // input index (user data)
};

// The exact-influence predicate. Every lookup structure must return exactly the particles for
// which this is true at the corner (no more, no fewer).
inline bool influences(const Particle& p, double cx, double cy, double cz) {
  const double dx = cx - p.x, dy = cy - p.y, dz = cz - p.z;
  return (dx * dx + dy * dy) + dz * dz < p.rc2;
}

// Shared arithmetic of every extractor: the offset from a particle to lattice corner c along an
// axis is float((c - anchor) * S) - rest, which depends only on the global lattice index (not on
// any block origin) and stays precise far from the origin. The paper's f(r) is then evaluated in
// float:  f = s (u - 1/2)^2, u = r^2 k;  df/dc = 4 s (u - 1/2) k (c - p).
inline float latticeOffset(std::int64_t corner, std::int64_t anchor, float rest, double s) {
  return float(double(corner - anchor) * s) - rest;
}

// dz2 is the float product dz * dz (callers may have it already; same bits either way).
inline float contributionDz2(float dxy2, float dz2, float k, float s) {
  const float w = (dxy2 + dz2) * k - 0.5f;
  return s * (w * w);
}
inline float contribution(float dxy2, float dz, float k, float s) { return contributionDz2(dxy2, dz * dz, k, s); }

inline void accumulateDz2(float dx, float dy, float dxy2, float dz, float dz2, float k, float s, float& value,
                          float& gx, float& gy, float& gz) {
  const float w = (dxy2 + dz2) * k - 0.5f;
  value += s * (w * w);
  const float g = 4.0f * s * w * k;
  gx += g * dx;
  gy += g * dy;
  gz += g * dz;
}
// The same with s4 = 4.0f * s formed by the caller (same bits: 4.0f * s * w * k is (4s * w) * k).
inline void accumulateDz2S4(float dx, float dy, float dxy2, float dz, float dz2, float k, float s, float s4,
                            float& value, float& gx, float& gy, float& gz) {
  const float w = (dxy2 + dz2) * k - 0.5f;
  value += s * (w * w);
  const float g = s4 * w * k;
  gx += g * dx;
  gy += g * dy;
  gz += g * dz;
}
inline void accumulate(float dx, float dy, float dxy2, float dz, float k, float s, float& value, float& gx, float& gy,
                       float& gz) {
  accumulateDz2(dx, dy, dxy2, dz, dz * dz, k, s, value, gx, gy, gz);
}

// Lattice-corner form (oracle, baselines). Caller guarantees influences() is true there.
inline void accumulate(const Particle& p, std::int64_t i, std::int64_t j, std::int64_t k, double s, float& value,
                       float& gx, float& gy, float& gz) {
  const float dx = latticeOffset(i, p.anchor[0], p.rest[0], s), dy = latticeOffset(j, p.anchor[1], p.rest[1], s),
              dz = latticeOffset(k, p.anchor[2], p.rest[2], s);
  accumulate(dx, dy, dx * dx + dy * dy, dz, p.k, p.strength, value, gx, gy, gz);
}

// An anisotropic particle's quadratic form (Yu & Turk 2013, Eq. 16 with the paper's kernel
// W(x - x̄, G) = σ det(G) P(|G (x - x̄)|)): the marching-slices field keeps its f = s (u - 1/2)^2
// but with u = |g (c - x̄)|^2 / (2 Rc_i^2) = d^T M d, M = g^T g / (2 Rc_i^2) in the sweep frame,
// and no term where u >= 1/2 (outside the ellipsoid |g d| < Rc_i, where f reaches 0 as the
// sphere's does at Rc_i). Symmetric: xx, xy, xz, yy, yz, zz. 32 bytes, so a block's copy is read
// with the same scaled index as its CacheParticle records (atParticle8).
struct StretchTerm {
  float m[6];
  float unused[2];
};
static_assert(sizeof(StretchTerm) == 32);

// u = d^T M d with the off-diagonal terms doubled, in one fixed order of float operations (the
// same bits in every route that sums it).
[[gnu::always_inline]] inline float stretchedU(const StretchTerm& t, float dx, float dy, float dz) {
  const float* m = t.m;
  return (m[0] * dx * dx + m[3] * dy * dy + m[5] * dz * dz) + 2.0f * (m[1] * dx * dy + m[2] * dx * dz + m[4] * dy * dz);
}
// The anisotropic particle's term (0 outside its ellipsoid).
[[gnu::always_inline]] inline float stretchedContribution(const StretchTerm& t, float dx, float dy, float dz, float s) {
  const float u = stretchedU(t, dx, dy, dz);
  if (!(u < 0.5f)) return 0.0f;
  const float w = u - 0.5f;
  return s * (w * w);
}
// Its term and gradient: df/dc = 2 s (u - 1/2) du/dc = 4 s (u - 1/2) M d.
[[gnu::always_inline]] inline void accumulateStretched(const StretchTerm& t, float dx, float dy, float dz, float s, float& value, float& gx,
                                float& gy, float& gz) {
  const float u = stretchedU(t, dx, dy, dz);
  if (!(u < 0.5f)) return;
  const float w = u - 0.5f;
  value += s * (w * w);
  const float g = 4.0f * s * w;
  const float* m = t.m;
  gx += g * (m[0] * dx + m[1] * dy + m[2] * dz);
  gy += g * (m[1] * dx + m[3] * dy + m[4] * dz);
  gz += g * (m[2] * dx + m[4] * dy + m[5] * dz);
}

// Lattice-corner form of either kind (the dense oracle, the baselines): `stretch` is the
// particles' StretchTerm array by input index, or null for spheres. Caller guarantees influences().
inline void accumulateAt(const Particle& p, const StretchTerm* stretch, std::int64_t i, std::int64_t j, std::int64_t k,
                         double s, float& value, float& gx, float& gy, float& gz) {
  if (stretch == nullptr) return accumulate(p, i, j, k, s, value, gx, gy, gz);
  const float dx = latticeOffset(i, p.anchor[0], p.rest[0], s), dy = latticeOffset(j, p.anchor[1], p.rest[1], s),
              dz = latticeOffset(k, p.anchor[2], p.rest[2], s);
  accumulateStretched(stretch[p.index], dx, dy, dz, p.strength, value, gx, gy, gz);
}

// Axis permutation used to sweep along the axis nearest the view (paper §5, "rotate the
// rendering volume"): world axis of local axis a is axis[a], with sign[a] = +1 or -1.
struct SweepFrame {
  int axis[3] = {0, 1, 2};
  int sign[3] = {1, 1, 1};
  bool flipsWinding() const;
};

// The sweep frame for params' order and view (identity for SurfaceOrder::none).
inline SweepFrame chooseFrame(const SurfaceParams& p) {
  SweepFrame f;
  if (p.order == SurfaceOrder::none) return f;
  const float d[3] = {p.viewDir.x, p.viewDir.y, p.viewDir.z};
  int a = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(d[i]) > std::fabs(d[a])) a = i;
  // §5: "rotate the rendering volume" so the sweep runs along the axis nearest the view.
  // Back-to-front sweeps towards the eye (against the view direction), front-to-back away.
  const int sweepSign = (d[a] > 0 ? -1 : 1) * (p.order == SurfaceOrder::backToFront ? 1 : -1);
  const int others[3][2] = {{1, 2}, {2, 0}, {0, 1}};  // cyclic: with signs (1, s, s) a rotation
  f.axis[0] = others[a][0];
  f.axis[1] = others[a][1];
  f.axis[2] = a;
  f.sign[0] = 1;
  f.sign[1] = sweepSign;
  f.sign[2] = sweepSign;
  return f;
}

// Sort key of prepareParticles (caller-owned scratch, reused across calls).
struct ParticleSortKey {
  double z;
  std::uint32_t index;
  std::uint32_t key;  // radix key of z (prepareParticles)
};

// Prepares particles in sweep-frame coordinates, sorted by (z, index). Fills rcMax with the
// largest Rc_i. Input must be valid (validateSurface). `keys`: sort scratch (a local one when
// null). With SurfaceInput::stretch, a particle's rc2 is its ellipsoid's bounding sphere
// (Rc_i times g's largest semi-axis factor, so every lookup structure built on rc2 returns a
// superset of the particles whose ellipsoid holds the corner), k stays 1 / (2 Rc_i^2), rcMax is
// the largest bounding radius, and `stretch` (when given) receives each particle's StretchTerm in
// the sweep frame, by input index.
void prepareParticles(const SurfaceInput& input, const SurfaceParams& params, const SweepFrame& frame,
                      std::vector<Particle>& out, double& rcMax, std::vector<ParticleSortKey>* keys = nullptr,
                      std::vector<StretchTerm>* stretch = nullptr);

// The smallest eigenvalue of the symmetric matrix g (closed form, double; Smith 1961's
// trigonometric solution). The ellipsoid { d : |g d| <= R } lies in the sphere of R / that value.
double smallestEigenvalue(const glm::mat3& g);

// Lattice coordinate helpers: corner k sits at k * S.
inline std::int64_t floorDiv(double v, double s) { return static_cast<std::int64_t>(std::floor(v / s)); }
// floor/ceil/round without a libm call (values are far inside the int range here).
inline int ifloor(double v) {
  const int i = static_cast<int>(v);
  return i - (v < double(i));
}
inline int iceil(double v) {
  const int i = static_cast<int>(v);
  return i + (v > double(i));
}
inline int iround(double v) { return ifloor(v + 0.5); }

// Edge key shared by all methods (SurfaceMesh::edgeKeys).
inline std::uint64_t edgeKey(std::int64_t i, std::int64_t j, std::int64_t k, int axis) {
  const std::uint64_t m = (1u << 20) - 1;
  return ((std::uint64_t(i) & m) << 42) | ((std::uint64_t(j) & m) << 22) | ((std::uint64_t(k) & m) << 2) |
         std::uint64_t(axis);
}

}  // namespace fluid::detail
