#pragma once
// Procedural closed test meshes for fluid/collide tests, the accuracy table and the benchmark:
// sphere, torus, box, and the fountain basin (a lathed pot whose rim overhangs its cavity).

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
