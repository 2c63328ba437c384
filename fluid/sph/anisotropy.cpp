#include "fluid/sph/anisotropy.hpp"

#include "fluid/core/finite.hpp"
#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fluid {
namespace {

// Cyclic Jacobi sweeps: each sweep zeroes the three off-diagonal entries once; convergence is
// quadratic, so six sweeps take any 3x3 symmetric matrix to double rounding (a fixed count keeps
// the cost and the bits independent of the data).
constexpr int kJacobiSweeps = 6;
constexpr std::size_t kGrain = 256;
constexpr float kHalfCell = 0.501f;  // just over r / 2, so that neighborReach is 2, not 3

}  // namespace

AnisotropyParams clampAnisotropyParams(const AnisotropyParams& p) {
  AnisotropyParams c = p;
  c.radius = std::isfinite(p.radius) ? std::max(p.radius, 1e-6f) : 1e-6f;
  c.k_r = std::isfinite(p.k_r) ? std::clamp(p.k_r, 1.0f, 1000.0f) : 4.0f;
  c.k_s = std::isfinite(p.k_s) ? std::clamp(p.k_s, 0.01f, 100.0f) : 1.0f;
  c.k_n = std::max(p.k_n, 0);
  c.lambda = std::isfinite(p.lambda) ? std::clamp(p.lambda, 0.0f, 1.0f) : 0.0f;
  return c;
}

void symmetricEigen3(const glm::mat3& in, glm::vec3& values, glm::mat3& vectors) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  bool finite = true;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      a[r][c] = 0.5 * (static_cast<double>(in[c][r]) + static_cast<double>(in[r][c]));  // symmetric part
      finite = finite && std::isfinite(a[r][c]);
    }
  if (!finite) {
    values = glm::vec3(0.0f);
    vectors = glm::mat3(1.0f);
    return;
  }
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < kJacobiSweeps; ++sweep) {
    if (a[0][1] == 0.0 && a[0][2] == 0.0 && a[1][2] == 0.0) break;  // diagonal: the rest would do nothing
    for (const auto& pq : kPairs) {
      const int p = pq[0], q = pq[1];
      // An entry this small against its diagonal moves the eigenvalues by less than 1e-12 of their
      // size (second order in it), far below the float results' rounding: zero it.
      if (std::abs(a[p][q]) <= 1e-6 * (std::abs(a[p][p]) + std::abs(a[q][q]))) {
        a[p][q] = a[q][p] = 0.0;
        continue;
      }
      // The rotation that zeroes a_pq (Numerical Recipes §11.1, Eqs. 11.1.4-11.1.8): the smaller
      // root t of t^2 + 2 θ t - 1 = 0, stable for any θ.
      const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
      const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
      const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
      for (int k = 0; k < 3; ++k) {  // A P (columns p, q)
        const double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq;
        a[k][q] = s * akp + c * akq;
      }
      for (int k = 0; k < 3; ++k) {  // P^T (A P) (rows p, q)
        const double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk;
        a[q][k] = s * apk + c * aqk;
      }
      a[p][q] = a[q][p] = 0.0;
      for (int k = 0; k < 3; ++k) {  // V P
        const double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
      }
    }
  }
  int idx[3] = {0, 1, 2};
  std::sort(idx, idx + 3, [&](int x, int y) { return a[x][x] > a[y][y] || (a[x][x] == a[y][y] && x < y); });
  for (int k = 0; k < 3; ++k) {
    values[k] = static_cast<float>(a[idx[k]][idx[k]]);
    for (int r = 0; r < 3; ++r) vectors[k][r] = static_cast<float>(v[r][idx[k]]);
  }
  if (glm::determinant(vectors) < 0.0f) vectors[2] = -vectors[2];  // right-handed
}

