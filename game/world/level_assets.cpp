#include "game/world/level_assets.hpp"

#include "engine/assets/assets.hpp"
#include "game/world/level.hpp"

#include <utility>

namespace game {

bool loadLevelAssets(const std::filesystem::path& content_dir, std::string_view level, LevelAssets& out,
                     std::string& error) {
  const std::span<const LevelModelDesc> rows = levelModels(level);
  if (rows.empty()) {
    error = "scene.level = \"" + std::string(level) + "\": no such level (fountain, blob_monster)";
    return false;
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
  if (level == "blob_monster") {
    engine::ImageData image;
    if (!engine::loadImage(content_dir / "textures" / "blob_tentacle.png", image, error)) return false;
    out.blob_tentacle = engine::uploadTexture(image);
  }
  out.models.clear();
  out.models.reserve(rows.size());
  for (const LevelModelDesc& row : rows) {
    engine::MeshData data;
    if (!engine::loadMesh(content_dir / "models" / row.file, data, error)) return false;
    LevelModel model;
    model.mesh = engine::uploadMesh(data);
    model.texture = row.skin == LevelSkin::paving ? &out.paving : &out.stone;
    model.tint = row.tint;
    model.specular = row.specular;
    model.casts_shadow = row.casts_shadow;
    out.models.push_back(std::move(model));
  }
  engine::MeshData crate;
  if (!engine::loadMesh(content_dir / "models" / "crate.obj", crate, error)) return false;
  out.crate = engine::uploadMesh(crate);
  engine::MeshData charge;
  if (!engine::loadMesh(content_dir / "models" / "charge.obj", charge, error)) return false;
  out.charge = engine::uploadMesh(charge);
  return true;
}

void submitLevel(const LevelAssets& assets, engine::FrameBatches& frame) {
  for (const LevelModel& model : assets.models) {
    engine::DrawItem item;
    item.mesh = &model.mesh;
    item.texture = model.texture;
    item.tint = model.tint;
    item.specular = model.specular;
    item.casts_shadow = model.casts_shadow;
    frame.opaque.push_back(item);
  }
}

}  // namespace game
