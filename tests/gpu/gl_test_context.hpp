#pragma once
// Headless GL context for the GPU tests and their bench tools: the engine's platform layer
// (engine/platform) with SDL's offscreen driver forced, so results do not depend on whether a
// display is present (golden images compare llvmpipe output with llvmpipe output).

#include "engine/platform/platform.hpp"

#include <string>

namespace gputest {

struct GlContext {
  engine::Platform platform;
  std::string error;    // why creation failed
  std::string version;  // "GL_VERSION / GL_RENDERER"
  bool ok() const { return platform.context != nullptr; }
};

// Creates a 64x64 hidden offscreen context (4.5 core, else 3.3) and makes it current; check ok().
void createContext(GlContext& out);
void destroyContext(GlContext& ctx);

}  // namespace gputest
