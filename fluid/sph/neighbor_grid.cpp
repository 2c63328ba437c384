#include "fluid/sph/neighbor_grid.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace fluid {
namespace {

struct Bounds {
  glm::vec3 lo{1e30f};
  glm::vec3 hi{-1e30f};
};

constexpr std::size_t kGrain = 1024;
constexpr std::size_t kPad = NeighborLists::kPad;  // padding of the SoA position copies (one 8-wide load)

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
  Bounds box = par::parallelReduce(
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
  par::parallelFor(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
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
  par::parallelFor(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t e = r.begin(); e != r.end(); ++e) grid.order[e] = static_cast<std::uint32_t>(e);
  });
  // particle_key must follow the permutation too: entries are now in key order.
  for (std::uint32_t k = 0; k + 1 < grid.cell_start.size(); ++k) {
    for (std::uint32_t e = grid.cell_start[k]; e < grid.cell_start[k + 1]; ++e) grid.particle_key[e] = k;
  }
  grid.identity_order = true;
}

void markGridReordered(NeighborGrid& grid, std::vector<std::uint32_t>& sorted_keys) {
  assert(sorted_keys.size() == grid.order.size());
  grid.particle_key.swap(sorted_keys);
  grid.identity_order = true;
}

namespace {

// Calls emit(t) for every sorted entry t in [b, e) with dot(p - x_t, p - x_t) < r2, ascending.
template <typename Emit>
inline void scanRun(const float* sx, const float* sy, const float* sz, std::uint32_t b, std::uint32_t e, glm::vec3 p,
                    float r2, Emit&& emit) {
#if defined(__SSE2__)
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z), rr = _mm_set1_ps(r2);
  for (std::uint32_t t = b; t < e; t += 4) {
    const __m128 dx = _mm_sub_ps(px, _mm_loadu_ps(sx + t));
    const __m128 dy = _mm_sub_ps(py, _mm_loadu_ps(sy + t));
    const __m128 dz = _mm_sub_ps(pz, _mm_loadu_ps(sz + t));
    // ((dx dx + dy dy) + dz dz): the evaluation order of glm::dot, so the test is bit-for-bit
    // the brute-force one.
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    unsigned bits = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(d2, rr)));
    if (e - t < 4) bits &= (1u << (e - t)) - 1u;  // lanes past the run (the arrays are padded)
    while (bits) {
      emit(t + static_cast<std::uint32_t>(__builtin_ctz(bits)));
      bits &= bits - 1u;
    }
  }
#else
  for (std::uint32_t t = b; t < e; ++t) {
    const glm::vec3 d = p - glm::vec3(sx[t], sy[t], sz[t]);
    if (glm::dot(d, d) < r2) emit(t);
  }
#endif
}

// One particle's scan over the row runs of its cell: writes the neighbours (particle indices,
// without `self`) to out and returns the end. Every row gets room for all its candidates.
struct RowScan {
  const float* sx;
  const float* sy;
  const float* sz;
  const std::uint32_t* runs;  // rows pairs (begin, end) of sorted entries
  std::size_t rows;
  const std::uint32_t* order;  // sorted entry -> particle index; null when the order is the identity
  float r2;
};

std::uint32_t* scanRows(const RowScan& a, std::uint32_t self, glm::vec3 p, std::uint32_t* out) {
  for (std::size_t k = 0; k < a.rows; ++k)
    scanRun(a.sx, a.sy, a.sz, a.runs[2 * k], a.runs[2 * k + 1], p, a.r2, [&](std::uint32_t t) {
      *out = a.order ? a.order[t] : t;
      out += t != self ? 1 : 0;
    });
  return out;
}

