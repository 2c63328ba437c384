#include "fluid/sph/diffuse.hpp"

#include "fluid/core/finite.hpp"
#include "fluid/core/parallel.hpp"
#include "fluid/core/splitmix.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace fluid {
namespace {

constexpr std::size_t kGrain = 256;
constexpr float kHalfCell = 0.501f;  // cells just over h / 2: reach 2 (fewer candidates than reach 1 on h cells)

// Eq. 4's radially symmetric weight.
inline float weight(float distance, float h) { return distance < h ? 1.0f - distance / h : 0.0f; }

float unit(std::uint64_t& state) {
  state = splitmix64(state);
  return unitFloat(state);
}

// Calls f(j) for every sorted entry j within h of x (i itself included), in the grid's fixed order.
template <typename F>
void forNeighbours(const NeighborGrid& grid, int reach, const float* sx, const float* sy, const float* sz, glm::vec3 x,
                   float h2, F&& f) {
  forEachNeighborRun(grid, grid.cellOf(x), reach, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t u = b; u < e; ++u) {
      const glm::vec3 d(x.x - sx[u], x.y - sy[u], x.z - sz[u]);
      const float d2 = glm::dot(d, d);
      if (d2 < h2) f(u, d, d2);
    }
  });
}

}  // namespace

DiffuseParams clampDiffuseParams(const DiffuseParams& p) {
  DiffuseParams c = p;
  auto finite = [](float v, float fallback) { return std::isfinite(v) ? v : fallback; };
  c.radius = std::max(finite(p.radius, 1e-6f), 1e-6f);
  c.ta_min = std::max(finite(p.ta_min, 0.0f), 0.0f);
  c.ta_max = std::max(finite(p.ta_max, c.ta_min), c.ta_min);
  c.wc_min = std::max(finite(p.wc_min, 0.0f), 0.0f);
  c.wc_max = std::max(finite(p.wc_max, c.wc_min), c.wc_min);
  c.k_min = std::max(finite(p.k_min, 0.0f), 0.0f);
  c.k_max = std::max(finite(p.k_max, c.k_min), c.k_min);
  c.k_ta = std::clamp(finite(p.k_ta, 0.0f), 0.0f, 1e6f);
  c.k_wc = std::clamp(finite(p.k_wc, 0.0f), 0.0f, 1e6f);
  c.surface_threshold = std::clamp(finite(p.surface_threshold, 0.15f), 0.0f, 1.0f);
  c.spray_below = std::max(p.spray_below, 0);
  c.bubble_above = std::max(p.bubble_above, c.spray_below);
  return c;
}

float clampPotential(float value, float tmin, float tmax) {
  if (!std::isfinite(value)) return 0.0f;
  if (!(tmax > tmin)) return value >= tmax ? 1.0f : 0.0f;
  return (std::min(value, tmax) - std::min(value, tmin)) / (tmax - tmin);
}

DiffuseClass classifyDiffuse(float neighbours, int spray_below, int bubble_above) {
  if (!(neighbours >= static_cast<float>(spray_below))) return DiffuseClass::spray;  // NaN: spray
  if (neighbours > static_cast<float>(bubble_above)) return DiffuseClass::bubble;
  return DiffuseClass::foam;
}

float trappedAirTerm(glm::vec3 xi, glm::vec3 vi, glm::vec3 xj, glm::vec3 vj, float h) {
  const glm::vec3 x = xi - xj, v = vi - vj;
  const float dx = glm::length(x), dv = glm::length(v);
  if (!(dx > 0.0f) || !(dv > 0.0f)) return 0.0f;
  return dv * (1.0f - glm::dot(v / dv, x / dx)) * weight(dx, h);
}

