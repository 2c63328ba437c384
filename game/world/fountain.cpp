#include "game/world/fountain.hpp"

#include "game/world/collider_model.hpp"

#include <algorithm>
#include <cfloat>
#include <chrono>

namespace game {
namespace {

// The intersection of the collider's ortho maps' view volumes (world space = collider space):
// outside any one of them that map votes "far outside" or beyond its margin ring.
fluid::Bounds orthoReachBox(const fluid::DepthMapCollider& collider) {
  fluid::Bounds box{glm::vec3(-FLT_MAX), glm::vec3(FLT_MAX)};
  for (const fluid::DepthMap& map : collider.maps()) {
    if (map.format == fluid::DepthMapFormat::cube8) continue;  // inside the ortho volumes (Kolb §4.1)
    const glm::mat4 to_collider = glm::inverse(map.collider_to_map);
    glm::vec3 lo(FLT_MAX), hi(-FLT_MAX);
    for (int corner = 0; corner < 8; ++corner) {
      const glm::vec4 q((corner & 1) ? 1.0f : 0.0f, (corner & 2) ? 1.0f : 0.0f, (corner & 4) ? 1.0f : 0.0f, 1.0f);
      const glm::vec3 p(to_collider * q);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    box.lo = glm::max(box.lo, lo);
    box.hi = glm::min(box.hi, hi);
  }
  return box;
}

}  // namespace

bool loadLevelColliders(const std::filesystem::path& content_dir, const std::string& level, LevelColliders& out,
                        std::string& error) {
  const auto start = std::chrono::steady_clock::now();
  out = LevelColliders{};
  std::vector<fluid::LevelColliderEntry> entries;
  const std::filesystem::path manifest = content_dir / "colliders" / (level + ".colliders");
  if (const fluid::CacheStatus st = fluid::readLevelColliders(manifest, entries); !st.ok()) {
    error = st.error;
    return false;
  }
  if (const fluid::CacheStatus st = fluid::loadLevelColliders(content_dir, level, colliderModelLoader(),
                                                              fluid::CachePolicy::load_or_bake, out.parts);
      !st.ok()) {
    error = st.error;
    return false;
  }
  if (out.parts.size() != entries.size()) {
    error = manifest.string() + ": lists " + std::to_string(entries.size()) + " colliders, loaded " +
            std::to_string(out.parts.size());
    return false;
  }
  for (std::size_t k = 0; k < out.parts.size(); ++k) {
    out.reach_boxes.push_back(orthoReachBox(out.parts[k].collider));
    out.margins.push_back(entries[k].recipe.margin);
  }
  out.load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return true;
}

bool ensureLevelColliders(const std::filesystem::path& content_dir, const std::string& level,
                          std::shared_ptr<const LevelColliders>& slot, std::string& error) {
  if (slot) {
    if (slot->level == level) return true;
    error = "the colliders of level '" + slot->level + "' are loaded, not those of '" + level + "'";
    return false;
  }
  auto loaded = std::make_shared<LevelColliders>();
  if (!loadLevelColliders(content_dir, level, *loaded, error)) return false;
  loaded->level = level;
  slot = std::move(loaded);
  return true;
}

bool ensureFountainColliders(const std::filesystem::path& content_dir, std::shared_ptr<const LevelColliders>& slot,
                             std::string& error) {
  return ensureLevelColliders(content_dir, "fountain", slot, error);
}

std::shared_ptr<const fluid::SignedDistanceShape> culledPart(const std::shared_ptr<const LevelColliders>& level,
                                                             std::size_t k, float support) {
  const float grow = std::max(0.0f, support - level->margins[k]);
  fluid::Bounds box = level->reach_boxes[k];
  box.lo -= glm::vec3(grow);
  box.hi += glm::vec3(grow);
  // The collider lives in `level`: the alias keeps the whole level alive while the shape is.
  std::shared_ptr<const fluid::DepthMapCollider> inner(level, &level->parts[k].collider);
  fluid::ReachGridDesc grid;
  grid.reach = support;
  return std::make_shared<fluid::ReachCulledCollider>(std::move(inner), box, grid);
}

}  // namespace game
