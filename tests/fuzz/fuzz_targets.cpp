// Fuzz targets of every parser that reads user files (see fuzz_targets.hpp).
#include "fuzz_targets.hpp"

#include "fluid/collide/collide.hpp"
#include "fluid/collide/mesh_checks.hpp"
#include "fluid/io/particle_io.hpp"
#include "game/world/collider_model.hpp"
#include "game/scene/scene_config.hpp"

#include "fluid/core/fnv1a.hpp"
#include <algorithm>
#include <array>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <vector>

namespace fuzz {
namespace {

// A rejection is one readable line or a few: longer means file content is being echoed.
constexpr std::size_t kMaxMessage = 1000;

std::string text(std::span<const std::uint8_t> input) { return {input.begin(), input.end()}; }

// Skips digits at `at`; true when there was at least one.
bool digits(const std::string& s, std::size_t& at) {
  const std::size_t start = at;
  while (at < s.size() && std::isdigit(static_cast<unsigned char>(s[at]))) ++at;
  return at > start;
}

std::string rejection(const std::string& error, const std::string& why) {
  return why + ": \"" + error.substr(0, 300) + "\"";
}

// ---- particle files (fluid/io) --------------------------------------------------------

// "NAME:LINE: ..." (text) or "NAME: byte OFFSET ..." (binary data).
bool namesParticlePlace(const std::string& error, const std::string& name) {
  if (error.rfind(name, 0) != 0) return false;
  std::size_t at = name.size();
  if (error.compare(at, 7, ": byte ") == 0) {
    at += 7;
    return digits(error, at);
  }
  if (at >= error.size() || error[at] != ':') return false;
  ++at;
  return digits(error, at) && error.compare(at, 2, ": ") == 0;
}

std::string checkParticles(std::span<const std::uint8_t> input, const std::string& format) {
  const std::string name = "fuzz." + format;
  fluid::ParticlePositions particles;
  const fluid::IoStatus status = fluid::parseParticleText(text(input), format, name, particles);
  if (status.ok()) {
    // The shortest particle is 3 bytes (binary PLY, char x y z; text "0 0 0" is more).
    if (particles.size() > input.size() / 3 + 1) return "accepted more particles than the bytes can hold";
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const glm::vec3 p = particles.at(i);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        return "accepted particle " + std::to_string(i) + " with a non-finite coordinate";
    }
    return {};
  }
  if (!particles.empty()) return rejection(status.error, "rejected but left particles behind");
  if (!namesParticlePlace(status.error, name)) return rejection(status.error, "rejection names no file:line or byte");
  if (status.error.size() > kMaxMessage) return rejection(status.error, "rejection message too long");
  return {};
}

std::string checkXyz(std::span<const std::uint8_t> input) { return checkParticles(input, "xyz"); }
std::string checkCsv(std::span<const std::uint8_t> input) { return checkParticles(input, "csv"); }
std::string checkPly(std::span<const std::uint8_t> input) { return checkParticles(input, "ply"); }

// ---- scenes (game/scene, through the schema) ------------------------------------------

// Every value of an accepted scene is what the schema allows.
std::string checkSection(const game::SectionConfig& section) {
  const game::SectionSpec* spec = game::findSection(section.name);
  if (spec == nullptr) return "accepted unknown section " + section.name;
  for (const game::ParamSpec& param : spec->params) {
    const auto found = section.params.find(param.key);
    if (found == section.params.end()) return "accepted scene lacks " + section.name + "." + std::string(param.key);
    const game::ParamValue& value = found->second;
    auto in_range = [&](double v) { return std::isfinite(v) && v >= param.min && v <= param.max; };
    const std::string where = section.name + "." + std::string(param.key);
    switch (param.type) {
      case game::ParamType::number:
      case game::ParamType::integer:
        if (!in_range(value.number)) return "accepted " + where + " out of range";
        if (param.type == game::ParamType::integer && value.number != std::floor(value.number))
          return "accepted non-integer " + where;
        break;
      case game::ParamType::vec3:
        for (int i = 0; i < 3; ++i) {
          if (!in_range(value.vec[i])) return "accepted " + where + " component out of range";
        }
        break;
      case game::ParamType::text:
        if (!param.choices.empty() &&
            std::find(param.choices.begin(), param.choices.end(), value.text) == param.choices.end())
          return "accepted " + where + " outside its choices";
        break;
      case game::ParamType::boolean:
        break;
    }
  }
  return {};
}

std::string checkScene(const game::SceneConfig& scene) {
  if (std::string e = checkSection(scene.scene); !e.empty()) return e;
  if (std::string e = checkSection(scene.camera); !e.empty()) return e;
  for (const game::SectionConfig& effect : scene.effects) {
    if (std::string e = checkSection(effect); !e.empty()) return e;
  }
  return {};
}

std::string checkSceneJson(std::span<const std::uint8_t> input) {
  const std::string label = "fuzz.json";
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text(input), label, scene);
  if (status.ok()) return checkScene(scene);
  // "FILE: invalid JSON...line L, column C..." or "FILE: key.path: ..." (or "the top level").
  const std::string& e = status.error;
  if (e.rfind(label + ": ", 0) != 0) return rejection(e, "rejection does not start with the file");
  const std::size_t place_end = e.find(": ", label.size() + 2);
  const bool json_error = e.compare(label.size() + 2, 12, "invalid JSON") == 0;
  const bool top_level = e.compare(label.size() + 2, 13, "the top level") == 0;
  if (json_error ? e.find("line ") == std::string::npos : place_end == std::string::npos && !top_level)
    return rejection(e, "rejection names no line or key");
  if (e.size() > kMaxMessage) return rejection(e, "rejection message too long");
  return {};
}

