#pragma once
// The fountain level: its dimensions (nozzle, drains, the SPH domain) and its baked depth-map
// colliders (content/colliders/fountain.colliders: ground, basin and statue baked from the models
// the renderer draws, Kolb et al. 2004 §4; fluid/collide/collider_cache.hpp). The SPH boundary,
// the GPU sprites and the soak checks all use that one baked data.
// The numbers below drive scripts/generate_content.py (basin.obj, statue.obj): keep them in sync.
// Units: metres, y up, fountain centred on the origin.

#include "fluid/collide/collider_cache.hpp"
#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace game {

struct FountainGeometry {
  float basin_outer_radius = 3.2f;
  float basin_inner_radius = 2.9f;
  float basin_wall_top = 0.7f;
  float basin_floor = 0.2f;
  // Statue (a column with a dish and a spire), as capped cylinders.
  float plinth_radius = 0.6f;
  float plinth_top = 0.4f;
  float column_radius = 0.45f;  // plinth to dish
  float column_top = 1.42f;
  float dish_radius = 1.05f;
  float dish_bottom = 1.32f;
  float dish_rim_top = 1.62f;
  float dish_inner_radius = 0.92f;
  float dish_floor = 1.55f;
  float spire_radius = 0.2f;
  float spire_top = 2.45f;
  glm::vec3 nozzle{0.0f, 2.5f, 0.0f};  // where the jet leaves the spire
};

// A level's baked colliders, static (collider space = world space), in manifest order.
struct LevelColliders {
  std::string level;  // the level's name (content/colliders/LEVEL.colliders)
  std::vector<fluid::CachedCollider> parts;
  // Per part: the box (world space) outside which the part is farther than its bake margin
  // from any point of its model: the intersection of its ortho maps' view volumes, which
  // recipeMapSpecs grows by the margin beyond the model's bounds.
  std::vector<fluid::Bounds> reach_boxes;
  std::vector<float> margins;  // per part: the recipe's margin (m)
  double load_ms = 0.0;
};

// Loads CONTENT/colliders/LEVEL.colliders (re-baking a stale or missing file, CachePolicy::
// load_or_bake). False + error naming the file on failure.
bool loadLevelColliders(const std::filesystem::path& content_dir, const std::string& level, LevelColliders& out,
                        std::string& error);
// `level`'s colliders, loaded once into `slot` (EffectLinks::colliders): a no-op when it already
// holds that level's, an error naming both when it holds another level's.
bool ensureLevelColliders(const std::filesystem::path& content_dir, const std::string& level,
                          std::shared_ptr<const LevelColliders>& slot, std::string& error);
// ensureLevelColliders for the fountain level (the SPH water's basin and statue).
bool ensureFountainColliders(const std::filesystem::path& content_dir, std::shared_ptr<const LevelColliders>& slot,
                             std::string& error);

// Part `k` of `level` as a shape that answers within `support` of the surface
// (fluid::ReachCulledCollider with reach = support over the part's reach box grown by
// max(0, support - margin)): points outside the box or in a grid cell the maps place at least
// `support` away answer {FLT_MAX, invalid}, "beyond reach", without touching the maps; the SPH
// solver treats that like any distance >= support (no boundary volume, no collision). So water far
// from a part never pays for its maps. Shares the collider with `level`.
std::shared_ptr<const fluid::SignedDistanceShape> culledPart(const std::shared_ptr<const LevelColliders>& level,
                                                             std::size_t k, float support);

}  // namespace game
