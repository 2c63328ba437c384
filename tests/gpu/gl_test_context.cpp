#include "tests/gpu/gl_test_context.hpp"

#include <GL/gl.h>
#include <SDL2/SDL.h>

#include <cstdlib>

namespace gputest {

void createContext(GlContext& out) {
  setenv("SDL_VIDEODRIVER", "offscreen", 1);
  if (SDL_Init(SDL_INIT_VIDEO) != 0) {
    out.error = std::string("SDL_Init: ") + SDL_GetError();
    return;
  }
  const int versions[2][2] = {{4, 5}, {3, 3}};
  for (const auto& v : versions) {
    SDL_GL_ResetAttributes();
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, v[0]);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, v[1]);
    SDL_Window* window = SDL_CreateWindow("gpu test", 0, 0, 64, 64, SDL_WINDOW_OPENGL | SDL_WINDOW_HIDDEN);
    if (window == nullptr) {
      out.error = std::string("SDL_CreateWindow: ") + SDL_GetError();
      continue;
    }
    SDL_GLContext context = SDL_GL_CreateContext(window);
    if (context == nullptr) {
      out.error = std::string("SDL_GL_CreateContext: ") + SDL_GetError();
      SDL_DestroyWindow(window);
      continue;
    }
    SDL_GL_MakeCurrent(window, context);
    out.window = window;
    out.context = context;
    out.version = std::string(reinterpret_cast<const char*>(glGetString(GL_VERSION))) + " / " +
                  reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    out.error.clear();
    return;
  }
  SDL_Quit();
}

void destroyContext(GlContext& ctx) {
  if (ctx.context != nullptr) SDL_GL_DeleteContext(static_cast<SDL_GLContext>(ctx.context));
  if (ctx.window != nullptr) SDL_DestroyWindow(ctx.window);
  if (ctx.context != nullptr || ctx.window != nullptr) SDL_Quit();
  ctx = GlContext{};
}

}  // namespace gputest
