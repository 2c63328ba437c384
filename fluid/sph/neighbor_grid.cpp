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
    // Clamp in float first (float -> int conversion of out-of-range values is undefined); on the
    // clamped, non-negative value truncation equals floor, without a libm call.
    const float f = std::clamp(c[a], 0.0f, static_cast<float>(dims[a] - 1));
    out[a] = static_cast<int>(f);
  }
  return out;
}

std::uint32_t NeighborGrid::keyOf(glm::ivec3 cell) const {
  return (static_cast<std::uint32_t>(cell.z) * static_cast<std::uint32_t>(dims.y) +
          static_cast<std::uint32_t>(cell.y)) *
             static_cast<std::uint32_t>(dims.x) +
         static_cast<std::uint32_t>(cell.x);
}

void buildNeighborGrid(NeighborGrid& grid, std::span<const glm::vec3> positions, float cell_size, glm::vec3 domain_min,
                       glm::vec3 domain_max) {
  assert(cell_size > 0.0f);
  const std::size_t n = positions.size();
  grid.cell_size = cell_size;
  grid.identity_order = false;

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
      total *= grid.dims[a];
    }
    if (total <= budget) break;
    grid.cell_size *= static_cast<float>(std::cbrt(total / budget) * 1.01);
  }
  const std::uint32_t key_count = grid.keyCount();

  grid.particle_key.resize(n);
  grid.order.resize(n);
  // Capacity for the whole budget at once: the key count changes with the particles' box every
  // step, and a growing fluid must not reallocate step after step.
  const std::size_t capacity = static_cast<std::size_t>(std::max(budget, static_cast<double>(key_count))) + 1;
  if (grid.cell_start.capacity() < capacity) {
    grid.cell_start.reserve(capacity);
    grid.cursor.reserve(capacity);
  }
  grid.cell_start.assign(key_count + 1, 0u);

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
  // 3. serial stable scatter in particle order: no per-cell sort needed for determinism, and it is
  // one store per particle (about 0.1 ms for 100k particles).
  grid.cursor.resize(key_count + 1);
  std::copy(grid.cell_start.begin(), grid.cell_start.end(), grid.cursor.begin());
  for (std::size_t i = 0; i < n; ++i) grid.order[grid.cursor[grid.particle_key[i]]++] = static_cast<std::uint32_t>(i);
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
  grid.identity_order = true;
}

namespace {

// Calls f(begin, end) for each run of sorted entries that holds the cells overlapping the box
// [p - r, p + r] (one run per (y, z) row, since x is the fastest key), in a fixed order (z, then
// y ascending). Rows whose (y, z) slab is at least r from p are skipped. Cell coordinates are
// clamped like cellOf, which keeps strays exact (clamping is monotone).
template <typename F>
inline void forEachRun(const NeighborGrid& grid, glm::vec3 p, float r, F&& f) {
  const glm::ivec3 lo = grid.cellOf(p - glm::vec3(r)), hi = grid.cellOf(p + glm::vec3(r));
  const float cs = grid.cell_size, r2 = r * r;
  for (int z = lo.z; z <= hi.z; ++z) {
    // Distance from p to the slab of row z (conservative 0 for the open border rows).
    const float zlo = grid.origin.z + cs * static_cast<float>(z);
    float dz = std::max(std::max(zlo - p.z, p.z - (zlo + cs)), 0.0f);
    if (z == 0 || z == grid.dims.z - 1) dz = 0.0f;
    for (int y = lo.y; y <= hi.y; ++y) {
      const float ylo = grid.origin.y + cs * static_cast<float>(y);
      float dy = std::max(std::max(ylo - p.y, p.y - (ylo + cs)), 0.0f);
      if (y == 0 || y == grid.dims.y - 1) dy = 0.0f;
      if (dz * dz + dy * dy >= r2) continue;
      const std::uint32_t k0 = grid.keyOf({lo.x, y, z}), k1 = grid.keyOf({hi.x, y, z});
      const std::uint32_t b = grid.cell_start[k0], e = grid.cell_start[k1 + 1];
      if (b != e) f(b, e);
    }
  }
}

// Appends (via emit) every neighbour j != i of particle i within sqrt(r2), in run order.
template <bool kIdentity, typename Emit>
inline void searchParticle(const NeighborGrid& grid, std::span<const glm::vec3> positions, std::uint32_t i, float r,
                           Emit&& emit) {
  const glm::vec3 p = positions[i];
  const std::uint32_t* order = grid.order.data();
  const float r2 = r * r;
  forEachRun(grid, p, r, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t s = b; s < e; ++s) {
      const std::uint32_t j = kIdentity ? s : order[s];
      const glm::vec3 d = p - positions[j];
      if (glm::dot(d, d) < r2 && j != i) emit(j);
    }
  });
}

template <bool kIdentity>
void findImpl(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius, NeighborLists& lists) {
  const std::size_t n = positions.size();
  const std::uint32_t* order = grid.order.data();
  // One pass into fixed per-particle slots (a resting fluid has about 30 neighbours at H = 2d);
  // only particles with more than kSlots neighbours are searched a second time below. Particles
  // are visited in sorted (cell) order, so consecutive particles share their runs in cache.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      const std::uint32_t i = kIdentity ? static_cast<std::uint32_t>(s) : order[s];
      std::uint32_t c = 0;
      std::uint32_t* slot = lists.slots.data() + static_cast<std::size_t>(i) * NeighborLists::kSlots;
      searchParticle<kIdentity>(grid, positions, i, radius, [&](std::uint32_t j) {
        if (c < NeighborLists::kSlots) slot[c] = j;
        ++c;
      });
      lists.counts[i] = c;
    }
  });
  lists.offsets[0] = 0;
  for (std::size_t i = 0; i < n; ++i) lists.offsets[i + 1] = lists.offsets[i] + lists.counts[i];
  lists.indices.resize(lists.offsets[n]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      std::uint32_t out = lists.offsets[i];
      if (lists.counts[i] <= NeighborLists::kSlots) {
        const std::uint32_t* slot = lists.slots.data() + i * NeighborLists::kSlots;
        std::copy(slot, slot + lists.counts[i], lists.indices.data() + out);
        continue;
      }
      searchParticle<kIdentity>(grid, positions, static_cast<std::uint32_t>(i), radius,
                                [&](std::uint32_t j) { lists.indices[out++] = j; });
    }
  });
}

}  // namespace

void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius, NeighborLists& lists) {
  const std::size_t n = positions.size();
  lists.counts.resize(n);
  lists.offsets.resize(n + 1);
  lists.slots.resize(n * NeighborLists::kSlots);
  if (grid.identity_order)
    findImpl<true>(grid, positions, radius, lists);
  else
    findImpl<false>(grid, positions, radius, lists);
}

}  // namespace fluid
