// Every way to draw the water, one line each (water_backend.hpp); the order is the overlay's.
#include "engine/fluid_render/water_backend.hpp"

#include <array>
#include <vector>

namespace engine {

// Each backend's file defines its desc (fluid_render.cpp, screen_space.cpp, raycast.cpp, voxel.cpp).
const WaterBackendDesc& meshWaterBackend();
const WaterBackendDesc& screenSpaceWaterBackend();
const WaterBackendDesc& raycastWaterBackend();
const WaterBackendDesc& voxelWaterBackend();

std::span<const WaterBackendDesc* const> waterBackends() {
  static const std::array kBackends = {
      &meshWaterBackend(),
      &screenSpaceWaterBackend(),
      &raycastWaterBackend(),
      &voxelWaterBackend(),
  };
  return kBackends;
}

const WaterBackendDesc* findWaterBackend(std::string_view name) {
  for (const WaterBackendDesc* desc : waterBackends())
    if (desc->name == name) return desc;
  return nullptr;
}

std::span<const std::string_view> waterBackendNames() {
  static const std::vector<std::string_view> names = [] {
    std::vector<std::string_view> out;
    for (const WaterBackendDesc* desc : waterBackends()) out.push_back(desc->name);
    return out;
  }();
  return names;
}

}  // namespace engine