#if defined(__x86_64__) && defined(__GNUC__)
#define FLUID_SPH_AVX2_SCAN 1
// The same scan eight candidates at a time where the CPU has AVX2 (picked at run time; the build
// targets baseline x86-64). The arithmetic is the same IEEE sequence without FMA (the target
// does not enable it, so nothing is contracted): the lists are identical to the SSE2 scan's.
// Bit l set: candidate t + l (< e) lies within the radius, |p - x|^2 < r^2 (the SSE2 scan's test).
__attribute__((target("avx2"))) inline unsigned inRange8(const RowScan& a, std::uint32_t t, std::uint32_t e, __m256 px,
                                                         __m256 py, __m256 pz, __m256 rr) {
  const __m256 dx = _mm256_sub_ps(px, _mm256_loadu_ps(a.sx + t));
  const __m256 dy = _mm256_sub_ps(py, _mm256_loadu_ps(a.sy + t));
  const __m256 dz = _mm256_sub_ps(pz, _mm256_loadu_ps(a.sz + t));
  const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
  unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, rr, _CMP_LT_OQ)));
  if (e - t < 8) bits &= (1u << (e - t)) - 1u;
  return bits;
}

__attribute__((target("avx2"))) std::uint32_t* scanRowsAvx2(const RowScan& a, std::uint32_t self, glm::vec3 p,
                                                            std::uint32_t* out) {
  const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z), rr = _mm256_set1_ps(a.r2);
  for (std::size_t k = 0; k < a.rows; ++k) {
    const std::uint32_t b = a.runs[2 * k], e = a.runs[2 * k + 1];
    for (std::uint32_t t = b; t < e; t += 8) {
      unsigned bits = inRange8(a, t, e, px, py, pz, rr);
      while (bits) {
        const std::uint32_t u = t + static_cast<std::uint32_t>(__builtin_ctz(bits));
        *out = a.order ? a.order[u] : u;
        out += u != self ? 1 : 0;
        bits &= bits - 1u;
      }
    }
  }
  return out;
}

// Left-packing (identity order only): per 8-candidate block, the accepted lanes' entry numbers are
// moved to the front of one 8-wide store by a table lookup (lane numbers in ascending order, one
// byte each, widened to 32 bits) and the output advances by their count. The per-neighbour loop
// above costs a hard-to-predict branch per accepted candidate; this costs none. Same entries in
// the same order: the particle itself is masked out of its block instead of skipped at the store.
// The store writes 8 entries, so the output needs room for 8 beyond the last neighbour.
struct PackTable {
  std::uint64_t lanes[256];
  std::uint8_t count[256];
};
constexpr PackTable makePackTable() {
  PackTable t{};
  for (int m = 0; m < 256; ++m) {
    std::uint64_t v = 0;
    int k = 0;
    for (int l = 0; l < 8; ++l)
      if (m & (1 << l)) v |= static_cast<std::uint64_t>(l) << (8 * k++);
    t.lanes[m] = v;
    t.count[m] = static_cast<std::uint8_t>(k);
  }
  return t;
}
constexpr PackTable kPack = makePackTable();

__attribute__((target("avx2"))) std::uint32_t* scanRowsAvx2Packed(const RowScan& a, std::uint32_t self, glm::vec3 p,
                                                                  std::uint32_t* out) {
  const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z), rr = _mm256_set1_ps(a.r2);
  for (std::size_t k = 0; k < a.rows; ++k) {
    const std::uint32_t b = a.runs[2 * k], e = a.runs[2 * k + 1];
    for (std::uint32_t t = b; t < e; t += 8) {
      unsigned bits = inRange8(a, t, e, px, py, pz, rr);
      if (self - t < 8u) bits &= ~(1u << (self - t));  // the particle itself (unsigned: t <= self < t + 8)
      const __m256i lanes = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(kPack.lanes[bits])));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out),
                          _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(t)), lanes));
      out += kPack.count[bits];
    }
  }
  return out;
}
#endif

}  // namespace

