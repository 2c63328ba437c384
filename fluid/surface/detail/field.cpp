#include "fluid/surface/detail/field.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace fluid::detail {

bool SweepFrame::flipsWinding() const {
  // Parity of the permutation times the product of the signs.
  int inversions = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) inversions += axis[a] > axis[b];
  const int signs = sign[0] * sign[1] * sign[2];
  return ((inversions & 1) ? -1 : 1) * signs < 0;
}

void prepareParticles(const SurfaceInput& input, const SurfaceParams& params, const SweepFrame& frame,
                      std::vector<Particle>& out, double& rcMax, std::vector<ParticleSortKey>* keys) {
  const std::size_t n = input.x.size();
  const std::span<const float> world[3] = {input.x, input.y, input.z};
  // Sort by (z, index): the summation order every method uses (see the header). The keys are
  // unique, so sorting 16-byte (z, index) keys and building the records in that order gives the
  // same order as sorting the 80-byte records, with far less data moved.
  std::vector<ParticleSortKey> local;
  std::vector<ParticleSortKey>& order = keys ? *keys : local;
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    order[i] = {frame.sign[2] * double(world[frame.axis[2]][i]), static_cast<std::uint32_t>(i)};
  std::sort(order.begin(), order.end(), [](const ParticleSortKey& a, const ParticleSortKey& b) {
    return a.z < b.z || (a.z == b.z && a.index < b.index);
  });
  out.resize(n);
  const double rc = params.rc;
  rcMax = 0.0;
  for (std::size_t r = 0; r < n; ++r) {
    const std::size_t i = order[r].index;
    Particle& p = out[r];
    p.x = frame.sign[0] * double(world[frame.axis[0]][i]);
    p.y = frame.sign[1] * double(world[frame.axis[1]][i]);
    p.z = order[r].z;
    const double scale = input.radiusScale.empty() ? 1.0 : double(input.radiusScale[i]);
    const double rci = rc * scale;
    p.rc2 = rci * rci;
    p.k = float(1.0 / (2.0 * p.rc2));
    p.strength = input.strength.empty() ? 1.0f : input.strength[i];
    p.index = static_cast<std::uint32_t>(i);
    const double pc[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      p.anchor[a] = static_cast<std::int64_t>(std::floor(pc[a] / double(params.cube)));
      p.rest[a] = float(pc[a] - double(p.anchor[a]) * double(params.cube));
    }
    rcMax = std::max(rcMax, rci);
  }
}

}  // namespace fluid::detail
