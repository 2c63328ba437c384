#pragma once
// Headless GL context for the GPU tests: SDL2's offscreen driver (EGL pbuffer), core profile
// 4.5, else 3.3. Kept local to the tests until the engine's platform layer is on this branch.

#include <string>

struct SDL_Window;

namespace gputest {

struct GlContext {
  SDL_Window* window = nullptr;
  void* context = nullptr;
  std::string error;    // why creation failed
  std::string version;  // GL_VERSION / GL_RENDERER
  bool ok() const { return context != nullptr; }
};

// Creates and makes current; check ok().
void createContext(GlContext& out);
void destroyContext(GlContext& ctx);

}  // namespace gputest
