#pragma once
// The GPU copies of the level's models and textures (content/models, content/textures): the
// fountain's ground, basin and statue, drawn in every scene, and the crate model the
// rigid_bodies effect draws its bodies with. Loaded by runScene with the GL context current.

#include "engine/render/frame.hpp"
#include "engine/render/renderer.hpp"

#include <filesystem>
#include <string>

namespace game {

struct LevelAssets {
  engine::GpuMesh ground, basin, statue, crate;
  engine::GpuTexture paving, stone, wood;
};

// False + error naming the missing or broken file.
bool loadLevelAssets(const std::filesystem::path& content_dir, LevelAssets& out, std::string& error);

// The level's static meshes, first in the frame's opaque list.
void submitLevel(const LevelAssets& assets, engine::FrameBatches& frame);

}  // namespace game
