#pragma once
// Uniform neighbour grid for fluid/sph: particles counting-sorted by cell (Green 2008 "Particle
// simulation using CUDA"; Ihmsen et al. 2011 "A parallel SPH implementation on multi-core CPUs",
// §4: index sort by a cell key). The SPH step uses cells a little wider than the search radius.
//
// Cells are numbered row-major with x fastest, so the cells of one (y, z) row that a query box
// spans are consecutive keys and their particles one contiguous run of the sorted order: a query
// reads one run per row (Ihmsen et al. 2011 §4 use z-order). With support-sized cells all
// particles of a cell share 9 runs, found once per cell, and the distance tests run four at a
// time: fewer instructions than per-particle runs over half-support cells, whose per-row
// bookkeeping cost more than the extra candidates (callgrind, bench_sph steps; see docs/sph.md).
//
// The grid covers the particles' bounding box clipped to [domain_min, domain_max]; at most
// kMaxCellsPerAxis cells per axis. Cell coordinates outside the grid are clamped to the border
// cells. Clamping is monotone, so the cells overlapping [x - r, x + r] after clamping still hold
// every particle within r: the query stays exact, only slower for stray particles.
//
// Determinism: keys and counts run in parallel (oneTBB); the scatter is a serial pass in particle
// order (a stable counting sort), so `order` is the same for every thread count.

#include <glm/glm.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

struct NeighborGrid {
  static constexpr int kMaxCellsPerAxis = 1024;

  float cell_size = 0.0f;
  glm::vec3 origin{0.0f};
  glm::ivec3 dims{0};                       // cells per axis
  std::vector<std::uint32_t> cell_start;    // size key_count + 1: entries of key k are [cell_start[k], cell_start[k+1])
  std::vector<std::uint32_t> order;         // order[e] = particle index of sorted entry e
  std::vector<std::uint32_t> particle_key;  // key of each particle (input order)
  std::vector<std::uint32_t> cursor;        // scratch for the scatter
  bool identity_order = false;              // set by markGridReordered: order[e] == e

  std::uint32_t keyCount() const { return static_cast<std::uint32_t>(dims.x * dims.y * dims.z); }
  glm::ivec3 cellOf(glm::vec3 p) const;
  std::uint32_t keyOf(glm::ivec3 cell) const;  // cell must be inside [0, dims)
};

// Rebuilds `grid` (vectors are reused; they only grow) for `positions`. cell_size > 0 (the grid may
// use larger cells when the particles' box would need too many).
// Positions must be finite (the SPH world checks before calling).
void buildNeighborGrid(NeighborGrid& grid, std::span<const glm::vec3> positions, float cell_size,
                       glm::vec3 domain_min = glm::vec3(-1e30f), glm::vec3 domain_max = glm::vec3(1e30f));

// After the caller permuted its particle data by grid.order (new index e = old index order[e]),
// makes the grid describe the permuted data (order becomes the identity).
void markGridReordered(NeighborGrid& grid);
// The same for a caller that permuted its data in its own parallel pass and, in that pass, also
// wrote sorted_keys[e] = grid.particle_key[grid.order[e]] (the keys in the new order) and
// grid.order[e] = e: swaps the keys in (sorted_keys gets the old buffer) without another pass.
void markGridReordered(NeighborGrid& grid, std::vector<std::uint32_t>& sorted_keys);

// Compressed neighbour lists: neighbours of i are indices[offsets[i] .. offsets[i+1]), each j != i
// with |x_i - x_j| < radius (any radius > 0), in a fixed order (row by row, then by sorted
// entry), identical for every thread count. The query visits, for all particles of one cell at
// once, the cells within neighborReach(grid, radius) of that cell (one run of sorted entries per
// (y, z) row): cheapest for cells a little wider than the radius (3 x 3 rows of 3 cells; the
// SPH step uses radius * 1.002). The distance test is the same float expression as a
// brute-force dot(x_i - x_j, x_i - x_j) < radius^2, four candidates at a time (SSE2) over SoA
// copies of the sorted positions, so the lists are exact.
struct NeighborLists {
  // Particles are searched in chunks of kChunk consecutive sorted entries; a chunk's lists are
  // written to its own buffer and then copied into `indices` (one search per particle, any count).
  static constexpr std::uint32_t kChunk = 256;
  // Initial size per particle of a chunk buffer (it grows if a chunk needs more room: it must
  // hold the chunk's lists plus one cell's candidates).
  static constexpr std::uint32_t kReservePerParticle = 64;
  // Padding of sx/sy/sz beyond the n positions (one 8-wide load past a run's end).
  static constexpr std::size_t kPad = 8;
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> indices;
  std::vector<std::uint32_t> counts;                    // scratch: count per particle
  std::vector<std::uint32_t> chunk_used;                // scratch: entries used in each chunk buffer
  std::vector<std::uint32_t> runs;                      // scratch: row runs of the current cell, per chunk
  std::vector<std::vector<std::uint32_t>> chunk_pairs;  // scratch: one buffer per chunk
  std::vector<float> sx, sy, sz;                        // scratch: sorted positions (SoA, padded)
};

// Cells per axis on each side of a particle's cell that can hold neighbours within `radius`
// (>= 1): ceil((radius + float slack) / cell_size).
int neighborReach(const NeighborGrid& grid, float radius);

// The candidates of a query around `cell`: the cells within `reach` of it, one run of sorted
// entries [begin, end) per (y, z) row (cells x - reach .. x + reach of a row are consecutive keys,
// x fastest), rows in z then y order. Calls run(begin, end) for each row, empty ones included. The
// order is fixed, so sums taken in it are the same for every thread count.
template <class Run>
void forEachNeighborRun(const NeighborGrid& grid, glm::ivec3 cell, int reach, Run&& run) {
  const auto x0 = static_cast<std::uint32_t>(std::max(cell.x - reach, 0)),
             x1 = static_cast<std::uint32_t>(std::min(cell.x + reach, grid.dims.x - 1));
  const auto dx = static_cast<std::uint32_t>(grid.dims.x), dy = static_cast<std::uint32_t>(grid.dims.y);
  for (int z = std::max(cell.z - reach, 0); z <= std::min(cell.z + reach, grid.dims.z - 1); ++z)
    for (int y = std::max(cell.y - reach, 0); y <= std::min(cell.y + reach, grid.dims.y - 1); ++y) {
      // keyOf({x, y, z}), inline: this runs once per row of every query.
      const std::uint32_t row = (static_cast<std::uint32_t>(z) * dy + static_cast<std::uint32_t>(y)) * dx;
      run(grid.cell_start[row + x0], grid.cell_start[row + x1 + 1]);
    }
}

// The positions in the grid's sorted order as three float arrays (SoA), each of n + pad floats with
// the padding zeroed, so a run's neighbours are one contiguous stretch of each array and a wide
// load at a run's end stays inside them. Parallel; the result does not depend on the thread count.
void copySortedPositions(const NeighborGrid& grid, std::span<const glm::vec3> positions, std::size_t pad,
                         std::vector<float>& sx, std::vector<float>& sy, std::vector<float>& sz);

// Reserves the scratch of `lists` for `capacity` particles.
void reserveNeighborLists(NeighborLists& lists, std::size_t capacity);

// positions_copied: the caller already wrote the positions in sorted order to lists.sx/sy/sz
// (sized n + NeighborLists::kPad; the padding is zeroed here), e.g. in its own re-sort pass.
void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius, NeighborLists& lists,
                   bool positions_copied = false);

}  // namespace fluid