glm::mat3 anisotropyMatrix(const glm::mat3& covariance, std::uint32_t neighbours, const AnisotropyParams& params,
                           float* max_axis) {
  if (max_axis != nullptr) *max_axis = 1.0f;
  // Eq. 15: too few neighbours for a meaningful covariance, a sphere (the paper's k_n I, here I).
  if (neighbours <= static_cast<std::uint32_t>(std::max(params.k_n, 0))) return glm::mat3(1.0f);
  glm::vec3 sigma;
  glm::mat3 axes;
  symmetricEigen3(covariance, sigma, axes);
  if (!(sigma[0] > 0.0f) || !std::isfinite(sigma[0])) return glm::mat3(1.0f);  // coincident neighbours
  const double k_r = std::max(static_cast<double>(params.k_r), 1.0);
  double s[3];
  for (int k = 0; k < 3; ++k) s[k] = std::max(static_cast<double>(sigma[k]), static_cast<double>(sigma[0]) / k_r);
  // Divided by the geometric mean: k_s = 1 keeps the sphere's volume (see the header's mapping).
  const double mean = std::cbrt(s[0] * s[1] * s[2]);
  if (!(mean > 0.0) || !std::isfinite(mean)) return glm::mat3(1.0f);
  const double k_s = std::max(static_cast<double>(params.k_s), 1e-6);
  glm::vec3 inverse_axis;
  for (int k = 0; k < 3; ++k) inverse_axis[k] = static_cast<float>(mean / (k_s * s[k]));
  if (max_axis != nullptr) *max_axis = static_cast<float>(k_s * s[0] / mean);
  // Eq. 16 without the 1/h: g = R Σ~^-1 R^T.
  glm::mat3 g(0.0f);
  for (int k = 0; k < 3; ++k) g += inverse_axis[k] * glm::outerProduct(axes[k], axes[k]);
  for (int c = 0; c < 3; ++c)  // exactly symmetric
    for (int r = c + 1; r < 3; ++r) g[c][r] = g[r][c] = 0.5f * (g[c][r] + g[r][c]);
  return g;
}

namespace {

// Weighted sums of one particle's neighbourhood, relative to x_i: sum w, sum w d, sum w d d^T
// (Eqs. 9-11), and the count of neighbours within r (i itself included: d = 0, w = 1).
struct Moments {
  float w = 0, fx = 0, fy = 0, fz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  std::uint32_t count = 0;
};

#if defined(__SSE2__)
// Four candidates at a time over the sorted SoA copies (SSE2, the x86-64 baseline): no branch per
// candidate, a weight of exactly 0 beyond r (w = max(0, 1 - q^3)) and for lanes past the run, so
// the sums are those of the accepted neighbours. The lanes are summed in a fixed order at the end:
// the same bits whichever thread runs the particle.
inline void accumulateRun(const float* sx, const float* sy, const float* sz, std::uint32_t b, std::uint32_t e,
                          __m128 px, __m128 py, __m128 pz, __m128 r2, __m128 inv_r2, __m128 acc[10],
                          std::uint32_t& count) {
  const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
  for (std::uint32_t t = b; t < e; t += 4) {
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(sx + t), px);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(sy + t), py);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(sz + t), pz);
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    __m128 inside = _mm_cmplt_ps(d2, r2);
    if (e - t < 4) {  // lanes past the run (the copies are padded)
      alignas(16) static constexpr std::uint32_t kLive[4][4] = {
          {0, 0, 0, 0}, {~0u, 0, 0, 0}, {~0u, ~0u, 0, 0}, {~0u, ~0u, ~0u, 0}};
      inside = _mm_and_ps(inside, _mm_load_ps(reinterpret_cast<const float*>(kLive[e - t])));
    }
    constexpr std::uint8_t kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};  // no POPCNT in the baseline
    count += kBits[_mm_movemask_ps(inside)];
    // Eq. 11: w = 1 - (|d| / r)^3 = 1 - q2 sqrt(q2), q2 = |d|^2 / r^2.
    const __m128 q2 = _mm_mul_ps(d2, inv_r2);
    const __m128 w = _mm_and_ps(inside, _mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(q2, _mm_sqrt_ps(q2))), zero));
    const __m128 wx = _mm_mul_ps(w, dx), wy = _mm_mul_ps(w, dy), wz = _mm_mul_ps(w, dz);
    acc[0] = _mm_add_ps(acc[0], w);
    acc[1] = _mm_add_ps(acc[1], wx);
    acc[2] = _mm_add_ps(acc[2], wy);
    acc[3] = _mm_add_ps(acc[3], wz);
    acc[4] = _mm_add_ps(acc[4], _mm_mul_ps(wx, dx));
    acc[5] = _mm_add_ps(acc[5], _mm_mul_ps(wx, dy));
    acc[6] = _mm_add_ps(acc[6], _mm_mul_ps(wx, dz));
    acc[7] = _mm_add_ps(acc[7], _mm_mul_ps(wy, dy));
    acc[8] = _mm_add_ps(acc[8], _mm_mul_ps(wy, dz));
    acc[9] = _mm_add_ps(acc[9], _mm_mul_ps(wz, dz));
  }
}

