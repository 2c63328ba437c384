#pragma once
// Baked collider files as a cache of the level's models (issue 18, item 2): a collider is baked
// once from the same model file the renderer draws and stored with the model's FNV-1a hash and the
// bake parameters (ColliderSource, collide.hpp). Loading checks both and re-bakes when either
// changed, so an edited model never meets a stale collider.
//
// A level lists its colliders in CONTENT/colliders/LEVEL.colliders, one per line:
//   NAME  MODEL  MAPS  RES  FORMAT  NORMAL_RES  [MARGIN]
// NAME names the baked file CONTENT/colliders/NAME.fdm; MODEL is relative to CONTENT; MAPS is a
// --maps list (parseMapSpec), RES texels per side, FORMAT an ortho format name (formatName),
// NORMAL_RES the L1 normal index resolution, MARGIN (collider units, default 0) the silhouette
// margin of the ortho maps (MapSpec::margin). '#' starts a comment. fluid/ reads no model
// formats: the caller passes a ModelLoader (the game's is game::colliderModelLoader, assimp).

#include "fluid/collide/collide.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace fluid {

// What a bake is made of, besides the model. Its canonical text (bakeRecipeText) is stored in the
// file and compared on load.
struct BakeRecipe {
  std::string maps = "axes";
  int resolution = 256;
  DepthMapFormat format = DepthMapFormat::front_back16;
  int normal_resolution = 256;
  float margin = 0.0f;  // collider units, every ortho map (MapSpec::margin)
};
// Version of what bakeDepthMaps writes for a given mesh and maps: raise it whenever a change to
// the baker changes texels, so every cached file is re-baked (3: the margin ring and its flag).
inline constexpr int kBakerVersion = 3;
// "baker=3 maps=axes res=256 format=front-back16 normal_res=256 margin=0.16" (margin: the
// shortest text that reads back as the same float).
std::string bakeRecipeText(const BakeRecipe& recipe);
// The maps of `recipe` for a mesh with `bounds`: parseMapSpec, then every ortho map gets the
// margin and its view volume grows by it on every side (so the margin ring is inside the volume).
bool recipeMapSpecs(const BakeRecipe& recipe, const Bounds& bounds, std::vector<MapSpec>& out, std::string& error);

// Reads a model file into triangles (positions + 3 indices per triangle); false with a message
// naming the file on failure.
using ModelLoader = std::function<bool(const std::filesystem::path& model, std::vector<glm::vec3>& positions,
                                       std::vector<std::uint32_t>& indices, std::string& error)>;

enum class CachePolicy {
  load_or_bake,  // a missing, unreadable or stale file is re-baked and rewritten (first use)
  load_only,     // a missing, unreadable or stale file is an error (checks that the shipped files are fresh)
};

struct CachedCollider {
  std::string name;  // the manifest's NAME, or the baked file's stem
  DepthMapCollider collider;
  ColliderSource source;
  bool rebaked = false;
  std::string rebake_reason;  // why the file was not used as it was ("" when it was)
};

struct CacheStatus {
  std::string error;  // empty = success; names the file, the line or the field
  bool ok() const { return error.empty(); }
};

// The collider baked from `model` by `recipe`, read from `baked` when the file is a valid
// collider recorded with the model's current hash and the same recipe; otherwise (load_or_bake)
// baked again and written to `baked` (atomically), the reason in out.rebake_reason.
CacheStatus loadOrBakeCollider(const std::filesystem::path& model, const std::filesystem::path& baked,
                               const BakeRecipe& recipe, const ModelLoader& load_model, CachePolicy policy,
                               CachedCollider& out);

struct LevelColliderEntry {
  std::string name;
  std::filesystem::path model;  // relative to the content directory
  BakeRecipe recipe;
};
// Parses CONTENT/colliders/LEVEL.colliders (format above); errors name "FILE:LINE".
CacheStatus readLevelColliders(const std::filesystem::path& manifest, std::vector<LevelColliderEntry>& out);

// Every collider of `level` (e.g. "fountain": ground, basin and statue), in manifest order, from
// CONTENT/colliders, re-baked where stale (load_or_bake). This is what the game calls when a
// level is built; colliders are static, collider space = world space (the models' own space).
CacheStatus loadLevelColliders(const std::filesystem::path& content_dir, const std::string& level,
                               const ModelLoader& load_model, CachePolicy policy, std::vector<CachedCollider>& out);

}  // namespace fluid
