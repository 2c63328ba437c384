#include "game/world/blob_program.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace game {
namespace {

using Json = nlohmann::json;

struct ProgramReader {
  std::string file;
  std::string error;

  bool fail(const std::string& path, const Json& value, const std::string& why) {
    if (error.empty()) error = file + ": " + path + " = " + value.dump() + ": " + why;
    return false;
  }
  bool number(const Json& v, const std::string& path, float& out) {
    if (!v.is_number()) return fail(path, v, "expected a number");
    out = v.get<float>();
    if (!std::isfinite(out)) return fail(path, v, "not finite");
    return true;
  }
  bool integer(const Json& v, const std::string& path, int& out) {
    if (!v.is_number_integer()) return fail(path, v, "expected an integer");
    out = v.get<int>();
    return true;
  }
  bool vec3(const Json& v, const std::string& path, glm::vec3& out) {
    if (!v.is_array() || v.size() != 3) return fail(path, v, "expected [x, y, z]");
    for (int k = 0; k < 3; ++k)
      if (!number(v[k], path + "[" + std::to_string(k) + "]", out[k])) return false;
    return true;
  }
  bool text(const Json& v, const std::string& path, std::string& out) {
    if (!v.is_string()) return fail(path, v, "expected a string");
    out = v.get<std::string>();
    return true;
  }

  // One behaviour's keys besides name/behaviour/triggers; `walls` names the level's colliders
  // (the coat_wall `wall` key resolves to its index).
  bool behaviourKey(const std::string& key, const Json& v, const std::string& path, fluid::BlobBehaviour& b,
                    const std::vector<std::string>& walls) {
    if (key == "point") return vec3(v, path, b.point);
    if (key == "height") return number(v, path, b.height);
    if (key == "speed") return number(v, path, b.speed);
    if (key == "weight") return number(v, path, b.weight);
    if (key == "tentacles") return integer(v, path, b.tentacles);
    if (key == "tentacle_particles") return integer(v, path, b.tentacle_particles);
    if (key == "tentacle_length") return number(v, path, b.tentacle_length);
    if (key == "tentacle_spread") return number(v, path, b.tentacle_spread);
    if (key == "tip_strength") return number(v, path, b.tip_strength);
    if (key == "tip_radius_scale") return number(v, path, b.tip_radius_scale);
    if (key == "catch_distance") return number(v, path, b.catch_distance);
    if (key == "reach_range") return number(v, path, b.reach_range);
    if (key == "grow_speed") return number(v, path, b.grow_speed);
    if (key == "curl") return number(v, path, b.curl);
    if (key == "stretch") return number(v, path, b.stretch);
    if (key == "wall") {
      std::string name;
      if (!text(v, path, name)) return false;
      for (std::size_t i = 0; i < walls.size(); ++i)
        if (walls[i] == name) b.wall_collider = static_cast<int>(i);
      if (b.wall_collider < 0) return fail(path, v, "not a collider of the level (its .colliders file)");
      return true;
    }
    return fail(path, v, "unknown key");
  }

  bool trigger(const Json& t, const std::string& path, fluid::BlobTrigger& out) {
    if (!t.is_object()) return fail(path, t, "expected an object {\"when\": ..., \"next\": ...}");
    for (const auto& [key, v] : t.items()) {
      const std::string at = path + "." + key;
      if (key == "when") {
        std::string name;
        if (!text(v, at, name)) return false;
        if (!fluid::parseBlobTrigger(name, out.kind))
          return fail(at, v,
                      "unknown trigger (after_seconds, goal_reached, target_within, target_beyond, blasted, event)");
      } else if (key == "value") {
        if (!number(v, at, out.value)) return false;
      } else if (key == "event") {
        if (!text(v, at, out.event)) return false;
      } else if (key == "next") {
        if (!text(v, at, out.next)) return false;
      } else {
        return fail(at, v, "unknown key (when, value, event, next)");
      }
    }
    if (!t.contains("when")) return fail(path, t, "missing \"when\"");
    if (!t.contains("next")) return fail(path, t, "missing \"next\"");
    return true;
  }

  bool state(const Json& s, const std::string& path, fluid::BlobState& out, const std::vector<std::string>& walls) {
    if (!s.is_object()) return fail(path, s, "expected an object");
    if (!s.contains("name")) return fail(path, s, "missing \"name\"");
    if (!s.contains("behaviour")) return fail(path, s, "missing \"behaviour\"");
    for (const auto& [key, v] : s.items()) {
      const std::string at = path + "." + key;
      if (key == "name") {
        if (!text(v, at, out.name)) return false;
      } else if (key == "behaviour") {
        std::string name;
        if (!text(v, at, name)) return false;
        if (!fluid::parseBlobBehaviour(name, out.behaviour.kind))
          return fail(at, v, "unknown behaviour (idle, emerge, ball, tentacles, coat_wall, chase, reassemble)");
      } else if (key == "triggers") {
        if (!v.is_array()) return fail(at, v, "expected an array");
        for (std::size_t k = 0; k < v.size(); ++k) {
          out.triggers.emplace_back();
          if (!trigger(v[k], at + "[" + std::to_string(k) + "]", out.triggers.back())) return false;
        }
      } else if (!behaviourKey(key, v, at, out.behaviour, walls)) {
        return false;
      }
    }
    return true;
  }

  bool program(const std::string& text_in, fluid::BlobProgram& out, const std::vector<std::string>& walls) {
    Json root;
    try {
      root = Json::parse(text_in);
    } catch (const Json::parse_error& e) {
      error = file + ": invalid JSON: " + e.what();
      return false;
    }
    if (!root.is_object()) return fail("(top level)", root, "expected an object with \"states\"");
    for (const auto& [key, v] : root.items()) {
      if (key == "initial") {
        if (!text(v, key, out.initial)) return false;
      } else if (key == "description") {
        continue;
      } else if (key == "states") {
        if (!v.is_array() || v.empty()) return fail(key, v, "expected a non-empty array of states");
        for (std::size_t k = 0; k < v.size(); ++k) {
          out.states.emplace_back();
          if (!state(v[k], "states[" + std::to_string(k) + "]", out.states.back(), walls)) return false;
        }
      } else {
        return fail(key, v, "unknown key (description, initial, states)");
      }
    }
    if (out.states.empty()) return fail("(top level)", root, "missing \"states\"");
    return true;
  }
};

}  // namespace

bool loadBlobProgram(const std::filesystem::path& path, const fluid::BlobParams& params,
                     const std::vector<std::string>& walls, fluid::BlobProgram& out, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = "blob.program: cannot read " + path.string();
    return false;
  }
  std::stringstream text;
  text << in.rdbuf();
  ProgramReader reader{path.string(), {}};
  if (!reader.program(text.str(), out, walls)) {
    error = "blob.program: " + reader.error;
    return false;
  }
  const fluid::BlobStatus st = fluid::validateBlobProgram(out, params);
  if (!st.ok()) {
    error = "blob.program: " + path.string() + ": " + st.error;
    return false;
  }
  return true;
}

}  // namespace game