inline float laneSum(__m128 v) {
  alignas(16) float l[4];
  _mm_store_ps(l, v);
  return (l[0] + l[1]) + (l[2] + l[3]);
}
#endif

}  // namespace

void computeAnisotropy(const NeighborGrid& grid, std::span<const glm::vec3> positions, const AnisotropyParams& raw,
                       AnisotropyScratch& scratch, Anisotropy& out) {
  const AnisotropyParams params = clampAnisotropyParams(raw);
  const std::size_t n = positions.size();
  assert(grid.order.size() == n);
  out.centre.resize(n);
  out.g.resize(n);
  out.max_axis.resize(n);
  out.neighbours.resize(n);
  const float r = params.radius, r2 = r * r, inv_r2 = 1.0f / r2;
  const int reach = neighborReach(grid, r);
  const std::uint32_t* order = grid.order.data();
  const bool identity = grid.identity_order;
  // The positions in sorted order (SoA, padded for one 4-wide load past a run's end): each row
  // run of the grid is then one contiguous stretch of each array.
  copySortedPositions(grid, positions, 4, scratch.sx, scratch.sy, scratch.sz);
  const float* sx = scratch.sx.data();
  const float* sy = scratch.sy.data();
  const float* sz = scratch.sz.data();
  // Sorted entries in order: particles of one cell run together and share their rows in cache.
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& range) {
    for (std::size_t e = range.begin(); e != range.end(); ++e) {
      const std::uint32_t i = identity ? static_cast<std::uint32_t>(e) : order[e];
      const glm::vec3 xi(sx[e], sy[e], sz[e]);
      Moments m;
#if defined(__SSE2__)
      __m128 acc[10];
      for (__m128& a : acc) a = _mm_setzero_ps();
      const __m128 px = _mm_set1_ps(xi.x), py = _mm_set1_ps(xi.y), pz = _mm_set1_ps(xi.z);
      const __m128 vr2 = _mm_set1_ps(r2), vinv = _mm_set1_ps(inv_r2);
#endif
      forEachNeighborRun(grid, grid.cellOf(xi), reach, [&](std::uint32_t b, std::uint32_t end) {
#if defined(__SSE2__)
        accumulateRun(sx, sy, sz, b, end, px, py, pz, vr2, vinv, acc, m.count);
#else
        for (std::uint32_t u = b; u < end; ++u) {
          const glm::vec3 d = glm::vec3(sx[u], sy[u], sz[u]) - xi;
          const float d2 = glm::dot(d, d);
          if (!(d2 < r2)) continue;
          const float q2 = d2 * inv_r2;
          const float w = std::max(1.0f - q2 * std::sqrt(q2), 0.0f);  // Eq. 11
          m.w += w;
          m.fx += w * d.x;
          m.fy += w * d.y;
          m.fz += w * d.z;
          m.xx += w * d.x * d.x;
          m.xy += w * d.x * d.y;
          m.xz += w * d.x * d.z;
          m.yy += w * d.y * d.y;
          m.yz += w * d.y * d.z;
          m.zz += w * d.z * d.z;
          ++m.count;
        }
#endif
      });
#if defined(__SSE2__)
      m.w = laneSum(acc[0]);
      m.fx = laneSum(acc[1]);
      m.fy = laneSum(acc[2]);
      m.fz = laneSum(acc[3]);
      m.xx = laneSum(acc[4]);
      m.xy = laneSum(acc[5]);
      m.xz = laneSum(acc[6]);
      m.yy = laneSum(acc[7]);
      m.yz = laneSum(acc[8]);
      m.zz = laneSum(acc[9]);
#endif
      // i itself is among the candidates (d = 0, w = 1); a non-finite x_i matched nothing.
      const std::uint32_t count = m.count > 0 ? m.count - 1 : 0;
      const float weight = m.w > 0.0f ? m.w : 1.0f;
      // Eq. 10 (mean) and Eq. 9 (covariance about the mean): E[w d d^T] - m m^T. The sums are
      // relative to x_i and bounded by r^2, so the cancellation costs a few ulps of r^2 only.
      const float inv_w = 1.0f / weight;
      const glm::vec3 mean = glm::vec3(m.fx, m.fy, m.fz) * inv_w;
      glm::mat3 c;
      c[0][0] = m.xx * inv_w - mean.x * mean.x;
      c[1][1] = m.yy * inv_w - mean.y * mean.y;
      c[2][2] = m.zz * inv_w - mean.z * mean.z;
      c[1][0] = c[0][1] = m.xy * inv_w - mean.x * mean.y;
      c[2][0] = c[0][2] = m.xz * inv_w - mean.x * mean.z;
      c[2][1] = c[1][2] = m.yz * inv_w - mean.y * mean.z;
      // Eq. 6: x̄ = (1 - λ) x_i + λ x^w_i = x_i + λ (x^w_i - x_i).
      out.centre[i] = xi + params.lambda * mean;
      out.g[i] = anisotropyMatrix(c, count, params, &out.max_axis[i]);
      out.neighbours[i] = count;
    }
  });
  const std::uint32_t k_n = static_cast<std::uint32_t>(params.k_n);
  std::size_t stretched = 0;
  for (std::uint32_t c : out.neighbours) stretched += c > k_n ? 1 : 0;
  out.stretched = stretched;
}

