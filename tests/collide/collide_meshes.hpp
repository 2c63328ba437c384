#pragma once
// Procedural closed test meshes for fluid/collide tests, the accuracy table and the benchmark:
// sphere, torus, box, and the fountain basin (a lathed pot whose rim overhangs its cavity), and the
// concave models of the coverage tests (issue 32): bowl, mug with a handle, pipe, thin dish.

#include "fluid/collide/collide.hpp"

#include <cstdint>
#include <vector>

namespace collide_test {

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  fluid::MeshView view() const { return {positions, indices}; }
};

// UV sphere, radius r, `rings` latitude bands and `segments` longitude segments.
Mesh makeSphere(float radius, int rings, int segments);
// Torus around the z axis: major radius R, minor radius r.
Mesh makeTorus(float major_radius, float minor_radius, int major_segments, int minor_segments);
// Axis-aligned box [lo, hi] (12 triangles).
Mesh makeBox(glm::vec3 lo, glm::vec3 hi);
// Surface of revolution about z of a closed profile (r, z) that starts and ends on the axis.
Mesh makeLathe(const std::vector<glm::vec2>& profile, int segments);
// Surface of revolution about z of a closed loop profile (r, z) that does not touch the axis (the
// last point joins the first): a tube's wall.
Mesh makeLatheLoop(const std::vector<glm::vec2>& profile, int segments);
// Rewinds the triangles of `m` so that its signed volume is positive (outward = counter-clockwise).
void orientOutward(Mesh& m);
// Appends `part` (a separate closed component) to `m`.
void append(Mesh& m, const Mesh& part);

// Concave models of the coverage tests and table (closed, wound outward; sizes in metres, about the
// fountain's): each has a region the six axis maps cannot see.
// Spherical shell (outer radius 0.5, wall 0.05) cut at z = 0.2 above its centre: the rim overhangs
// the cavity.
Mesh makeBowl(int segments);
// Cup (outer radius 0.4, wall 0.05, floor 0.1, height 1) with a ring handle in the x-z plane beside
// it (major radius 0.25, minor 0.05, 0.03 from the wall: a separate closed component, so the exact
// distance's crossing parity stays right).
Mesh makeMug(int segments);
// Open tube along z: inner radius 0.25, outer 0.3, length 2 (z in [-1, 1]).
Mesh makePipe(int segments);
// Thin dish: radius 0.5, 0.015 thick, its top dished 0.06 deep.
Mesh makeDish(int segments);

// The fountain basin: outer radius 1.2, height 1, wall 0.2, inner cavity wider (r 1.0 at
// z 0.6) than the opening (r 0.8 at the rim z 1.0), floor at z 0.15. Points under the rim
// are invisible from above: a concave region the axis maps alone cannot see.
Mesh makeBasin(int segments);
// Cavity of the basin: centre and half size of the extra depth cube that captures it.
inline constexpr glm::vec3 kBasinCavityCenter{0.0f, 0.0f, 0.55f};
inline constexpr float kBasinCavityHalf = 1.02f;
// That cube: a LESS cube8 map (the cavity centre is outside the basin, so LESS calls it outside).
inline fluid::MapSpec basinCavityCube(int resolution) {
  return fluid::cubeMapSpec(kBasinCavityCenter, glm::vec3(kBasinCavityHalf), resolution, fluid::DepthCompare::less);
}

}  // namespace collide_test
