#include "fluid/sph/anisotropy.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace fluid {
namespace {

// Cyclic Jacobi sweeps: each sweep zeroes the three off-diagonal entries once; convergence is
// quadratic, so six sweeps take any 3x3 symmetric matrix to double rounding (a fixed count keeps
// the cost and the bits independent of the data).
constexpr int kJacobiSweeps = 6;
constexpr std::size_t kGrain = 256;

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
    for (const auto& pq : kPairs) {
      const int p = pq[0], q = pq[1];
      if (a[p][q] == 0.0) continue;
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

void computeAnisotropy(const NeighborGrid& grid, std::span<const glm::vec3> positions,
                       const AnisotropyParams& raw, Anisotropy& out) {
  const AnisotropyParams params = clampAnisotropyParams(raw);
  const std::size_t n = positions.size();
  assert(grid.order.size() == n);
  out.centre.resize(n);
  out.g.resize(n);
  out.max_axis.resize(n);
  out.neighbours.resize(n);
  const float r = params.radius, r2 = r * r, inv_r = 1.0f / r;
  const int reach = neighborReach(grid, r);
  const std::uint32_t* order = grid.order.data();
  const bool identity = grid.identity_order;
  // Sorted entries in order: particles of one cell run together and share their rows in cache.
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& range) {
    for (std::size_t e = range.begin(); e != range.end(); ++e) {
      const std::uint32_t i = identity ? static_cast<std::uint32_t>(e) : order[e];
      const glm::vec3 xi = positions[i];
      const glm::ivec3 cell = grid.cellOf(xi);
      // Sums relative to x_i (exact translation invariance, small numbers): i itself adds w = 1 at 0.
      float weight = 1.0f;
      glm::vec3 first(0.0f);
      float xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
      std::uint32_t count = 0;
      const int x0 = std::max(cell.x - reach, 0), x1 = std::min(cell.x + reach, grid.dims.x - 1);
      for (int z = std::max(cell.z - reach, 0); z <= std::min(cell.z + reach, grid.dims.z - 1); ++z)
        for (int y = std::max(cell.y - reach, 0); y <= std::min(cell.y + reach, grid.dims.y - 1); ++y) {
          const std::uint32_t b = grid.cell_start[grid.keyOf({x0, y, z})],
                              end = grid.cell_start[grid.keyOf({x1, y, z}) + 1];
          for (std::uint32_t u = b; u < end; ++u) {
            const std::uint32_t j = identity ? u : order[u];
            if (j == i) continue;
            const glm::vec3 d = positions[j] - xi;
            const float d2 = glm::dot(d, d);
            if (!(d2 < r2)) continue;
            // Eq. 11: w = 1 - (|d| / r)^3, smooth at r and flat near i.
            const float q = std::sqrt(d2) * inv_r;
            const float w = 1.0f - q * q * q;
            weight += w;
            first += w * d;
            xx += w * d.x * d.x;
            xy += w * d.x * d.y;
            xz += w * d.x * d.z;
            yy += w * d.y * d.y;
            yz += w * d.y * d.z;
            zz += w * d.z * d.z;
            ++count;
          }
        }
      // Eq. 10 (mean) and Eq. 9 (covariance about the mean): E[w d d^T] - m m^T. The sums are
      // relative to x_i and bounded by r^2, so the cancellation costs a few ulps of r^2 only.
      const float inv_w = 1.0f / weight;
      const glm::vec3 m = first * inv_w;
      glm::mat3 c;
      c[0][0] = xx * inv_w - m.x * m.x;
      c[1][1] = yy * inv_w - m.y * m.y;
      c[2][2] = zz * inv_w - m.z * m.z;
      c[1][0] = c[0][1] = xy * inv_w - m.x * m.y;
      c[2][0] = c[0][2] = xz * inv_w - m.x * m.z;
      c[2][1] = c[1][2] = yz * inv_w - m.y * m.z;
      // Eq. 6: x̄ = (1 - λ) x_i + λ x^w_i = x_i + λ (x^w_i - x_i).
      out.centre[i] = xi + params.lambda * m;
      out.g[i] = anisotropyMatrix(c, count, params, &out.max_axis[i]);
      out.neighbours[i] = count;
    }
  });
  const std::uint32_t k_n = static_cast<std::uint32_t>(params.k_n);
  std::size_t stretched = 0;
  for (std::uint32_t c : out.neighbours) stretched += c > k_n ? 1 : 0;
  out.stretched = stretched;
}

void computeAnisotropy(std::span<const glm::vec3> positions, const AnisotropyParams& params,
                       AnisotropyScratch& scratch, Anisotropy& out) {
  const AnisotropyParams p = clampAnisotropyParams(params);
  buildNeighborGrid(scratch.grid, positions, p.radius);
  computeAnisotropy(scratch.grid, positions, p, out);
}

}  // namespace fluid