bool computeDiffusePotentials(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                              const DiffuseParams& raw, DiffuseScratch& scratch, DiffusePotentials& out) {
  const DiffuseParams p = clampDiffuseParams(raw);
  const std::size_t n = positions.size();
  out.normal.assign(n, glm::vec3(0.0f));
  out.neighbours.assign(n, 0u);
  out.trapped_air.assign(n, 0.0f);
  out.wave_crest.assign(n, 0.0f);
  out.kinetic.assign(n, 0.0f);
  if (velocities.size() != n) return false;
  const bool finite = par::parallelReduce(
      par::Range<std::size_t>(0, n, 4096), true,
      [&](const par::Range<std::size_t>& r, bool ok) {
        for (std::size_t i = r.begin(); ok && i != r.end(); ++i) ok = isFinite(positions[i]) && isFinite(velocities[i]);
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  if (!finite) return false;
  if (n == 0) return true;
  const float h = p.radius, h2 = h * h;
  NeighborGrid& grid = scratch.grid;
  buildNeighborGrid(grid, positions, kHalfCell * h);
  const int reach = neighborReach(grid, h);
  const std::uint32_t* order = grid.order.data();
  const bool identity = grid.identity_order;
  copySortedPositions(grid, positions, 0, scratch.sx, scratch.sy, scratch.sz);
  const float* sx = scratch.sx.data();
  const float* sy = scratch.sy.data();
  const float* sz = scratch.sz.data();
  auto original = [&](std::uint32_t e) { return identity ? e : order[e]; };
  // I_k first: eq. 2 multiplies everything by it, so only particles with I_k > 0 need the
  // potentials, and only they and their neighbours need a normal.
  par::parallelFor(par::Range<std::size_t>(0, n, 4096), [&](const par::Range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i)
      out.kinetic[i] = 0.5f * glm::dot(velocities[i], velocities[i]);
  });
  std::vector<std::uint8_t>& need = scratch.need;
  std::vector<std::uint32_t>& active = scratch.active;
  need.assign(n, 0);
  active.clear();
  for (std::uint32_t e = 0; e < n; ++e)
    if (clampPotential(out.kinetic[original(e)], p.k_min, p.k_max) > 0.0f) active.push_back(e);
  if (active.empty()) return true;
  // Serial (the active set is small): entries are marked in a fixed order, so the result is the same
  // for every thread count.
  for (std::uint32_t e : active) {
    need[e] = 1;
    forNeighbours(grid, reach, sx, sy, sz, glm::vec3(sx[e], sy[e], sz[e]), h2, [&](std::uint32_t u, glm::vec3, float) {
      if (need[u] == 0) need[u] = 2;
    });
  }
  // Pass 1: neighbour counts and normals (the weighted count gradient) where needed.
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& range) {
    for (std::size_t e = range.begin(); e != range.end(); ++e) {
      if (need[e] == 0) continue;
      const std::uint32_t i = original(static_cast<std::uint32_t>(e));
      const glm::vec3 xi(sx[e], sy[e], sz[e]);
      glm::vec3 gradient(0.0f);
      float total = 0.0f;
      std::uint32_t count = 0;
      forNeighbours(grid, reach, sx, sy, sz, xi, h2, [&](std::uint32_t u, glm::vec3 d, float d2) {
        if (u == e) return;
        ++count;
        const float r = std::sqrt(d2);
        const float w = weight(r, h);
        total += w;
        if (r > 0.0f) gradient += (w / r) * d;  // W x^_ij: points away from the neighbours
      });
      out.neighbours[i] = count;
      const float length = glm::length(gradient);
      // A surrounded particle's gradient is noise: no normal (see the header).
      if (total > 0.0f && length > p.surface_threshold * total) out.normal[i] = gradient / length;
    }
  });
  // Pass 2: trapped air (eq. 4) and wave crests (eqs. 5-6) of the active particles.
  par::parallelFor(par::Range<std::size_t>(0, active.size(), 64), [&](const par::Range<std::size_t>& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const std::uint32_t e = active[k];
      const std::uint32_t i = original(e);
      const glm::vec3 xi(sx[e], sy[e], sz[e]);
      const glm::vec3 vi = velocities[i], ni = out.normal[i];
      const bool has_normal = glm::dot(ni, ni) > 0.0f;
      const float speed = glm::length(vi);
      // δ^vn: the crest must move along its normal.
      const bool outward = has_normal && speed > 0.0f && glm::dot(vi / speed, ni) >= 0.6f;
      float ta = 0.0f, kappa = 0.0f;
      forNeighbours(grid, reach, sx, sy, sz, xi, h2, [&](std::uint32_t u, glm::vec3 d, float d2) {
        if (u == e) return;
        const std::uint32_t j = original(u);
        const float r = std::sqrt(d2);
        if (!(r > 0.0f)) return;
        const float w = weight(r, h);
        const glm::vec3 vij = vi - velocities[j];
        const float dv = glm::length(vij);
        if (dv > 0.0f) ta += dv * (1.0f - glm::dot(vij / dv, d / r)) * w;
        if (outward) {
          const glm::vec3 nj = out.normal[j];
          // x^_ji . n^_i < 0: j lies behind i's surface (convex); d = x_ij = -x_ji.
          if (glm::dot(nj, nj) > 0.0f && glm::dot(d, ni) > 0.0f) kappa += (1.0f - glm::dot(ni, nj)) * w;
        }
      });
      out.trapped_air[i] = ta;
      out.wave_crest[i] = kappa;
    }
  });
  return true;
}

