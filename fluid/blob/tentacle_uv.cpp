// u around the tentacles (see fluid/blob/tentacle_uv.hpp for why this is a pass after meshing).
#include "fluid/blob/tentacle_uv.hpp"

#include "fluid/core/finite.hpp"
#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <cmath>

namespace fluid {
namespace {

// The tentacle particles bucketed in a uniform grid (counting sort by cell), so each vertex
// looks at the particles of the 27 cells around it instead of all of them.
struct ChainGrid {
  std::vector<std::uint32_t> chain;   // particle ids, in the order the brute force would visit them
  std::vector<std::uint32_t> start;   // per cell: first slot in `sorted` (cells + 1 entries)
  std::vector<std::uint32_t> sorted;  // positions in `chain`, by cell, each cell in chain order
  glm::vec3 lo{0.0f};
  glm::ivec3 dims{1};
  float cell = 1.0f;

  glm::ivec3 cellOf(glm::vec3 p) const {
    return glm::clamp(glm::ivec3(glm::floor((p - lo) / cell)), glm::ivec3(0), dims - 1);
  }
  std::size_t index(glm::ivec3 c) const {
    return (static_cast<std::size_t>(c.z) * static_cast<std::size_t>(dims.y) + static_cast<std::size_t>(c.y)) *
               static_cast<std::size_t>(dims.x) +
           static_cast<std::size_t>(c.x);
  }
};

void buildChainGrid(ChainGrid& g, std::span<const glm::vec3> positions, float cell) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (std::uint32_t i : g.chain) lo = glm::min(lo, positions[i]), hi = glm::max(hi, positions[i]);
  g.lo = lo;
  // At most 64 cells a side: a body blown across the street still gets a small grid (coarser cells
  // only mean more candidates, never a different answer).
  const glm::vec3 span = hi - lo;
  g.cell = std::max(cell, std::max({span.x, span.y, span.z}) / 64.0f);
  g.dims = glm::max(glm::ivec3(glm::floor(span / g.cell)) + 1, glm::ivec3(1));
  const std::size_t cells = static_cast<std::size_t>(g.dims.x) * g.dims.y * g.dims.z;
  g.start.assign(cells + 1, 0);
  for (std::uint32_t i : g.chain) ++g.start[g.index(g.cellOf(positions[i])) + 1];
  for (std::size_t c = 0; c < cells; ++c) g.start[c + 1] += g.start[c];
  g.sorted.resize(g.chain.size());
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (std::uint32_t k = 0; k < g.chain.size(); ++k) g.sorted[fill[g.index(g.cellOf(positions[g.chain[k]]))]++] = k;
}

}  // namespace

void blobTentacleU(SurfaceMesh& mesh, const BlobWorld& world, glm::vec3 origin, float min_share) {
  blobTentacleU(mesh, world.particles, world.target.tentacle_particles, world.params.spacing, origin, min_share);
}

void blobTentacleU(SurfaceMesh& mesh, const BlobParticles& parts, std::span<const std::vector<std::uint32_t>> tentacles,
                   float spacing, glm::vec3 origin, float min_share) {
  ChainGrid grid;
  for (const auto& chain : tentacles)
    grid.chain.insert(grid.chain.end(), chain.begin(), chain.end());
  if (grid.chain.empty() || mesh.attributes.size() != mesh.positions.size()) return;
  for (std::uint32_t i : grid.chain)
    if (!isFinite(parts.position[i])) return;
  // Cells of two spacings: a vertex with a tentacle share lies within the field cutoff (about two
  // spacings) of a tentacle particle, so its nearest one is almost always in the 27 cells around it.
  buildChainGrid(grid, parts.position, 2.0f * spacing);
  constexpr float kTwoPi = 6.28318530717958f;
  // Per vertex, independent: the result does not depend on the thread count.
  par::parallelFor(par::Range<std::size_t>(0, mesh.positions.size(), 512), [&](const par::Range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      glm::vec4& attr = mesh.attributes[k];
      if (attr.z < min_share) continue;
      const glm::vec3 p = mesh.positions[k] + origin;
      // The nearest tentacle particle, ties to the first in chain order (as a scan of the chain
      // would pick). Exact: any particle closer than one cell lies in the 27 cells around p's, so
      // a best found closer than that is the best of all.
      std::uint32_t best_k = 0;
      float best_d2 = INFINITY;
      auto consider = [&](std::uint32_t chain_k) {
        const glm::vec3 d = p - parts.position[grid.chain[chain_k]];
        const float d2 = glm::dot(d, d);
        if (d2 < best_d2 || (d2 == best_d2 && chain_k < best_k)) best_d2 = d2, best_k = chain_k;
      };
      const glm::ivec3 c = grid.cellOf(p);
      const glm::ivec3 c_lo = glm::max(c - 1, glm::ivec3(0)), c_hi = glm::min(c + 1, grid.dims - 1);
      for (int z = c_lo.z; z <= c_hi.z; ++z)
        for (int y = c_lo.y; y <= c_hi.y; ++y)
          for (int x = c_lo.x; x <= c_hi.x; ++x) {
            const std::size_t cell = grid.index({x, y, z});
            for (std::uint32_t s = grid.start[cell]; s < grid.start[cell + 1]; ++s) consider(grid.sorted[s]);
          }
      // p outside the grid (clamped to its border cells) or nothing within a cell: scan them all.
      const glm::vec3 rel = (p - grid.lo) / grid.cell;
      const bool in_grid =
          glm::all(glm::greaterThanEqual(rel, glm::vec3(0.0f))) && glm::all(glm::lessThan(rel, glm::vec3(grid.dims)));
      const float sure = 0.99f * grid.cell;  // below one cell, with room for rounding
      if (!in_grid || !(best_d2 < sure * sure)) {
        best_d2 = INFINITY;
        for (std::uint32_t chain_k = 0; chain_k < grid.chain.size(); ++chain_k) consider(chain_k);
      }
      const std::uint32_t best = grid.chain[best_k];
      const glm::vec3 t = parts.tangent[best];
      const glm::vec3 n = parts.normal[best];
      const glm::vec3 rel_p = p - parts.position[best];
      const float angle = std::atan2(glm::dot(rel_p, glm::cross(t, n)), glm::dot(rel_p, n));  // (-pi, pi]
      float u = angle / kTwoPi + 0.5f;
      if (u >= 1.0f) u = 0.0f;
      attr.x = u;
    }
  });
}

}  // namespace fluid
