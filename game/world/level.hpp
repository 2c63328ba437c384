#pragma once
// The levels a scene can name (scene.level): each is a list of models under content/models, in world
// coordinates, drawn by the renderer (level_assets.hpp), made static Bullet meshes where `solid`
// (rigid_bodies.hpp; the ground is Bullet's plane y = 0 in every level), and baked into the particle
// colliders listed in content/colliders/LEVEL.colliders from the same files. GL-free.

#include <glm/vec3.hpp>

#include <span>
#include <string_view>

namespace game {

enum class LevelSkin { paving, stone };

struct LevelModelDesc {
  const char* file;  // under content/models
  LevelSkin skin;
  glm::vec3 tint;
  float specular;
  bool casts_shadow;
  bool solid;  // a static Bullet mesh (the crates land on it)
};

// The models of `level`, in draw order; empty for a level the game does not know.
std::span<const LevelModelDesc> levelModels(std::string_view level);

}  // namespace game