std::size_t generateDiffuse(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                            const DiffusePotentials& pot, const DiffuseParams& raw, float dt, std::uint64_t seed,
                            std::size_t max_births, std::vector<DiffuseBirth>& out) {
  const DiffuseParams p = clampDiffuseParams(raw);
  const std::size_t n = std::min({positions.size(), velocities.size(), pot.kinetic.size(), pot.trapped_air.size(),
                                  pot.wave_crest.size(), pot.neighbours.size()});
  if (!(dt > 0.0f) || !std::isfinite(dt)) return 0;
  const float two_pi = 2.0f * std::numbers::pi_v<float>;
  // §4.1: the cylinder's radius, the particle's radius (half the spacing: h / 4 for h = 2 d).
  const float r_v = 0.25f * p.radius;
  std::size_t added = 0;
  for (std::size_t i = 0; i < n && added < max_births; ++i) {
    const float ik = clampPotential(pot.kinetic[i], p.k_min, p.k_max);
    if (ik <= 0.0f) continue;
    // Eq. 2.
    const float nd = ik *
                     (p.k_ta * clampPotential(pot.trapped_air[i], p.ta_min, p.ta_max) +
                      p.k_wc * clampPotential(pot.wave_crest[i], p.wc_min, p.wc_max)) *
                     dt;
    if (!(nd > 0.0f)) continue;
    std::uint64_t state = splitmix64(seed ^ splitmix64(static_cast<std::uint64_t>(i) + 1));
    const auto count = static_cast<std::size_t>(nd + unit(state));  // unbiased rounding
    if (count == 0) continue;
    const glm::vec3 x = positions[i], v = velocities[i];
    const float speed = glm::length(v);
    if (!(speed > 0.0f)) continue;
    const glm::vec3 axis = v / speed;
    const glm::vec3 helper = std::fabs(axis.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 e1 = glm::normalize(glm::cross(helper, axis)), e2 = glm::cross(axis, e1);
    const DiffuseClass type = classifyDiffuse(static_cast<float>(pot.neighbours[i]), p.spray_below, p.bubble_above);
    for (std::size_t k = 0; k < count && added < max_births; ++k) {
      // Eq. 3: uniform in the cylinder of radius r_v along v dt.
      const float r = r_v * std::sqrt(unit(state)), theta = two_pi * unit(state), along = unit(state);
      const glm::vec3 radial = std::cos(theta) * e1 + std::sin(theta) * e2;
      DiffuseBirth b;
      b.position = x + r * radial + along * dt * v;
      // The paper adds the radial offset to the velocity; scaled to 10 % of the speed so a sheet fans out a little.
      b.velocity = v + (0.1f * speed * r / std::max(r_v, 1e-6f)) * radial;
      b.type = type;
      out.push_back(b);
      ++added;
    }
  }
  return added;
}

bool buildFluidCellGrid(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities, float cell_size,
                        float radius, int max_cells, FluidCellGrid& out) {
  const std::size_t n = std::min(positions.size(), velocities.size());
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  std::size_t finite = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!isFinite(positions[i]) || !isFinite(velocities[i])) continue;
    lo = glm::min(lo, positions[i]);
    hi = glm::max(hi, positions[i]);
    ++finite;
  }
  out.cells.clear();
  out.size = glm::ivec3(0);
  if (finite == 0 || !(cell_size > 0.0f) || !std::isfinite(cell_size)) return false;
  max_cells = std::clamp(max_cells, 2, 512);
  float cell = cell_size;
  const glm::vec3 span = hi - lo;
  const float widest = std::max({span.x, span.y, span.z});
  // Padded by a cell each side: max_cells - 2 cells hold the particles.
  cell = std::max(cell, widest / static_cast<float>(max_cells - 2));
  out.cell = cell;
  out.origin = lo - glm::vec3(cell);
  out.size = glm::min(glm::ivec3(glm::floor(span / cell)) + 3, glm::ivec3(max_cells));
  out.cells.assign(static_cast<std::size_t>(out.size.x) * out.size.y * out.size.z, glm::vec4(0.0f));
  for (std::size_t i = 0; i < n; ++i) {
    if (!isFinite(positions[i]) || !isFinite(velocities[i])) continue;
    const glm::ivec3 c =
        glm::clamp(glm::ivec3(glm::floor((positions[i] - out.origin) / cell)), glm::ivec3(0), out.size - 1);
    glm::vec4& slot =
        out.cells[(static_cast<std::size_t>(c.z) * out.size.y + static_cast<std::size_t>(c.y)) * out.size.x +
                  static_cast<std::size_t>(c.x)];
    slot += glm::vec4(velocities[i], 1.0f);
  }
  const float h = std::isfinite(radius) ? std::max(radius, 0.0f) : 0.0f;
  out.neighbour_scale = 4.0f / 3.0f * std::numbers::pi_v<float> * h * h * h / (cell * cell * cell);
  return true;
}

}  // namespace fluid
