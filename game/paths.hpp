#pragma once
// Where run-time files live. The executable knows the source tree it was built from
// (FLUIDDEMO_SOURCE_DIR); FLUIDDEMO_ROOT in the environment overrides it, e.g. for an
// installed copy.

#include <cstdlib>
#include <filesystem>

namespace game {

inline std::filesystem::path projectRoot() {
  if (const char* root = std::getenv("FLUIDDEMO_ROOT"); root != nullptr && *root != '\0') return root;
  return FLUIDDEMO_SOURCE_DIR;
}

inline std::filesystem::path scenesDir() { return projectRoot() / "content" / "scenes"; }
inline std::filesystem::path shadersDir() { return projectRoot() / "shaders"; }
inline std::filesystem::path contentDir() { return projectRoot() / "content"; }

}  // namespace game
