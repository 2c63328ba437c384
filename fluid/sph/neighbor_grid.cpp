#include "fluid/sph/neighbor_grid.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>

namespace fluid {
namespace {

// Interleaves the low 2 bits of x, y, z: Morton index inside a 4x4x4 tile.
constexpr std::uint32_t morton2(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return (x & 1u) | ((y & 1u) << 1) | ((z & 1u) << 2) | ((x & 2u) << 2) | ((y & 2u) << 3) | ((z & 2u) << 4);
}

struct Bounds {
  glm::vec3 lo{1e30f};
  glm::vec3 hi{-1e30f};
};

constexpr std::size_t kGrain = 1024;

}  // namespace

glm::ivec3 NeighborGrid::cellOf(glm::vec3 p) const {
  const glm::vec3 c = (p - origin) / cell_size;
  glm::ivec3 out;
  for (int a = 0; a < 3; ++a) {
    // Clamp in float first: float -> int conversion of out-of-range values is undefined.
    const float f = std::clamp(std::floor(c[a]), 0.0f, static_cast<float>(dims[a] - 1));
    out[a] = static_cast<int>(f);
  }
  return out;
}

std::uint32_t NeighborGrid::keyOf(glm::ivec3 cell) const {
  const auto tx = static_cast<std::uint32_t>(cell.x >> 2), ty = static_cast<std::uint32_t>(cell.y >> 2),
             tz = static_cast<std::uint32_t>(cell.z >> 2);
  const std::uint32_t tile = (tz * static_cast<std::uint32_t>(tiles.y) + ty) * static_cast<std::uint32_t>(tiles.x) + tx;
  return tile * 64u + morton2(static_cast<std::uint32_t>(cell.x), static_cast<std::uint32_t>(cell.y),
                              static_cast<std::uint32_t>(cell.z));
}

void buildNeighborGrid(NeighborGrid& grid, std::span<const glm::vec3> positions, float cell_size,
                       glm::vec3 domain_min, glm::vec3 domain_max) {
  assert(cell_size > 0.0f);
  const std::size_t n = positions.size();
  grid.cell_size = cell_size;

  // Bounding box (min/max are exact and order-independent, so any reduction order is fine).
  Bounds box = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), Bounds{},
      [&](const tbb::blocked_range<std::size_t>& r, Bounds b) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          b.lo = glm::min(b.lo, positions[i]);
          b.hi = glm::max(b.hi, positions[i]);
        }
        return b;
      },
      [](Bounds a, const Bounds& b) {
        a.lo = glm::min(a.lo, b.lo);
        a.hi = glm::max(a.hi, b.hi);
        return a;
      });
  if (n == 0) box = Bounds{glm::vec3(0.0f), glm::vec3(0.0f)};
  box.lo = glm::clamp(box.lo, domain_min, domain_max);
  box.hi = glm::clamp(box.hi, domain_min, domain_max);
  box.hi = glm::max(box.hi, box.lo);
  grid.origin = box.lo;
  // Bounded key range: at most kMaxCellsPerAxis per axis and about max(2^18, 8n) cells in all. A
  // box too large for that (stray particles without a domain) gets proportionally larger cells,
  // which keeps the 27-cell query exact (cells only need to be at least `cell_size` wide).
  const double budget = std::max(262144.0, 8.0 * static_cast<double>(n));
  for (int attempt = 0; attempt < 8; ++attempt) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a) {
      const double cells = std::floor(static_cast<double>(box.hi[a] - box.lo[a]) / grid.cell_size) + 1.0;
      grid.dims[a] = static_cast<int>(std::clamp(cells, 1.0, static_cast<double>(NeighborGrid::kMaxCellsPerAxis)));
      grid.tiles[a] = (grid.dims[a] + 3) / 4;
      total *= grid.dims[a];
    }
    if (total <= budget) break;
    grid.cell_size *= static_cast<float>(std::cbrt(total / budget) * 1.01);
  }
  const std::uint32_t key_count = grid.keyCount();

  grid.particle_key.resize(n);
  grid.order.resize(n);
  grid.cell_start.assign(key_count + 1, 0u);  // reuses capacity once warmed up
  grid.cursor.resize(key_count + 1);

  // 1. keys and counts (atomic increments: the counts do not depend on the order).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t key = grid.keyOf(grid.cellOf(positions[i]));
      grid.particle_key[i] = key;
      std::atomic_ref<std::uint32_t>(grid.cell_start[key + 1]).fetch_add(1u, std::memory_order_relaxed);
    }
  });
  // 2. exclusive scan -> start of each cell.
  for (std::uint32_t k = 0; k < key_count; ++k) grid.cell_start[k + 1] += grid.cell_start[k];
  std::copy(grid.cell_start.begin(), grid.cell_start.end(), grid.cursor.begin());
  // 3. scatter (slot order inside a cell depends on scheduling) ...
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t slot =
          std::atomic_ref<std::uint32_t>(grid.cursor[grid.particle_key[i]]).fetch_add(1u, std::memory_order_relaxed);
      grid.order[slot] = static_cast<std::uint32_t>(i);
    }
  });
  // 4. ... so each cell is sorted by particle index: a stable counting sort, thread-count invariant.
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, key_count, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t b = grid.cell_start[k], e = grid.cell_start[k + 1];
      if (e - b > 1) std::sort(grid.order.begin() + b, grid.order.begin() + e);
    }
  });
}

