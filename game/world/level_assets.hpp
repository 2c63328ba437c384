#pragma once
// The GPU copies of the level's models and textures (content/models, content/textures): the models
// of the scene's level (scene.level: the fountain's ground, basin and statue; the blob monster's
// street, sewer, grate and wall), drawn in every frame, the crate model the rigid_bodies effect
// draws its bodies with, the sphere the explosives draw their charges with, and the blob's tentacle skin (the blob
// effect hands it to the goo pass). Loaded by runScene with the GL context current.

#include "engine/render/frame.hpp"
#include "engine/render/renderer.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace game {

// One model of the level as drawn: its mesh, texture and material (the model's own coordinates are
// world coordinates, as the colliders baked from the same file).
struct LevelModel {
  engine::GpuMesh mesh;
  const engine::GpuTexture* texture = nullptr;
  glm::vec3 tint{1.0f};
  float specular = 0.15f;
  bool casts_shadow = true;
};

struct LevelAssets {
  std::vector<LevelModel> models;  // the level's models, in draw order
  engine::GpuMesh crate;
  engine::GpuMesh charge;  // the explosives' charge: a unit-diameter sphere
  engine::GpuTexture paving, stone, wood;
  engine::GpuTexture blob_tentacle;  // loaded for the blob_monster level only
};

// Loads the models of `level` (a scene.level choice) and the shared textures and crate. False +
// error naming the missing or broken file, or the unknown level.
bool loadLevelAssets(const std::filesystem::path& content_dir, std::string_view level, LevelAssets& out,
                     std::string& error);

// The level's static meshes, first in the frame's opaque list.
void submitLevel(const LevelAssets& assets, engine::FrameBatches& frame);

}  // namespace game
