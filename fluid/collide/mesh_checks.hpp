#pragma once
// Checks a triangle mesh must pass before it is baked into a depth-map collider (defined in
// bake.cpp). A depth map stores, per texel, the first and last surface along its view
// direction (Kolb et al. 2004 §4.1): a hole lets a ray through the solid without a hit, so a
// point inside the model reads "outside". Closedness is therefore checked, not assumed.

#include "fluid/collide/collide.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace fluid {

// Largest |coordinate| a collider model may have, in collider units (metres in the game):
// 100 km. Beyond it float positions keep less than a centimetre and the maps' depth
// resolution is spread over absurd bounds; such a model is a broken file, not a scene.
inline constexpr float kMaxColliderCoordinate = 1.0e5f;

// Index of the first vertex (referenced or not) with a non-finite coordinate or one beyond
// `limit` in magnitude; -1 when all are fine.
std::int64_t firstBadVertex(std::span<const glm::vec3> positions, float limit = kMaxColliderCoordinate);

struct ClosedMeshReport {
  std::size_t welded_vertices = 0;           // distinct positions after welding coincident vertices
  std::size_t boundary_edges = 0;            // edges used by an odd number of triangles (usually one)
  glm::vec3 edge_from{0.0f}, edge_to{0.0f};  // the first boundary edge in triangle order
  bool closed() const { return boundary_edges == 0; }
};

// Welds vertices with bitwise-equal positions (after -0 == +0), drops triangles that collapse
// to an edge or a point, and counts the edges not shared by an even number of triangles.
// Indices must be in range (bakeDepthMaps checks that too).
ClosedMeshReport checkClosed(const MeshView& mesh);

}  // namespace fluid
