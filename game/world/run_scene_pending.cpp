// Temporary: runScene lands with the engine branch, which replaces this file.
#include "game/run_scene.hpp"

namespace game {

int runScene(const SceneConfig&, const RunOptions&, RunReport&, std::string& error) {
  error = "the renderer is not built yet";
  return 1;
}

}  // namespace game