void reserveNeighborLists(NeighborLists& lists, std::size_t capacity) {
  lists.counts.reserve(capacity);
  lists.offsets.reserve(capacity + 1);
  for (auto* v : {&lists.sx, &lists.sy, &lists.sz}) v->reserve(capacity + kPad);
  const std::size_t chunks = (capacity + NeighborLists::kChunk - 1) / NeighborLists::kChunk;
  lists.chunk_used.reserve(chunks);
  lists.runs.reserve(chunks * 2 * 27);
  lists.chunk_pairs.reserve(chunks);
  while (lists.chunk_pairs.size() < chunks)
    lists.chunk_pairs.emplace_back(static_cast<std::size_t>(NeighborLists::kChunk) *
                                   NeighborLists::kReservePerParticle);
}

void copySortedPositions(const NeighborGrid& grid, std::span<const glm::vec3> positions, std::size_t pad,
                         std::vector<float>& sx, std::vector<float>& sy, std::vector<float>& sz) {
  const std::size_t n = positions.size();
  sx.resize(n + pad);
  sy.resize(n + pad);
  sz.resize(n + pad);
  const std::uint32_t* order = grid.order.data();
  const bool identity = grid.identity_order;
  par::parallelFor(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const glm::vec3 x = positions[identity ? t : order[t]];
      sx[t] = x.x;
      sy[t] = x.y;
      sz[t] = x.z;
    }
  });
  for (std::size_t t = n; t < n + pad; ++t) sx[t] = sy[t] = sz[t] = 0.0f;
}

int neighborReach(const NeighborGrid& grid, float radius) {
  // Float slack: cell coordinates and the distance test are rounded relative to the coordinates'
  // magnitude (one ulp is 1.2e-7 of it); 5e-6 of the largest coordinate (and 1e-5 of the radius)
  // is far above that, so a pair the float test accepts never lies more than `reach` cells apart.
  float extent = 0.0f;
  for (int a = 0; a < 3; ++a)
    extent = std::max({extent, std::abs(grid.origin[a]),
                       std::abs(grid.origin[a] + grid.cell_size * static_cast<float>(grid.dims[a]))});
  const float slack = 5e-6f * extent + 1e-5f * radius;
  return std::max(1, static_cast<int>(std::ceil((radius + slack) / grid.cell_size)));
}