// A scene with every effect listed, all defaults: --set can reach every key.
const game::SceneConfig& everyEffectScene() {
  static const game::SceneConfig scene = [] {
    std::string json = R"({"effects": {)";
    bool first = true;
    for (const game::SectionSpec& spec : game::sceneSchema()) {
      if (!spec.is_effect) continue;
      json += (first ? "\"" : ", \"") + std::string(spec.name) + "\": {}";
      first = false;
    }
    json += "}}";
    game::SceneConfig parsed;
    (void)game::parseSceneText(json, "every_effect.json", parsed);
    return parsed;
  }();
  return scene;
}

std::string checkSceneSet(std::span<const std::uint8_t> input) {
  game::SceneConfig scene = everyEffectScene();
  const std::string assignment = text(input);
  const game::SceneStatus status = game::applyOverride(scene, assignment);
  if (status.ok()) return checkScene(scene);
  // The place is the --set argument itself, quoted first.
  if (status.error.rfind("--set " + assignment + ": ", 0) != 0)
    return rejection(status.error, "rejection does not quote the --set argument");
  if (status.error.size() > assignment.size() + kMaxMessage) return rejection(status.error, "rejection too long");
  return {};
}

// ---- collider files (fluid/collide) -----------------------------------------------------

std::uint64_t fnv1a(std::span<const std::uint8_t> bytes) { return fluid::fnv1a64(bytes.data(), bytes.size()); }

std::string checkCollider(std::span<const std::uint8_t> input) {
  // Rewrite the trailing FNV-1a checksum so mutations reach the fields behind it (a wrong
  // checksum alone is rejected first; the unit tests cover that).
  std::vector<std::uint8_t> bytes(input.begin(), input.end());
  if (bytes.size() >= 16) {
    const std::uint64_t sum = fnv1a(std::span(bytes).first(bytes.size() - 8));
    std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
  }
  const std::string name = "fuzz.fdm";
  fluid::DepthMapCollider collider;
  const fluid::FileStatus status = fluid::deserializeCollider(bytes, name, collider);
  if (!status.ok()) {
    std::size_t at = name.size() + 7;
    if (status.error.rfind(name + ": byte ", 0) != 0 || !digits(status.error, at) ||
        status.error.compare(at, 2, ": ") != 0)
      return rejection(status.error, "rejection names no byte offset");
    if (status.error.size() > kMaxMessage) return rejection(status.error, "rejection message too long");
    return {};
  }
  // A loaded collider answers every query with a finite distance and unit normal, or invalid.
  // Points a scene could hold (|p| <= 100): far beyond that, eq. (1) on a legal map can exceed
  // float range (depth_map.cpp's business, not the file's).
  const glm::vec3 points[] = {{0, 0, 0},    {0.5f, 0.5f, 0.5f}, {-0.3f, 0.2f, 0.9f},  {100, 0, 0},
                              {0, -100, 0}, {2, 2, 2},          {0.01f, -0.99f, 0.5f}};
  for (const glm::vec3& p : points) {
    const fluid::ColliderSample s = collider.sample(p);
    if (!s.valid) {
      if (s.distance != FLT_MAX) return "invalid sample with distance " + std::to_string(s.distance);
      continue;
    }
    if (!std::isfinite(s.distance) || !std::isfinite(s.normal.x) || !std::isfinite(s.normal.y) ||
        !std::isfinite(s.normal.z))
      return "loaded collider answers a non-finite sample";
  }
  return {};
}

