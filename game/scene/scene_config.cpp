#include "game/scene/scene_config.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cassert>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace game {
namespace {

using Json = nlohmann::json;

std::string_view typeName(ParamType type) {
  switch (type) {
    case ParamType::number:
      return "a number";
    case ParamType::integer:
      return "an integer";
    case ParamType::boolean:
      return "true or false";
    case ParamType::vec3:
      return "an array of 3 numbers";
    case ParamType::text:
      return "a string";
  }
  return "?";
}

// Appends ", item" (or "item" first). Written out because `"" + std::string` trips a GCC 12
// -Wrestrict false positive.
void appendListItem(std::string& list, std::string_view item) {
  if (!list.empty()) list += ", ";
  list += item;
}

// A JSON value as quoted in a message: scalars as JSON text (invalid UTF-8 replaced, at most
// 60 bytes), arrays and objects by their size only, so a message stays one readable line.
std::string describe(const Json& value) {
  if (value.is_array()) {
    if (value.size() <= 3 && std::all_of(value.begin(), value.end(), [](const Json& v) { return v.is_primitive(); })) {
      return value.dump(-1, ' ', false, Json::error_handler_t::replace);
    }
    return "an array of " + std::to_string(value.size()) + " items";
  }
  if (value.is_object()) return "an object with " + std::to_string(value.size()) + " keys";
  std::string text = value.dump(-1, ' ', false, Json::error_handler_t::replace);
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

// Text from the file as quoted in a message: control bytes as '?', at most `limit` bytes.
std::string printable(std::string_view text, std::size_t limit) {
  std::string out;
  for (char c : text.substr(0, limit)) out += static_cast<unsigned char>(c) < 0x20 ? '?' : c;
  if (text.size() > limit) out += "...";
  return out;
}

// A key from the file as quoted in a message.
std::string keyText(std::string_view key) { return printable(key, 60); }

// Records where a SAX parse stops, for the errors nlohmann reports without a position
// (out_of_range 406: a number too large for a double).
struct ErrorPosition : nlohmann::json_sax<Json> {
  std::size_t byte = 0;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception&) override {
    byte = position >= token.size() ? position - token.size() : 0;  // the start of the offending token
    return false;
  }
};

std::string lineAndColumn(const std::string& text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < std::min(byte, text.size()); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// nlohmann's message without its "[json.exception.parse_error.101] " tag, whole (position, what
// was expected), with only the token it quotes after "last read:" cut to 40 bytes (an unclosed
// string would quote the rest of the file). nlohmann words it
//   parse error at line L, column C: syntax error while parsing CONTEXT - MESSAGE[; last read: 'TOKEN'][; expected E]
std::string jsonErrorText(std::string_view what) {
  if (what.starts_with("[json.exception.")) {
    const std::size_t tag_end = what.find("] ");
    if (tag_end != std::string_view::npos) what.remove_prefix(tag_end + 2);
  }
  const std::size_t last = what.find("; last read: '");
  if (last == std::string_view::npos) return printable(what, 400);
  const std::size_t token_begin = last + 14;
  const std::size_t expected = what.rfind("'; expected ");
  const std::size_t token_end =
      expected != std::string_view::npos && expected >= token_begin ? expected : what.size() - 1;
  return printable(what.substr(0, token_begin), 400) +
         printable(what.substr(token_begin, token_end - token_begin), 40) + printable(what.substr(token_end), 200);
}

// The first key that appears twice in one object, as its dotted path ("scene.step_hz"). nlohmann
// keeps the last value of a repeated key without a word, so a scene that sets a key twice would
// silently lose the first value.
struct DuplicateKeys : nlohmann::json_sax<Json> {
  std::vector<std::vector<std::string>> objects;  // keys seen so far in each open object
  std::vector<std::string> path;                  // the key of each open object and array
  std::string pending_key;                        // the key whose value comes next
  std::string duplicate;                          // dotted path of the first repeated key
  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(); }
  bool start_array(std::size_t) override { return open(); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& name) override {
    std::vector<std::string>& seen = objects.back();
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) {
      for (const std::string& part : path) duplicate += part.empty() ? "" : part + ".";
      duplicate += name;
      return false;  // the first is enough
    }
    seen.push_back(name);
    pending_key = name;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

 private:
  bool value() {
    pending_key.clear();
    return true;
  }
  bool open() {
    path.push_back(pending_key);
    pending_key.clear();
    objects.emplace_back();
    return true;
  }
  bool close() {
    path.pop_back();
    objects.pop_back();
    return true;
  }
};

std::string formatNumber(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string rangeText(const ParamSpec& spec) {
  std::string text = "[";
  text += formatNumber(spec.min);
  text += ", ";
  text += formatNumber(spec.max);
  text += "]";
  return text;
}

// Prefix of every message: "file: key.path: ".
std::string at(const std::string& file, std::string_view key_path) {
  return file + ": " + std::string(key_path) + ": ";
}

std::string checkNumber(const ParamSpec& spec, double value, const std::string& where) {
  if (!std::isfinite(value)) return where + "value " + formatNumber(value) + " is not finite";
  if (spec.type == ParamType::integer && value != std::floor(value)) {
    return where + "value " + formatNumber(value) + " is not " + std::string(typeName(spec.type));
  }
  if (value < spec.min || value > spec.max) {
    return where + "value " + formatNumber(value) + " is out of range " + rangeText(spec);
  }
  return {};
}

// Converts one JSON value to the spec's type, with range checks.
std::string paramFromJson(const ParamSpec& spec, const Json& value, const std::string& where, ParamValue& out) {
  out = spec.default_value;
  const std::string got = " (got " + describe(value) + ")";
  switch (spec.type) {
    case ParamType::number:
    case ParamType::integer:
      if (!value.is_number()) return where + "expected " + std::string(typeName(spec.type)) + got;
      out.number = value.get<double>();
      return checkNumber(spec, out.number, where);
    case ParamType::boolean:
      if (!value.is_boolean()) return where + "expected " + std::string(typeName(spec.type)) + got;
      out.boolean = value.get<bool>();
      return {};
    case ParamType::text:
      if (!value.is_string()) return where + "expected " + std::string(typeName(spec.type)) + got;
      out.text = value.get<std::string>();
      if (!spec.choices.empty() &&
          std::find(spec.choices.begin(), spec.choices.end(), out.text) == spec.choices.end()) {
        std::string expected;
        for (std::string_view choice : spec.choices) appendListItem(expected, choice);
        return where + "value \"" + keyText(out.text) + "\" is not one of: " + expected;
      }
      return {};
    case ParamType::vec3: {
      if (!value.is_array() || value.size() != 3) return where + "expected " + std::string(typeName(spec.type)) + got;
      for (int i = 0; i < 3; ++i) {
        if (!value[static_cast<std::size_t>(i)].is_number())
          return where + "expected " + std::string(typeName(spec.type)) + got;
        const double component = value[static_cast<std::size_t>(i)].get<double>();
        if (std::string error = checkNumber(spec, component, where); !error.empty()) return error;
        out.vec[i] = static_cast<float>(component);
      }
      return {};
    }
  }
  return where + "unsupported type";
}

SectionConfig defaultSection(const SectionSpec& spec) {
  SectionConfig section;
  section.name = std::string(spec.name);
  for (const ParamSpec& param : spec.params) section.params.emplace(std::string(param.key), param.default_value);
  return section;
}

std::string knownKeys(const SectionSpec& spec) {
  std::string keys;
  for (const ParamSpec& param : spec.params) appendListItem(keys, param.key);
  return keys.empty() ? "(none)" : keys;
}

std::string knownEffects() {
  std::string names;
  for (const SectionSpec& spec : sceneSchema()) {
    if (spec.is_effect) appendListItem(names, spec.name);
  }
  return names;
}

const ParamSpec* findParam(const SectionSpec& spec, std::string_view key) {
  for (const ParamSpec& param : spec.params) {
    if (param.key == key) return &param;
  }
  return nullptr;
}

std::string sectionFromJson(const SectionSpec& spec, const Json& object, const std::string& file,
                            const std::string& path, SectionConfig& out) {
  out = defaultSection(spec);
  if (!object.is_object()) return at(file, path) + "expected an object (got " + describe(object) + ")";
  for (const auto& [key, value] : object.items()) {
    const ParamSpec* param = findParam(spec, key);
    const std::string key_path = path + "." + keyText(key);
    if (param == nullptr) return at(file, key_path) + "unknown key (known: " + knownKeys(spec) + ")";
    if (std::string error = paramFromJson(*param, value, at(file, key_path), out.params[key]); !error.empty()) {
      return error;
    }
  }
  return {};
}

SectionConfig* findConfigSection(SceneConfig& scene, std::string_view name) {
  if (name == "scene") return &scene.scene;
  if (name == "camera") return &scene.camera;
  if (name == "graphics") return &scene.graphics;
  for (SectionConfig& effect : scene.effects) {
    if (effect.name == name) return &effect;
  }
  return nullptr;
}

// Parses an override value written on the command line as JSON, accepting "1,2,3" for vec3
// and bare words for text.
Json overrideValueToJson(const ParamSpec& spec, std::string_view text) {
  std::string value(text);
  if (spec.type == ParamType::vec3 && !value.empty() && value.front() != '[') value = "[" + value + "]";
  if (spec.type == ParamType::text && (value.empty() || value.front() != '"')) return Json(value);
  return Json::parse(value, nullptr, false);
}

}  // namespace

const SectionSpec* findSection(std::string_view name) {
  for (const SectionSpec& spec : sceneSchema()) {
    if (spec.name == name) return &spec;
  }
  return nullptr;
}

static const ParamValue& findValue(const SectionConfig& section, std::string_view key, ParamType type) {
  const auto found = section.params.find(key);
  assert(found != section.params.end() && "parameter not in the schema");
  assert(found->second.type == type && "parameter read with the wrong type");
  (void)type;
  return found->second;
}

double SectionConfig::number(std::string_view key) const { return findValue(*this, key, ParamType::number).number; }
int SectionConfig::integer(std::string_view key) const {
  return static_cast<int>(findValue(*this, key, ParamType::integer).number);
}
bool SectionConfig::boolean(std::string_view key) const { return findValue(*this, key, ParamType::boolean).boolean; }
glm::vec3 SectionConfig::vec3(std::string_view key) const { return findValue(*this, key, ParamType::vec3).vec; }
const std::string& SectionConfig::text(std::string_view key) const {
  return findValue(*this, key, ParamType::text).text;
}

bool SceneConfig::has(std::string_view effect_name) const { return effect(effect_name) != nullptr; }

const SectionConfig* SceneConfig::effect(std::string_view effect_name) const {
  for (const SectionConfig& section : effects) {
    if (section.name == effect_name) return &section;
  }
  return nullptr;
}

std::vector<std::string> SceneConfig::effectNames() const {
  std::vector<std::string> names;
  for (const SectionConfig& section : effects) names.push_back(section.name);
  return names;
}

SceneStatus parseSceneText(const std::string& json_text, const std::string& file_label, SceneConfig& out) {
  out = SceneConfig{};
  Json root;
  try {
    root = Json::parse(json_text);
  } catch (const Json::parse_error& error) {
    // nlohmann reports "line L, column C"; keep its wording after the file name.
    return {file_label + ": invalid JSON: " + jsonErrorText(error.what())};
  } catch (const Json::exception& error) {
    // E.g. a number beyond double range: no position in the message, so find it.
    ErrorPosition position;
    Json::sax_parse(json_text, &position);
    return {file_label + ": invalid JSON at " + lineAndColumn(json_text, position.byte) + ": " +
            jsonErrorText(error.what())};
  }
  if (!root.is_object()) return {file_label + ": the top level must be an object (got " + describe(root) + ")"};
  if (DuplicateKeys keys; !Json::sax_parse(json_text, &keys) && !keys.duplicate.empty())
    return {file_label + ": " + keyText(keys.duplicate) + ": the key appears twice (one value would be lost)"};

  const SectionSpec* scene_spec = findSection("scene");
  const SectionSpec* camera_spec = findSection("camera");
  const SectionSpec* graphics_spec = findSection("graphics");
  assert(scene_spec && camera_spec && graphics_spec);
  SceneConfig scene;
  scene.scene = defaultSection(*scene_spec);
  scene.camera = defaultSection(*camera_spec);
  scene.graphics = defaultSection(*graphics_spec);
  bool has_effects = false;
  for (const auto& [key, value] : root.items()) {
    if (key == "description") {
      if (!value.is_string()) return {at(file_label, key) + "expected a string (got " + describe(value) + ")"};
      scene.description = value.get<std::string>();
    } else if (key == "scene" || key == "camera" || key == "graphics") {
      const SectionSpec& spec = key == "scene" ? *scene_spec : (key == "camera" ? *camera_spec : *graphics_spec);
      SectionConfig& section = key == "scene" ? scene.scene : (key == "camera" ? scene.camera : scene.graphics);
      if (std::string error = sectionFromJson(spec, value, file_label, key, section); !error.empty()) return {error};
    } else if (key == "effects") {
      has_effects = true;
      if (!value.is_object())
        return {at(file_label, key) + "expected an object of effects (got " + describe(value) + ")"};
      // Effects are kept in schema order so construction order does not depend on the file.
      for (const SectionSpec& spec : sceneSchema()) {
        if (!spec.is_effect || !value.contains(spec.name)) continue;
        SectionConfig section;
        const std::string path = "effects." + std::string(spec.name);
        if (std::string error = sectionFromJson(spec, value.at(std::string(spec.name)), file_label, path, section);
            !error.empty()) {
          return {error};
        }
        scene.effects.push_back(std::move(section));
      }
      for (const auto& [effect_name, effect_value] : value.items()) {
        const SectionSpec* spec = findSection(effect_name);
        if (spec == nullptr || !spec->is_effect) {
          return {at(file_label, "effects." + keyText(effect_name)) + "unknown effect (known: " + knownEffects() + ")"};
        }
        (void)effect_value;
      }
    } else {
      return {at(file_label, keyText(key)) + "unknown top-level key (known: description, scene, camera, graphics, effects)"};
    }
  }
  if (!has_effects) return {at(file_label, "effects") + "missing (a scene must list its effects)"};
  out = std::move(scene);
  return {};
}

SceneStatus loadSceneFile(const std::filesystem::path& path, SceneConfig& out) {
  out = SceneConfig{};
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return {path.string() + ": scene file not found"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {path.string() + ": cannot open scene file"};
  std::ostringstream text;
  text << in.rdbuf();
  SceneStatus status = parseSceneText(text.str(), path.string(), out);
  if (status.ok()) {
    out.name = path.stem().string();
    out.source = path;
  }
  return status;
}

SceneStatus applyOverride(SceneConfig& scene, std::string_view assignment) {
  const std::string label = "--set " + std::string(assignment);
  const std::size_t equals = assignment.find('=');
  if (equals == std::string_view::npos) return {label + ": expected section.key=value"};
  const std::string_view path = assignment.substr(0, equals);
  const std::string_view value_text = assignment.substr(equals + 1);
  const std::size_t dot = path.find('.');
  if (dot == std::string_view::npos) return {label + ": expected section.key=value (e.g. camera.fov_degrees=70)"};
  const std::string_view section_name = path.substr(0, dot);
  const std::string_view key = path.substr(dot + 1);

  const SectionSpec* spec = findSection(section_name);
  if (spec == nullptr) {
    return {label + ": unknown section '" + keyText(section_name) +
            "' (scene, camera, or an effect: " + knownEffects() + ")"};
  }
  SectionConfig* section = findConfigSection(scene, section_name);
  if (section == nullptr) {
    return {label + ": effect '" + keyText(section_name) + "' is not used by scene '" + scene.name + "'"};
  }
  const ParamSpec* param = findParam(*spec, key);
  if (param == nullptr) {
    return {label + ": unknown key '" + keyText(key) + "' (known: " + knownKeys(*spec) + ")"};
  }
  const Json value = overrideValueToJson(*param, value_text);
  if (value.is_discarded()) return {label + ": cannot parse value '" + keyText(value_text) + "'"};
  ParamValue parsed;
  if (std::string error = paramFromJson(*param, value, label + ": ", parsed); !error.empty()) return {error};
  section->params[std::string(key)] = parsed;
  return {};
}

std::vector<std::string> availableScenes(const std::filesystem::path& scenes_dir) {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(scenes_dir, error)) {
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

SceneStatus resolveScene(std::string_view name_or_path, const std::filesystem::path& scenes_dir,
                         std::filesystem::path& out) {
  const std::filesystem::path as_path{std::string(name_or_path)};
  std::error_code error;
  if (as_path.extension() == ".json" || name_or_path.find('/') != std::string_view::npos) {
    if (!std::filesystem::is_regular_file(as_path, error)) return {as_path.string() + ": scene file not found"};
    out = as_path;
    return {};
  }
  const std::filesystem::path candidate = scenes_dir / (std::string(name_or_path) + ".json");
  if (std::filesystem::is_regular_file(candidate, error)) {
    out = candidate;
    return {};
  }
  std::string list;
  for (const std::string& name : availableScenes(scenes_dir)) appendListItem(list, name);
  return {"unknown scene '" + std::string(name_or_path) + "' (available: " + (list.empty() ? "none" : list) + ")"};
}

}  // namespace game
