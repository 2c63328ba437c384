#pragma once
// Internal: the paper's field f(r) (§2) and the particle preparation shared by marching slices,
// the baselines and the dense oracle. Every extractor sums contributions in the same order
// (particles sorted by (z, input index)) with the same double expressions, so the corner values
// — and therefore the triangles — agree bit for bit between methods and block sizes.

#include "fluid/surface/marching_slices.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

namespace fluid::detail {

// One particle, prepared. Positions are doubles of the float input.
struct Particle {
  double x, y, z;
  double rc2;       // Rc_i^2: influence iff (dx*dx + dy*dy) + dz*dz < rc2
  double k;         // 1 / (2 Rc_i^2), so u = r^2 k = (r / (sqrt2 Rc_i))^2
  double strength;  // s_i
  std::uint32_t index;  // input index (user data)
};

// The exact-influence predicate. Every lookup structure must return exactly the particles for
// which this is true at the corner (no more, no fewer).
inline bool influences(const Particle& p, double cx, double cy, double cz) {
  const double dx = cx - p.x, dy = cy - p.y, dz = cz - p.z;
  return (dx * dx + dy * dy) + dz * dz < p.rc2;
}

// Adds particle p's contribution at corner c to value and gradient. f = s (u - 1/2)^2 with
// u = r^2 k; df/dc = s * 2 (u - 1/2) * k * 2 (c - p). Caller guarantees influences() is true.
inline void accumulate(const Particle& p, double cx, double cy, double cz, double& value, double& gx,
                       double& gy, double& gz) {
  const double dx = cx - p.x, dy = cy - p.y, dz = cz - p.z;
  const double u = ((dx * dx + dy * dy) + dz * dz) * p.k;
  const double w = u - 0.5;
  value += p.strength * (w * w);
  const double g = p.strength * 4.0 * w * p.k;
  gx += g * dx;
  gy += g * dy;
  gz += g * dz;
}

// Contribution only (margin corners need the sign, not the normal; same bits as above).
inline double contribution(const Particle& p, double cx, double cy, double cz) {
  const double dx = cx - p.x, dy = cy - p.y, dz = cz - p.z;
  const double u = ((dx * dx + dy * dy) + dz * dz) * p.k;
  const double w = u - 0.5;
  return p.strength * (w * w);
}

// Axis permutation used to sweep along the axis nearest the view (paper §5, "rotate the
// rendering volume"): world axis of local axis a is axis[a], with sign[a] = +1 or -1.
struct SweepFrame {
  int axis[3] = {0, 1, 2};
  int sign[3] = {1, 1, 1};
  bool flipsWinding() const;
};

// Prepares particles in sweep-frame coordinates, sorted by (z, index). Fills rcMax with the
// largest Rc_i. Input must be valid (validateSurface).
void prepareParticles(const SurfaceInput& input, const SurfaceParams& params, const SweepFrame& frame,
                      std::vector<Particle>& out, double& rcMax);

// Lattice coordinate helpers: corner k sits at k * S.
inline std::int64_t floorDiv(double v, double s) { return static_cast<std::int64_t>(std::floor(v / s)); }

// Edge key shared by all methods (SurfaceMesh::edgeKeys).
inline std::uint64_t edgeKey(std::int64_t i, std::int64_t j, std::int64_t k, int axis) {
  const std::uint64_t m = (1u << 20) - 1;
  return ((std::uint64_t(i) & m) << 42) | ((std::uint64_t(j) & m) << 22) | ((std::uint64_t(k) & m) << 2) |
         std::uint64_t(axis);
}

}  // namespace fluid::detail