// ---- models for bake-collider (assimp, OBJ) ---------------------------------------------

std::string checkModelObj(std::span<const std::uint8_t> input) {
  const std::string label = "fuzz.obj";
  game::ColliderModel model;
  std::string error;
  if (!game::loadColliderModelFromMemory(input, "obj", label, model, error)) {
    // "FILE:LINE: ..." (the OBJ pre-check), "FILE: mesh M vertex V ..." or "FILE: cannot load
    // model: <assimp's words>" (assimp names no place; the pre-check leaves it little to reject).
    std::size_t at = label.size() + 1;
    const bool line = error.rfind(label + ":", 0) == 0 && digits(error, at) && error.compare(at, 2, ": ") == 0;
    if (!line && error.rfind(label + ": ", 0) != 0) return rejection(error, "rejection does not name the file");
    if (error.size() > 4 * kMaxMessage) return rejection(error, "rejection message too long");
    return {};
  }
  if (fluid::firstBadVertex(model.positions) >= 0) return "accepted a vertex beyond the coordinate limit";
  for (std::uint32_t index : model.indices) {
    if (index >= model.positions.size()) return "accepted a triangle with a vertex out of range";
  }
  if (const std::string open = game::openMeshMessage(model, label); !open.empty() && open.rfind(label, 0) != 0)
    return rejection(open, "open-mesh message does not name the file");
  // Bake small models at a tiny resolution, as bake-collider would (it refuses open ones first).
  if (model.indices.size() / 3 > 5000) return {};
  const fluid::MeshView view{model.positions, model.indices};
  std::vector<fluid::MapSpec> specs;
  if (!fluid::parseMapSpec("axes,cube", fluid::meshBounds(view), 8, fluid::DepthMapFormat::front_back16, specs, error))
    return "parseMapSpec refused the default maps: " + error;
  fluid::DepthMapCollider collider;
  const fluid::BakeStatus baked = fluid::bakeDepthMaps(view, specs, {16, 1}, collider);
  if (!baked.ok()) return {};  // e.g. all triangles degenerate: a message, checked by the unit tests
  const fluid::Bounds b = fluid::meshBounds(view);
  for (const glm::vec3& p : {b.lo, b.hi, 0.5f * (b.lo + b.hi), glm::vec3(0.0f)}) {
    const fluid::ColliderSample s = collider.sample(p);
    if (s.valid && !(std::isfinite(s.distance) && std::isfinite(s.normal.x)))
      return "baked collider answers a non-finite sample";
  }
  return {};
}

constexpr std::array kTargets = {
    Target{"particles_xyz", "fluid::parseParticleText (xyz)", checkXyz},
    Target{"particles_csv", "fluid::parseParticleText (csv)", checkCsv},
    Target{"particles_ply", "fluid::parseParticleText (ASCII and binary ply)", checkPly},
    Target{"scene_json", "game::parseSceneText (JSON through the schema)", checkSceneJson},
    Target{"scene_set", "game::applyOverride (--set section.key=value)", checkSceneSet},
    Target{"collider_file", "fluid::deserializeCollider (checksum rewritten)", checkCollider},
    Target{"model_obj", "game::loadColliderModelFromMemory (assimp OBJ) + checkClosed + bake", checkModelObj},
};

}  // namespace

std::span<const Target> targets() { return kTargets; }

const Target* findTarget(std::string_view name) {
  for (const Target& target : kTargets) {
    if (target.name == name) return &target;
  }
  return nullptr;
}

}  // namespace fuzz