void markGridReordered(NeighborGrid& grid) {
  const std::size_t n = grid.order.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t e = r.begin(); e != r.end(); ++e) grid.order[e] = static_cast<std::uint32_t>(e);
  });
  // particle_key must follow the permutation too: entries are now in key order.
  for (std::uint32_t k = 0; k + 1 < grid.cell_start.size(); ++k) {
    for (std::uint32_t e = grid.cell_start[k]; e < grid.cell_start[k + 1]; ++e) grid.particle_key[e] = k;
  }
}

namespace {

struct Range {
  std::uint32_t begin, end;
  glm::vec3 lo, hi;  // the cell's box (the border cells' boxes are unbounded outward: clamping)
};

// Squared distance from p to the box of a cell: cells entirely out of reach are skipped, which
// removes about a third of the candidates of the 27-cell block.
inline float boxDistance2(glm::vec3 p, const Range& r) {
  const glm::vec3 d = glm::max(glm::max(r.lo - p, p - r.hi), glm::vec3(0.0f));
  return glm::dot(d, d);
}

// The (up to 27) entry ranges of the cells around `cell`, in a fixed order (z, y, x ascending).
inline int neighbourRanges(const NeighborGrid& grid, glm::ivec3 cell, Range* out) {
  const glm::ivec3 lo = glm::max(cell - 1, glm::ivec3(0));
  const glm::ivec3 hi = glm::min(cell + 1, grid.dims - 1);
  int count = 0;
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const std::uint32_t key = grid.keyOf({x, y, z});
        Range r{grid.cell_start[key], grid.cell_start[key + 1], glm::vec3(0.0f), glm::vec3(0.0f)};
        if (r.end == r.begin) continue;
        const glm::ivec3 c(x, y, z);
        for (int a = 0; a < 3; ++a) {
          // Border cells also hold the clamped particles beyond the grid: open their boxes outward.
          r.lo[a] = c[a] == 0 ? -3e38f : grid.origin[a] + grid.cell_size * static_cast<float>(c[a]);
          r.hi[a] = c[a] == grid.dims[a] - 1 ? 3e38f : grid.origin[a] + grid.cell_size * static_cast<float>(c[a] + 1);
        }
        out[count++] = r;
      }
  return count;
}

// Runs f(i, ranges, count) for every particle, cell by cell (all particles of a cell share the
// candidate ranges), in parallel over cells.
template <typename F>
void forEachParticleByCell(const NeighborGrid& grid, std::span<const glm::vec3> positions, F&& f) {
  const std::uint32_t keys = grid.keyCount();
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, keys, 64), [&](const tbb::blocked_range<std::uint32_t>& r) {
    Range ranges[27];
    for (std::uint32_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t b = grid.cell_start[k], e = grid.cell_start[k + 1];
      if (b == e) continue;
      const int count = neighbourRanges(grid, grid.cellOf(positions[grid.order[b]]), ranges);
      for (std::uint32_t s = b; s < e; ++s) f(grid.order[s], ranges, count);
    }
  });
}

}  // namespace

void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius,
                   NeighborLists& lists) {
  assert(radius <= grid.cell_size * 1.0001f);
  const std::size_t n = positions.size();
  const float r2 = radius * radius;
  lists.counts.resize(n);
  lists.offsets.resize(n + 1);
  lists.slots.resize(n * NeighborLists::kSlots);
  const std::uint32_t* order = grid.order.data();
  // One pass into fixed per-particle slots (a resting fluid has about 30 neighbours at H = 2d);
  // only particles with more than kSlots neighbours are searched a second time below.
  forEachParticleByCell(grid, positions, [&](std::uint32_t i, const Range* ranges, int count) {
    const glm::vec3 p = positions[i];
    std::uint32_t c = 0;
    std::uint32_t* slot = lists.slots.data() + static_cast<std::size_t>(i) * NeighborLists::kSlots;
    for (int q = 0; q < count; ++q) {
      if (boxDistance2(p, ranges[q]) >= r2) continue;
      for (std::uint32_t e = ranges[q].begin; e < ranges[q].end; ++e) {
        const std::uint32_t j = order[e];
        const glm::vec3 d = p - positions[j];
        if (j != i && glm::dot(d, d) < r2) {
          if (c < NeighborLists::kSlots) slot[c] = j;
          ++c;
        }
      }
    }
    lists.counts[i] = c;
  });
  lists.offsets[0] = 0;
  for (std::size_t i = 0; i < n; ++i) lists.offsets[i + 1] = lists.offsets[i] + lists.counts[i];
  lists.indices.resize(lists.offsets[n]);
  forEachParticleByCell(grid, positions, [&](std::uint32_t i, const Range* ranges, int count) {
    std::uint32_t out = lists.offsets[i];
    if (lists.counts[i] <= NeighborLists::kSlots) {
      const std::uint32_t* slot = lists.slots.data() + static_cast<std::size_t>(i) * NeighborLists::kSlots;
      for (std::uint32_t k = 0; k < lists.counts[i]; ++k) lists.indices[out++] = slot[k];
      return;
    }
    const glm::vec3 p = positions[i];
    for (int q = 0; q < count; ++q)
      for (std::uint32_t e = ranges[q].begin; e < ranges[q].end; ++e) {
        const std::uint32_t j = order[e];
        const glm::vec3 d = p - positions[j];
        if (j != i && glm::dot(d, d) < r2) lists.indices[out++] = j;
      }
  });
}

}  // namespace fluid
