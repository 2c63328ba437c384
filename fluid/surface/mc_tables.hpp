#pragma once
// Marching-cubes case tables, generated once from a face rule instead of typed in.
//
// Corner c of a cube has offset (c&1, (c>>1)&1, (c>>2)&1), the numbering of the paper's
// Algorithm 1 (corner_0 = (x,y,z), corner_1 = (x+1,y,z), corner_2 = (x,y+1,z), ... corner_7).
// Edge e runs from base corner kEdgeBase[e] along axis kEdgeAxis[e] (0=x, 1=y, 2=z); the base
// corner is the one holding the shared vertex index Ix/Iy/Iz of the paper's corner cache (§4).
//
// Face rule (why the mesh is watertight): on every cube face with two diagonal inside corners
// the inside corners are kept apart. The rule sees only the face's four corners, so the two
// cubes sharing a face cut it into the same segments, and every crossing edge is used by
// exactly two triangles across the whole lattice. Loops are fanned into triangles wound
// counter-clockwise seen from outside (lower field), i.e. outward normals.
//
// Back-to-front (paper §5): for each of the 8 view octants the triangles of each case are
// preprocessed into farthest-first order (centroid of edge midpoints along the octant's
// diagonal), so the per-cube order costs nothing at run time.

#include <array>
#include <cstdint>

namespace fluid::mc {

inline constexpr std::array<std::uint8_t, 12> kEdgeBase = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};
inline constexpr std::array<std::uint8_t, 12> kEdgeAxis = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};

struct CaseTable {
  std::uint8_t triangleCount = 0;        // 0..12
  std::uint16_t edgeMask = 0;            // bit e set when edge e is crossed
  std::uint8_t faceMask = 0;             // bit 2*axis+side set when that face is crossed
  std::array<std::uint8_t, 36> edges{};  // 3 edge ids per triangle, outward winding
  // The crossed edges in order of first use along `edges` (so resolving them in this order makes
  // vertices in the same order as walking `edges`), and each triangle corner as an index into it.
  std::uint8_t edgeCount = 0;
  std::array<std::uint8_t, 12> firstUse{};
  // The same edges as kEdgeBase[e] | kEdgeAxis[e] << 3 (what the vertex routine needs, without
  // two table lookups per edge).
  std::array<std::uint8_t, 12> firstCorner{};
  // 4 zero bytes of padding after the 36 slots: the AVX2 polygonizer reads them in groups of 8.
  std::array<std::uint8_t, 40> slot{};
};

struct Tables {
  // cases[octant][case]: octant bit a set when the view direction has a negative component on
  // axis a; octant 0 is also the plain order used when no view is given.
  std::array<std::array<CaseTable, 256>, 8> cases{};
};

// Built on first use (immutable afterwards; thread-safe static initialisation).
const Tables& tables();

// Case index: bit c set when corner c is inside (field > threshold).
}  // namespace fluid::mc
