#pragma once
// Comparison extractors for fluid/surface (paper §7, Figure 7) and the test oracle.
// All use the same field, lattice (corners at integer multiples of S), inside rule (f > T) and
// case tables as marching slices, so on the same input they produce the same triangles.
//
//   dense      brute force: every corner of the particles' bounding lattice is evaluated by
//              splatting each particle (in (z, index) order) into two rolling slices, then
//              marching cubes over every cube. The oracle of the tests; also "the dense route".
//   blocked    approach 2: surface-following marching cubes per block (same margins and zero
//              boundary as marching slices; auto blocks of up to max(64, 12 ceil(Rc/S)) cubes,
//              since its full 3D corner cache per block grows with the cube of the block edge)
//              and a point-insert / 3x3x3-lookup particle grid with cells of size Rc.
//   hashed     approach 3: global surface-following marching cubes, corners in a hash map and
//              particles in a hashed grid of cell size Rc (no blocks, single thread).
// Output meshes are single index spaces; `dense` and `hashed` share every vertex (no seams).

#include "fluid/surface/marching_slices.hpp"

#include <memory>

namespace fluid {

enum class BaselineMethod { dense, blocked, hashed };

namespace detail {
struct BaselineState;
}

// Scratch reused across calls (like SurfaceExtractor). threads/order/exactSlabOrder in params
// are honoured by `blocked` (threads) and ignored by the others. SurfaceInput::stretch
// (anisotropic kernels) is summed by `dense` and `hashed` with the mesher's terms (the dense
// oracle of the anisotropic tests); `blocked` refuses it.
class BaselineExtractor {
 public:
  BaselineExtractor();
  ~BaselineExtractor();
  BaselineExtractor(BaselineExtractor&&) noexcept;
  BaselineExtractor& operator=(BaselineExtractor&&) noexcept;

  SurfaceStatus extract(BaselineMethod method, const SurfaceInput& input, const SurfaceParams& params,
                        SurfaceMesh& out);
  // Bytes of the corner store and of the particle lookup structure at the last call's peak.
  std::uint64_t cornerBytes() const;
  std::uint64_t particleBytes() const;

  std::unique_ptr<detail::BaselineState> state;
};

}  // namespace fluid
