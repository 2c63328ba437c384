#pragma once
// Uniform neighbour grid for fluid/sph: particles counting-sorted by cell (Green 2008 "Particle
// simulation using CUDA"; Ihmsen et al. 2011 "A parallel SPH implementation on multi-core CPUs",
// §4: index sort by a cell key). The SPH step uses cells of half the kernel support.
//
// Cells are numbered row-major with x fastest, so the cells of one (y, z) row that a query box
// spans are consecutive keys and their particles one contiguous run of the sorted order: a query
// reads one run per row (Ihmsen et al. 2011 §4 use z-order; with half-support cells and the
// particle data re-sorted by cell, the row runs cost fewer instructions per query than the
// z-ordered 27 support-sized cells we had: callgrind, bench_sph steps).
//
// The grid covers the particles' bounding box clipped to [domain_min, domain_max]; at most
// kMaxCellsPerAxis cells per axis. Cell coordinates outside the grid are clamped to the border
// cells. Clamping is monotone, so the cells overlapping [x - r, x + r] after clamping still hold
// every particle within r: the query stays exact, only slower for stray particles.
//
// Determinism: keys and counts run in parallel (oneTBB); the scatter is a serial pass in particle
// order (a stable counting sort), so `order` is the same for every thread count.

#include <glm/glm.hpp>

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

// Compressed neighbour lists: neighbours of i are indices[offsets[i] .. offsets[i+1]), each j != i
// with |x_i - x_j| < radius (any radius > 0; the query visits the cells overlapping the box
// [x_i - radius, x_i + radius], cheapest for cells of about radius / 2: fewer candidates than the
// 27 cells of size radius), in a fixed order (row by row, then by sorted entry), identical for
// every thread count.
struct NeighborLists {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> indices;
  static constexpr std::uint32_t kSlots = 48;
  std::vector<std::uint32_t> counts;  // scratch
  std::vector<std::uint32_t> slots;   // scratch: kSlots per particle
};

void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius, NeighborLists& lists);

}  // namespace fluid