void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius, NeighborLists& lists,
                   bool positions_copied) {
  const std::size_t n = positions.size();
  constexpr std::uint32_t K = NeighborLists::kChunk;
  const std::size_t chunks = (n + K - 1) / K;
  lists.counts.resize(n);
  lists.offsets.resize(n + 1);
  lists.chunk_used.resize(chunks);
  // Chunk buffers: vectors only grow; a new buffer starts with the usual capacity so that a
  // growing fluid does not reallocate its buffers many times.
  while (lists.chunk_pairs.size() < chunks)
    lists.chunk_pairs.emplace_back(static_cast<std::size_t>(K) * NeighborLists::kReservePerParticle);
  const std::uint32_t* order = grid.order.data();
  const bool identity = grid.identity_order;
  // SoA copies of the positions in sorted order, padded so that a 4- or 8-wide load at the end
  // of a run never reads past the arrays (the lanes past the run are masked off).
  if (positions_copied) {
    lists.sx.resize(n + kPad);
    lists.sy.resize(n + kPad);
    lists.sz.resize(n + kPad);
    for (std::size_t t = n; t < n + kPad; ++t) lists.sx[t] = lists.sy[t] = lists.sz[t] = 0.0f;
  } else {
    copySortedPositions(grid, positions, kPad, lists.sx, lists.sy, lists.sz);
  }
  const float* sx = lists.sx.data();
  const float* sy = lists.sy.data();
  const float* sz = lists.sz.data();
  const float r2 = radius * radius;
  const int reach = neighborReach(grid, radius);
  const std::size_t max_rows = static_cast<std::size_t>(2 * reach + 1) * static_cast<std::size_t>(2 * reach + 1);
  lists.runs.resize(chunks * 2 * max_rows);
  auto scan = &scanRows;
#if defined(FLUID_SPH_AVX2_SCAN)
  if (__builtin_cpu_supports("avx2")) scan = identity ? &scanRowsAvx2Packed : &scanRowsAvx2;
#endif

  // 1. Search: chunk c holds sorted entries [c K, (c + 1) K), grouped by cell. The particles of
  // one cell share their candidates: the cells within `reach` of it, one run of sorted entries
  // per (y, z) row (x is the fastest key), computed once per cell. The chunk's output depends
  // only on the chunk, not on which thread ran it.
  par::parallelFor(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
    for (std::size_t c = cr.begin(); c != cr.end(); ++c) {
      std::vector<std::uint32_t>& buf = lists.chunk_pairs[c];
      std::uint32_t* runs = lists.runs.data() + c * 2 * max_rows;
      std::size_t used = 0;
      const std::size_t end = std::min(n, (c + 1) * K);
      for (std::size_t s = c * K; s < end;) {
        const std::uint32_t key = grid.particle_key[identity ? s : order[s]];
        std::size_t group_end = s + 1;
        while (group_end < end && grid.particle_key[identity ? group_end : order[group_end]] == key) ++group_end;
        // The cell's coordinates from its key (row-major, x fastest).
        const int cx = static_cast<int>(key % static_cast<std::uint32_t>(grid.dims.x));
        const int cy =
            static_cast<int>((key / static_cast<std::uint32_t>(grid.dims.x)) % static_cast<std::uint32_t>(grid.dims.y));
        const int cz = static_cast<int>(key / static_cast<std::uint32_t>(grid.dims.x * grid.dims.y));
        std::size_t rows = 0, candidates = 0;
        forEachNeighborRun(grid, {cx, cy, cz}, reach, [&](std::uint32_t b, std::uint32_t e) {
          if (b == e) return;
          runs[2 * rows] = b;
          runs[2 * rows + 1] = e;
          ++rows;
          candidates += e - b;
        });
        for (; s < group_end; ++s) {
          // Room for every candidate (plus the 8-wide store of the packed scan), so the scan
          // writes through a plain pointer.
          const std::size_t room = used + candidates + 8;
          if (buf.size() < room) buf.resize(std::max(2 * buf.size(), room));
          std::uint32_t* const first = buf.data() + used;
          const RowScan args{sx, sy, sz, runs, rows, identity ? nullptr : order, r2};
          const std::uint32_t* const last =
              scan(args, static_cast<std::uint32_t>(s), glm::vec3(sx[s], sy[s], sz[s]), first);
          const std::size_t count = static_cast<std::size_t>(last - first);
          lists.counts[identity ? s : order[s]] = static_cast<std::uint32_t>(count);
          used += count;
        }
      }
      lists.chunk_used[c] = static_cast<std::uint32_t>(used);
    }
  });
  // 2. Offsets (per particle index), then each chunk's lists copied to their places.
  lists.offsets[0] = 0;
  for (std::size_t i = 0; i < n; ++i) lists.offsets[i + 1] = lists.offsets[i] + lists.counts[i];
  lists.indices.resize(lists.offsets[n]);
  par::parallelFor(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
    for (std::size_t c = cr.begin(); c != cr.end(); ++c) {
      const std::uint32_t* src = lists.chunk_pairs[c].data();
      if (identity) {
        // Entries of a chunk are consecutive particles: one copy.
        std::copy(src, src + lists.chunk_used[c], lists.indices.data() + lists.offsets[c * K]);
        continue;
      }
      const std::size_t end = std::min(n, (c + 1) * K);
      for (std::size_t s = c * K; s < end; ++s) {
        const std::uint32_t i = order[s];
        std::copy(src, src + lists.counts[i], lists.indices.data() + lists.offsets[i]);
        src += lists.counts[i];
      }
    }
  });
}

}  // namespace fluid
