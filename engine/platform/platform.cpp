#include "engine/platform/platform.hpp"

#include "engine/gl/gl.hpp"

#include <algorithm>
#include <cstdlib>

namespace engine {
namespace {

struct GlVersion {
  int major;
  int minor;
};

// 4.5 core gives DSA, compute and KHR_debug; 3.3 core is the floor the shaders are written for.
constexpr GlVersion kVersions[] = {{4, 5}, {3, 3}};

}  // namespace

bool createPlatform(const PlatformDesc& desc, Platform& out, std::string& error) {
  out = Platform{};
  if (desc.headless) {
    // The offscreen driver creates its GL context through an EGL pbuffer: no display needed.
    setenv("SDL_VIDEODRIVER", "offscreen", 0);
  }
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) {
    error = std::string("SDL video init failed: ") + SDL_GetError();
    return false;
  }
  const int width = std::clamp(desc.width, 64, 8192);
  const int height = std::clamp(desc.height, 64, 8192);
  std::string attempts;
  for (const GlVersion& version : kVersions) {
    SDL_GL_ResetAttributes();
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, version.major);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, version.minor);
    SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
    if (desc.debug_context) SDL_GL_SetAttribute(SDL_GL_CONTEXT_FLAGS, SDL_GL_CONTEXT_DEBUG_FLAG);
    Uint32 flags = SDL_WINDOW_OPENGL;
    if (desc.headless)
      flags |= SDL_WINDOW_HIDDEN;
    else
      flags |= SDL_WINDOW_RESIZABLE | SDL_WINDOW_ALLOW_HIGHDPI;
    SDL_Window* window =
        SDL_CreateWindow(desc.title, SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width, height, flags);
    if (window == nullptr) {
      attempts += std::string(" [window for GL ") + std::to_string(version.major) + "." +
                  std::to_string(version.minor) + ": " + SDL_GetError() + "]";
      continue;
    }
    SDL_GLContext context = SDL_GL_CreateContext(window);
    if (context == nullptr) {
      attempts += std::string(" [GL ") + std::to_string(version.major) + "." + std::to_string(version.minor) +
                  " core: " + SDL_GetError() + "]";
      SDL_DestroyWindow(window);
      continue;
    }
    out.window = window;
    out.context = context;
    out.headless = desc.headless;
    out.gl_major = version.major;
    out.gl_minor = version.minor;
    break;
  }
  if (out.window == nullptr) {
    error = "could not create an OpenGL 4.5 or 3.3 core context (video driver '" +
            std::string(SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : "none") + "'):" + attempts;
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    return false;
  }
  SDL_GL_MakeCurrent(out.window, out.context);
  if (!desc.headless) SDL_GL_SetSwapInterval(desc.vsync ? 1 : 0);
  SDL_GL_GetDrawableSize(out.window, &out.width, &out.height);
  if (out.width <= 0 || out.height <= 0) {
    out.width = width;
    out.height = height;
  }
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  out.gl_renderer = renderer ? renderer : "unknown";
  out.gl_version = version ? version : "unknown";
  return true;
}

void destroyPlatform(Platform& platform) {
  if (platform.context != nullptr) SDL_GL_DeleteContext(platform.context);
  if (platform.window != nullptr) {
    SDL_DestroyWindow(platform.window);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
  }
  platform = Platform{};
}

void pollInput(Platform& platform, InputState& input, bool ui_wants_mouse, bool ui_wants_keyboard,
               bool (*event_hook)(const SDL_Event*)) {
  input.mouse_dx = input.mouse_dy = 0.0f;
  input.left_click = input.throw_explosive = input.toggle_ui = input.screenshot = input.resized = false;
  input.toggle_mute = false;
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    if (event_hook != nullptr) event_hook(&event);
    switch (event.type) {
      case SDL_QUIT:
        input.quit = true;
        break;
      case SDL_WINDOWEVENT:
        if (event.window.event == SDL_WINDOWEVENT_SIZE_CHANGED || event.window.event == SDL_WINDOWEVENT_RESIZED) {
          input.resized = true;
        }
        break;
      case SDL_KEYDOWN:
      case SDL_KEYUP: {
        const bool down = event.type == SDL_KEYDOWN;
        const SDL_Keycode key = event.key.keysym.sym;
        // Function keys always reach the game so the overlay can be closed while it has focus.
        if (down && !event.key.repeat) {
          if (key == SDLK_F1) input.toggle_ui = true;
          if (key == SDLK_F12) input.screenshot = true;
          if (key == SDLK_ESCAPE) {
            if (input.mouse_look)
              input.mouse_look = false;
            else
              input.quit = true;
          }
          if (key == SDLK_TAB && !ui_wants_keyboard) input.mouse_look = !input.mouse_look;
          if (key == SDLK_g && !ui_wants_keyboard) input.aiming = true;
          if (key == SDLK_m && !ui_wants_keyboard) input.toggle_mute = true;
        }
        // Aim while G is held, throw on its release (the arc shows where the charge will land).
        if (!down && key == SDLK_g && input.aiming) {
          input.aiming = false;
          input.throw_explosive = true;
        }
        if (ui_wants_keyboard && down) break;
        if (key == SDLK_w || key == SDLK_UP) input.forward = down;
        if (key == SDLK_s || key == SDLK_DOWN) input.back = down;
        if (key == SDLK_a || key == SDLK_LEFT) input.left = down;
        if (key == SDLK_d || key == SDLK_RIGHT) input.right = down;
        if (key == SDLK_SPACE || key == SDLK_e) input.up = down;
        if (key == SDLK_LCTRL || key == SDLK_q) input.down = down;
        if (key == SDLK_LSHIFT || key == SDLK_RSHIFT) input.fast = down;
        break;
      }
      case SDL_MOUSEBUTTONDOWN:
        if (ui_wants_mouse && !input.mouse_look) break;
        if (event.button.button == SDL_BUTTON_LEFT) input.left_click = true;
        if (event.button.button == SDL_BUTTON_MIDDLE) input.aiming = true;
        if (event.button.button == SDL_BUTTON_RIGHT) input.mouse_look = true;
        break;
      case SDL_MOUSEBUTTONUP:
        if (event.button.button == SDL_BUTTON_RIGHT) input.mouse_look = false;
        if (event.button.button == SDL_BUTTON_MIDDLE && input.aiming) {
          input.aiming = false;
          input.throw_explosive = true;
        }
        break;
      case SDL_MOUSEMOTION:
        if (input.mouse_look) {
          input.mouse_dx += static_cast<float>(event.motion.xrel);
          input.mouse_dy += static_cast<float>(event.motion.yrel);
        }
        break;
      default:
        break;
    }
  }
  if (!platform.headless) SDL_SetRelativeMouseMode(input.mouse_look ? SDL_TRUE : SDL_FALSE);
  int w = 0, h = 0;
  SDL_GL_GetDrawableSize(platform.window, &w, &h);
  if (w > 0 && h > 0 && (w != platform.width || h != platform.height)) {
    platform.width = w;
    platform.height = h;
    input.resized = true;
  }
}

void swapWindow(Platform& platform) {
  if (platform.window != nullptr) SDL_GL_SwapWindow(platform.window);
}

}  // namespace engine
