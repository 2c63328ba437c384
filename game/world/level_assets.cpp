#include "game/world/level_assets.hpp"

#include "engine/assets/assets.hpp"

namespace game {

bool loadLevelAssets(const std::filesystem::path& content_dir, LevelAssets& out, std::string& error) {
  struct MeshJob {
    const char* file;
    engine::GpuMesh* target;
  };
  const MeshJob meshes[] = {
      {"ground.obj", &out.ground}, {"basin.obj", &out.basin}, {"statue.obj", &out.statue}, {"crate.obj", &out.crate}};
  for (const MeshJob& job : meshes) {
    engine::MeshData data;
    if (!engine::loadMesh(content_dir / "models" / job.file, data, error)) return false;
    *job.target = engine::uploadMesh(data);
  }
  struct TextureJob {
    const char* file;
    engine::GpuTexture* target;
  };
  const TextureJob textures[] = {{"paving.png", &out.paving}, {"stone.png", &out.stone}, {"crate.png", &out.wood}};
  for (const TextureJob& job : textures) {
    engine::ImageData image;
    if (!engine::loadImage(content_dir / "textures" / job.file, image, error)) return false;
    *job.target = engine::uploadTexture(image);
  }
  return true;
}

void submitLevel(const LevelAssets& assets, engine::FrameBatches& frame) {
  engine::DrawItem ground;
  ground.mesh = &assets.ground;
  ground.texture = &assets.paving;
  ground.specular = 0.05f;
  ground.casts_shadow = false;
  frame.opaque.push_back(ground);
  engine::DrawItem basin;
  basin.mesh = &assets.basin;
  basin.texture = &assets.stone;
  basin.specular = 0.2f;
  frame.opaque.push_back(basin);
  engine::DrawItem statue = basin;
  statue.mesh = &assets.statue;
  statue.tint = glm::vec3(0.95f, 0.97f, 1.0f);
  frame.opaque.push_back(statue);
}

}  // namespace game
