#include "fluid/surface/detail/field.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

namespace fluid::detail {

bool SweepFrame::flipsWinding() const {
  // Parity of the permutation times the product of the signs.
  int inversions = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) inversions += axis[a] > axis[b];
  const int signs = sign[0] * sign[1] * sign[2];
  return ((inversions & 1) ? -1 : 1) * signs < 0;
}

double smallestEigenvalue(const glm::mat3& g) {
  // The symmetric part, in double (glm is column-major; g is symmetric up to rounding).
  auto at = [&](int r, int c) { return 0.5 * (double(g[c][r]) + double(g[r][c])); };
  const double a = at(0, 0), b = at(1, 1), c = at(2, 2), d = at(0, 1), e = at(1, 2), f = at(0, 2);
  const double off = d * d + e * e + f * f;
  if (off == 0.0) return std::min({a, b, c});
  const double q = (a + b + c) / 3.0;
  const double p = std::sqrt(((a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2.0 * off) / 6.0);
  if (p == 0.0) return q;
  // r = det((A - q I) / p) / 2, in [-1, 1] up to rounding; the eigenvalues are
  // q + 2 p cos(acos(r) / 3 + 2 pi k / 3), the smallest at k = 1.
  const double ba = (a - q) / p, bb = (b - q) / p, bc = (c - q) / p, bd = d / p, be = e / p, bf = f / p;
  const double det = ba * (bb * bc - be * be) - bd * (bd * bc - be * bf) + bf * (bd * be - bb * bf);
  const double r = std::clamp(det / 2.0, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  return q + 2.0 * p * std::cos(phi + 2.0 * 3.14159265358979323846 / 3.0);
}

void prepareParticles(const SurfaceInput& input, const SurfaceParams& params, const SweepFrame& frame,
                      std::vector<Particle>& out, double& rcMax, std::vector<ParticleSortKey>* keys,
                      std::vector<StretchTerm>* stretch) {
  // Positions are read in place through the caller's pointer + stride view (meshoptimizer's
  // convention): each coordinate is the same float whatever the layout, so the records and their
  // (z, index) order, and therefore the sums, do not depend on it.
  const PointView world = input.positions;
  const std::size_t n = world.count;
  // Sort by (z, index): the summation order every method uses (see the header). The keys are
  // unique, so sorting 16-byte (z, index) keys and building the records in that order gives the
  // same order as sorting the 80-byte records, with far less data moved.
  //
  // A least-significant-digit radix sort (8-bit digits) of the z values' float bits mapped to
  // unsigned integers in the order of the values (sign bit set: all bits flipped, else the sign
  // bit set; -0 counts as +0, which compares equal to it). z is a float input value times +-1,
  // so its float is exact and orders the keys as the doubles do. The passes start from index
  // order and are stable, so equal z keep index order: the same order as sorting by (z, index).
  // A digit on which all keys agree needs no pass. The caller's scratch holds both buffers (2n).
  // Fewer than 256 keys are sorted by comparison instead (the same order).
  std::vector<ParticleSortKey> local;
  std::vector<ParticleSortKey>& scratch = keys ? *keys : local;
  scratch.resize(2 * n);
  ParticleSortKey* order = scratch.data();
  ParticleSortKey* other = scratch.data() + n;
  std::uint32_t hist[4][256] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const float zf = float(frame.sign[2]) * world.at(i, frame.axis[2]);
    const float zc = zf == 0.0f ? 0.0f : zf;  // -0 -> +0
    std::uint32_t bits;
    std::memcpy(&bits, &zc, sizeof bits);
    const std::uint32_t k = (bits >> 31) ? ~bits : (bits | 0x80000000u);
    order[i] = {double(zf), static_cast<std::uint32_t>(i), k};
    for (int d = 0; d < 4; ++d) ++hist[d][(k >> (8 * d)) & 0xff];
  }
  if (n < 256) {  // few keys: a comparison sort is cheaper than the radix passes' fixed cost
    std::sort(order, order + n, [](const ParticleSortKey& a, const ParticleSortKey& b) {
      return a.z < b.z || (a.z == b.z && a.index < b.index);
    });
  }
  for (int d = 0; d < 4 && n >= 256; ++d) {
    std::uint32_t* h = hist[d];
    if (h[(order[0].key >> (8 * d)) & 0xff] == n) continue;  // one bucket: nothing to reorder
    std::uint32_t sum = 0;
    for (int b = 0; b < 256; ++b) {
      const std::uint32_t c = h[b];
      h[b] = sum;
      sum += c;
    }
    for (std::size_t i = 0; i < n; ++i) other[h[(order[i].key >> (8 * d)) & 0xff]++] = order[i];
    std::swap(order, other);
  }
  out.resize(n);
  const double rc = params.rc;
  rcMax = 0.0;
  // Without per-particle radii or stretch every particle has Rc_i = Rc: k and Rc_i^2 once.
  const bool oneRadius = input.radiusScale.empty() && input.stretch.empty();
  const float kOne = float(1.0 / (2.0 * rc * rc));
  for (std::size_t r = 0; r < n; ++r) {
    const std::size_t i = order[r].index;
    Particle& p = out[r];
    p.x = frame.sign[0] * double(world.at(i, frame.axis[0]));
    p.y = frame.sign[1] * double(world.at(i, frame.axis[1]));
    p.z = order[r].z;
    double bound = rc;
    if (oneRadius) {
      p.k = kOne;
    } else {
      const double scale = input.radiusScale.empty() ? 1.0 : double(input.radiusScale[i]);
      const double rci = rc * scale;
      p.k = float(1.0 / (2.0 * rci * rci));
      // An ellipsoid |g d| < Rc_i lies within Rc_i / lambda_min(g); the factor 1 + 2^-10 covers the
      // float rounding of u (stretchedU) near the ellipsoid's edge, so the bound stays a superset.
      bound = input.stretch.empty() ? rci : rci / smallestEigenvalue(input.stretch[i]) * (1.0 + 1.0 / 1024.0);
    }
    p.rc2 = bound * bound;
    p.strength = input.strength.empty() ? 1.0f : input.strength[i];
    p.index = static_cast<std::uint32_t>(i);
    const double pc[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      // floor without a libm call (|pc / S| <= 4e5 after validateSurface: far inside int64).
      const double q = pc[a] / double(params.cube);
      const std::int64_t t = static_cast<std::int64_t>(q);
      p.anchor[a] = t - (q < double(t));
      p.rest[a] = float(pc[a] - double(p.anchor[a]) * double(params.cube));
    }
    rcMax = std::max(rcMax, bound);
  }
  if (stretch == nullptr || input.stretch.empty()) return;
  // M = g^T g / (2 Rc_i^2) in the sweep frame: local axis a is world axis frame.axis[a] times
  // frame.sign[a], so M_local(a, b) = sign[a] sign[b] M_world(axis[a], axis[b]).
  stretch->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::mat3& g = input.stretch[i];
    const double scale = input.radiusScale.empty() ? 1.0 : double(input.radiusScale[i]);
    const double k = 1.0 / (2.0 * rc * scale * rc * scale);
    double mw[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        // (g^T g)(r, c) = sum_j g(j, r) g(j, c) (glm indexes [column][row]). Each product is exact
        // in double; they are added in order of magnitude, so a set rotated into another sweep
        // frame (a signed permutation of g's entries) gets the same bits (the oracle's check).
        double t3[3];
        for (int j = 0; j < 3; ++j) t3[j] = double(g[r][j]) * double(g[c][j]);
        std::sort(t3, t3 + 3, [](double a, double b) { return std::fabs(a) < std::fabs(b); });
        mw[r][c] = ((t3[0] + t3[1]) + t3[2]) * k;
      }
    auto sweepLocal = [&](int a, int b) {
      return float(double(frame.sign[a] * frame.sign[b]) * mw[frame.axis[a]][frame.axis[b]]);
    };
    StretchTerm& t = (*stretch)[i];
    t = {{sweepLocal(0, 0), sweepLocal(0, 1), sweepLocal(0, 2), sweepLocal(1, 1), sweepLocal(1, 2), sweepLocal(2, 2)}, {0.0f, 0.0f}};
  }
}

}  // namespace fluid::detail
