#pragma once
// Scenes are data: content/scenes/<name>.json lists the effects a scene uses, with their
// parameters. Only the listed effects' systems are ever constructed.
//
// File format:
//   {
//     "description": "free text",
//     "scene":   { "step_hz": 60, "substeps": 2, "seed": 1 },          // optional section
//     "camera":  { "position": [0, -12, 3], "yaw_degrees": 90, ... },   // optional section
//     "effects": { "rigid_bodies": { "crates": 6 }, "sprite_particles": {} }
//   }
// Every key is checked against the schema (effect_schema.cpp: the scene and camera rows, then one
// section per effect from its parameter table in game/effects/): unknown sections, effects or
// keys, wrong JSON types and out-of-range values are errors naming the file, the key path
// and the value. Keys left out take the schema default.
// Command-line overrides use the same validation: `--set section.key=value`, e.g.
// `--set sprite_particles.rate=900`, `--set camera.fov_degrees=70`, `--set scene.substeps=4`.

#include <glm/vec3.hpp>

#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace game {

enum class ParamType { number, integer, boolean, vec3, text };

struct ParamValue {
  ParamType type = ParamType::number;
  double number = 0.0;  // number and integer
  bool boolean = false;
  glm::vec3 vec{0.0f};
  std::string text;
};

struct ParamSpec {
  std::string_view key;
  ParamType type;
  double min = 0.0;  // range for number/integer (inclusive); each component for vec3
  double max = 0.0;
  ParamValue default_value;
  std::string_view doc;
  std::span<const std::string_view> choices = {};  // text: the only accepted values (empty = any)
  // Live keys take effect when the overlay edits them (Effect::applyLive re-reads only these);
  // fixed ones size or shape what the effect builds and take effect on a restart.
  bool live = true;
};

struct SectionSpec {
  std::string_view name;
  bool is_effect;  // effects are constructed only when listed; other sections always exist
  std::string_view doc;
  std::span<const ParamSpec> params;
};

// All sections and effects the game knows (game/scene/effect_schema.cpp), effects in registry
// order.
std::span<const SectionSpec> sceneSchema();
const SectionSpec* findSection(std::string_view name);

// One section's parameters after validation; every schema key is present.
struct SectionConfig {
  std::string name;
  std::map<std::string, ParamValue, std::less<>> params;

  // Typed getters; asking for a key the schema does not define is a programmer error (assert).
  double number(std::string_view key) const;
  int integer(std::string_view key) const;
  bool boolean(std::string_view key) const;
  glm::vec3 vec3(std::string_view key) const;
  const std::string& text(std::string_view key) const;
};

struct SceneConfig {
  std::string name;              // file stem, e.g. "fountain"
  std::filesystem::path source;  // the file it came from ("" if parsed from text)
  std::string description;
  SectionConfig scene;                 // "scene" section (step, substeps, seed)
  SectionConfig camera;                // "camera" section
  SectionConfig graphics;              // "graphics" section (quality preset, resolution scale): rendering only
  std::vector<SectionConfig> effects;  // listed effects only, in schema order

  bool has(std::string_view effect_name) const;
  const SectionConfig* effect(std::string_view effect_name) const;  // nullptr when not listed
  std::vector<std::string> effectNames() const;
};

// Empty error == success; the message names file, key path and value.
struct SceneStatus {
  std::string error;
  bool ok() const { return error.empty(); }
};

SceneStatus parseSceneText(const std::string& json_text, const std::string& file_label, SceneConfig& out);
SceneStatus loadSceneFile(const std::filesystem::path& path, SceneConfig& out);

// "section.key=value" with the value parsed by the key's type ("1,2,3" or "[1,2,3]" for vec3).
SceneStatus applyOverride(SceneConfig& scene, std::string_view assignment);

// Resolves "fountain" to <scenes_dir>/fountain.json, or accepts a path to a .json file.
// On an unknown name the error lists the available scenes.
SceneStatus resolveScene(std::string_view name_or_path, const std::filesystem::path& scenes_dir,
                         std::filesystem::path& out);
std::vector<std::string> availableScenes(const std::filesystem::path& scenes_dir);

}  // namespace game