bool computeAnisotropy(std::span<const glm::vec3> positions, const AnisotropyParams& params, AnisotropyScratch& scratch,
                       Anisotropy& out) {
  const AnisotropyParams p = clampAnisotropyParams(params);
  const bool finite = par::parallelReduce(
      par::Range<std::size_t>(0, positions.size(), 4096), true,
      [&](const par::Range<std::size_t>& r, bool ok) {
        for (std::size_t i = r.begin(); ok && i != r.end(); ++i) ok = isFinite(positions[i]);
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  if (!finite) {
    const std::size_t n = positions.size();
    out.centre.assign(positions.begin(), positions.end());
    out.g.assign(n, glm::mat3(1.0f));
    out.max_axis.assign(n, 1.0f);
    out.neighbours.assign(n, 0u);
    out.stretched = 0;
    return false;
  }
  // Cells of about r / 2 (reach 2: 5 x 5 rows of 5 cells, 15.7 r^3 of candidates) rather than r
  // (reach 1: 27 r^3): the sphere of radius r is 4.2 r^3, so fewer distance tests per neighbour.
  buildNeighborGrid(scratch.grid, positions, kHalfCell * p.radius);
  computeAnisotropy(scratch.grid, positions, p, scratch, out);
  return true;
}

}  // namespace fluid
