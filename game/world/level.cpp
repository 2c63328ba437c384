#include "game/world/level.hpp"

namespace game {
namespace {

// The fountain's rows keep the pictures and the Bullet world of the fountain and crate_yard scenes
// as they were before levels were data.
constexpr LevelModelDesc kFountain[] = {
    {"ground.obj", LevelSkin::paving, glm::vec3(1.0f), 0.05f, false, false},
    {"basin.obj", LevelSkin::stone, glm::vec3(1.0f), 0.2f, true, true},
    {"statue.obj", LevelSkin::stone, glm::vec3(0.95f, 0.97f, 1.0f), 0.2f, true, true},
};
// The blob monster's street (scripts/generate_content.py): the grate is dark iron, the wall brick-ish.
constexpr LevelModelDesc kBlobMonster[] = {
    {"blob_street.obj", LevelSkin::paving, glm::vec3(0.8f, 0.8f, 0.85f), 0.05f, false, false},
    {"blob_sewer.obj", LevelSkin::stone, glm::vec3(0.55f, 0.55f, 0.6f), 0.1f, true, true},
    {"blob_grate.obj", LevelSkin::stone, glm::vec3(0.18f, 0.18f, 0.2f), 0.5f, true, true},
    {"blob_wall.obj", LevelSkin::stone, glm::vec3(0.85f, 0.6f, 0.5f), 0.1f, true, true},
    // The street's building fronts (scripts/blob_street_walls.py): the player and the monster keep to the street.
    {"blob_front_west.obj", LevelSkin::stone, glm::vec3(0.72f, 0.66f, 0.58f), 0.05f, true, true},
    {"blob_front_east.obj", LevelSkin::stone, glm::vec3(0.62f, 0.64f, 0.7f), 0.05f, true, true},
    {"blob_front_south.obj", LevelSkin::stone, glm::vec3(0.7f, 0.58f, 0.52f), 0.05f, true, true},
    {"blob_front_north.obj", LevelSkin::stone, glm::vec3(0.66f, 0.62f, 0.6f), 0.05f, true, true},
};

}  // namespace

std::span<const LevelModelDesc> levelModels(std::string_view level) {
  if (level == "fountain") return kFountain;
  if (level == "blob_monster") return kBlobMonster;
  return {};
}

}  // namespace game
