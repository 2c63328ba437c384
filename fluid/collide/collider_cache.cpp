// Baked collider files as a cache of the level's models (collider_cache.hpp).
#include "fluid/collide/collider_cache.hpp"

#include "fluid/core/fnv1a.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

namespace fluid {
namespace {

bool modelHash(const std::filesystem::path& model, std::uint64_t& hash, std::string& error) {
  std::ifstream in(model, std::ios::binary);
  if (!in) {
    error = model.string() + ": cannot open the model";
    return false;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) {
    error = model.string() + ": read failed";
    return false;
  }
  hash = fnv1a64(bytes.data(), bytes.size());
  return true;
}

std::string hex(std::uint64_t value) {
  char text[20];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Why the file at `baked` cannot be used for (hash, recipe), or "" when it can.
std::string staleReason(const std::filesystem::path& baked, const ColliderSource& source, const ColliderSource& want) {
  if (source.empty()) return baked.string() + ": no source record (baked without one, or a version 1 file)";
  if (source.model_fnv1a64 != want.model_fnv1a64) {
    return baked.string() + ": model_fnv1a64 " + hex(source.model_fnv1a64) + " was baked from '" + source.model +
           "', the model '" + want.model + "' now hashes to " + hex(want.model_fnv1a64) + " (the model changed)";
  }
  if (source.recipe != want.recipe)
    return baked.string() + ": recipe '" + source.recipe + "', wanted '" + want.recipe + "' (bake parameters changed)";
  return {};
}

}  // namespace

std::string bakeRecipeText(const BakeRecipe& recipe) {
  char margin[32];
  const auto end = std::to_chars(margin, margin + sizeof margin - 1, recipe.margin).ptr;  // shortest round trip
  *end = '\0';
  return "baker=" + std::to_string(kBakerVersion) + " maps=" + recipe.maps +
         " res=" + std::to_string(recipe.resolution) + " format=" + formatName(recipe.format) +
         " normal_res=" + std::to_string(recipe.normal_resolution) + " margin=" + margin;
}

bool recipeMapSpecs(const BakeRecipe& recipe, const Bounds& bounds, std::vector<MapSpec>& out, std::string& error) {
  if (!(recipe.margin >= 0.0f && recipe.margin <= 1e5f)) {
    error = "margin " + std::to_string(recipe.margin) + " must be finite and >= 0";
    return false;
  }
  if (!parseMapSpec(recipe.maps, bounds, recipe.resolution, recipe.format, out, error)) return false;
  for (MapSpec& spec : out) {
    if (spec.kind != MapKind::ortho) continue;
    spec.margin = recipe.margin;
    // The margin ring plus two texels (the one-texel background border and a rounding texel).
    const float texels = 2.0f / static_cast<float>(std::max(recipe.resolution - 4, 1));
    spec.ortho.half_extent += glm::vec3(recipe.margin) * (1.0f + texels);
  }
  return true;
}

CacheStatus loadOrBakeCollider(const std::filesystem::path& model, const std::filesystem::path& baked,
                               const BakeRecipe& recipe, const ModelLoader& load_model, CachePolicy policy,
                               CachedCollider& out) {
  CacheStatus st;
  out.name = baked.stem().string();
  out.rebaked = false;
  out.rebake_reason.clear();
  ColliderSource want;
  want.model = model.filename().string();
  want.recipe = bakeRecipeText(recipe);
  if (!modelHash(model, want.model_fnv1a64, st.error)) return st;

  std::error_code ec;
  std::string reason;
  if (!std::filesystem::exists(baked, ec)) {
    reason = baked.string() + ": no such file";
  } else {
    const FileStatus loaded = loadCollider(baked, out.collider, &out.source);
    reason = loaded.ok() ? staleReason(baked, out.source, want) : loaded.error;
  }
  if (reason.empty()) return st;
  if (policy == CachePolicy::load_only) {
    st.error = reason + " (re-bake: fluiddemo bake-collider --level, or load with load_or_bake)";
    return st;
  }

  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  if (!load_model || !load_model(model, positions, indices, st.error)) {
    if (st.error.empty()) st.error = model.string() + ": no model loader";
    return st;
  }
  const MeshView view{positions, indices};
  std::vector<MapSpec> specs;
  if (!recipeMapSpecs(recipe, meshBounds(view), specs, st.error)) {
    st.error = model.string() + ": " + st.error;
    return st;
  }
  DepthMapCollider collider;
  BakeDesc desc;
  desc.normal_resolution = recipe.normal_resolution;
  if (const BakeStatus bake = bakeDepthMaps(view, specs, desc, collider); !bake.ok()) {
    st.error = model.string() + ": " + bake.error;
    return st;
  }
  if (const FileStatus saved = saveCollider(baked, collider, Overwrite::replace, want); !saved.ok()) {
    st.error = saved.error;
    return st;
  }
  out.collider = std::move(collider);
  out.source = want;
  out.rebaked = true;
  out.rebake_reason = reason;
  return st;
}

CacheStatus readLevelColliders(const std::filesystem::path& manifest, std::vector<LevelColliderEntry>& out) {
  CacheStatus st;
  out.clear();
  std::ifstream in(manifest);
  if (!in) {
    st.error = manifest.string() + ": cannot open the collider list";
    return st;
  }
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string where = manifest.string() + ":" + std::to_string(number) + ": ";
    if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    LevelColliderEntry e;
    std::string model, format, extra;
    if (!(fields >> e.name)) continue;  // blank or comment
    if (!(fields >> model >> e.recipe.maps >> e.recipe.resolution >> format >> e.recipe.normal_resolution)) {
      st.error = where + "expected NAME MODEL MAPS RES FORMAT NORMAL_RES [MARGIN]";
      return st;
    }
    if (!(fields >> e.recipe.margin)) {
      if (!fields.eof()) {
        st.error = where + "MARGIN is not a number";
        return st;
      }
      e.recipe.margin = 0.0f;
    }
    if (fields >> extra) {
      st.error = where + "unexpected '" + extra + "' after MARGIN";
      return st;
    }
    if (!parseFormat(format, e.recipe.format) || e.recipe.format == DepthMapFormat::cube8) {
      st.error = where + "FORMAT '" + format + "' unknown (expected float, fixed8 or front-back16)";
      return st;
    }
    if (e.recipe.resolution < 4 || e.recipe.resolution > 4096 || e.recipe.normal_resolution < 2 ||
        e.recipe.normal_resolution > 256 || !(e.recipe.margin >= 0.0f && e.recipe.margin <= 1e5f)) {
      st.error = where + "RES (4..4096), NORMAL_RES (2..256) or MARGIN (>= 0) out of range";
      return st;
    }
    for (char c : e.name)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
        st.error = where + "NAME '" + e.name + "' may hold letters, digits, '_' and '-' only";
        return st;
      }
    e.model = model;
    if (e.model.is_absolute() || model.find("..") != std::string::npos) {
      st.error = where + "MODEL '" + model + "' must be relative to the content directory, without '..'";
      return st;
    }
    out.push_back(std::move(e));
  }
  if (out.empty()) st.error = manifest.string() + ": no colliders listed";
  return st;
}

CacheStatus loadLevelColliders(const std::filesystem::path& content_dir, const std::string& level,
                               const ModelLoader& load_model, CachePolicy policy, std::vector<CachedCollider>& out) {
  out.clear();
  std::vector<LevelColliderEntry> entries;
  const std::filesystem::path dir = content_dir / "colliders";
  CacheStatus st = readLevelColliders(dir / (level + ".colliders"), entries);
  for (const LevelColliderEntry& e : entries) {
    if (!st.ok()) break;
    CachedCollider part;
    st = loadOrBakeCollider(content_dir / e.model, dir / (e.name + ".fdm"), e.recipe, load_model, policy, part);
    part.name = e.name;
    if (st.ok()) out.push_back(std::move(part));
  }
  if (!st.ok()) out.clear();
  return st;
}

}  // namespace fluid
