#pragma once
// The first water surface along each pixel's ray, read back from a particle-direct renderer after
// its draw: the world point and the world normal that its shading used. For measuring what a
// renderer shows (docs/appearance.md's flat-pool normals), not for drawing.
//   raycast:      the cast's hit texture (outward normal, distance along the pixel ray);
//   voxel:        the first span's filtered entry depth and its Sobel normal (Zirr & Dachsbacher
//                 2015 §3.3-3.4);
//   screen_space: the filtered linear depth, with the normal the composite pass builds from it
//                 (the smaller one-sided difference per axis).
// Pixels are bottom-up rows (GL's order), index y * width + x.
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "engine/fluid_render/voxel.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace engine {

struct FirstSurface {
  int width = 0, height = 0;
  std::vector<std::uint8_t> hit;  // 1 where the ray meets water
  std::vector<glm::vec3> point;   // world position of the hit (0 where none)
  std::vector<glm::vec3> normal;  // world normal, unit, facing the eye (0 where none)
};

void readRaycastFirstSurface(const RaycastRenderer& renderer, const FluidCamera& camera, FirstSurface& out);
void readVoxelFirstSurface(const VoxelRenderer& renderer, const FluidCamera& camera, FirstSurface& out);
void readScreenSpaceFirstSurface(const ScreenSpaceRenderer& renderer, const FluidCamera& camera, FirstSurface& out);

}  // namespace engine
