#pragma once
// Uniform neighbour grid for fluid/sph: cell size = kernel support radius, particles counting-
// sorted by cell (Green 2008 "Particle simulation using CUDA"; Ihmsen et al. 2011 "A parallel
// SPH implementation on multi-core CPUs", §4: index sort by a cell key with z-order locality).
//
// Cells are numbered in tiles of 4x4x4 cells, tiles row-major and cells inside a tile in
// Morton (z-)order, so neighbouring cells are mostly near in memory while the key range stays
// dense (counting sort needs a bounded key range).
//
// The grid covers the particles' bounding box clipped to [domain_min, domain_max]; at most
// kMaxCellsPerAxis cells per axis. Cell coordinates outside the grid are clamped to the border
// cells. Clamping is 1-Lipschitz, so two particles within one cell size of each other still land
// in cells at most one apart: the 27-cell query stays exact, only slower for stray particles.
//
// Determinism: keys, counts and the scatter run in parallel (oneTBB), then each cell's entries
// are sorted by particle index, so `order` is the same for every thread count.

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

struct NeighborGrid {
  static constexpr int kMaxCellsPerAxis = 1024;

  float cell_size = 0.0f;
  glm::vec3 origin{0.0f};
  glm::ivec3 dims{0};    // cells per axis
  glm::ivec3 tiles{0};   // 4x4x4 tiles per axis
  std::vector<std::uint32_t> cell_start;  // size key_count + 1: entries of key k are [cell_start[k], cell_start[k+1])
  std::vector<std::uint32_t> order;       // order[e] = particle index of sorted entry e
  std::vector<std::uint32_t> particle_key;  // key of each particle (input order)
  std::vector<std::uint32_t> cursor;        // scratch for the scatter

  std::uint32_t keyCount() const { return static_cast<std::uint32_t>(tiles.x * tiles.y * tiles.z * 64); }
  glm::ivec3 cellOf(glm::vec3 p) const;
  std::uint32_t keyOf(glm::ivec3 cell) const;  // cell must be inside [0, dims)
};

// Rebuilds `grid` (vectors are reused; they only grow) for `positions`. cell_size > 0.
// Positions must be finite (the SPH world checks before calling).
void buildNeighborGrid(NeighborGrid& grid, std::span<const glm::vec3> positions, float cell_size,
                       glm::vec3 domain_min = glm::vec3(-1e30f), glm::vec3 domain_max = glm::vec3(1e30f));

// After the caller permuted its particle data by grid.order (new index e = old index order[e]),
// makes the grid describe the permuted data (order becomes the identity).
void markGridReordered(NeighborGrid& grid);

// Compressed neighbour lists: neighbours of i are indices[offsets[i] .. offsets[i+1]), each j != i
// with |x_i - x_j| < radius (radius <= grid.cell_size), in a fixed order (cell by cell, then by
// sorted entry), identical for every thread count.
struct NeighborLists {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> indices;
  static constexpr std::uint32_t kSlots = 48;
  std::vector<std::uint32_t> counts;  // scratch
  std::vector<std::uint32_t> slots;   // scratch: kSlots per particle
};

void findNeighbors(const NeighborGrid& grid, std::span<const glm::vec3> positions, float radius,
                   NeighborLists& lists);

}  // namespace fluid
