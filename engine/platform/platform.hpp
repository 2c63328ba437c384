#pragma once
// Window + OpenGL context (SDL2), or a headless context (SDL offscreen driver = EGL pbuffer),
// and the per-frame input state. Requests a 4.5 core context and falls back to 3.3 core.

#include <SDL.h>

#include <string>

namespace engine {

struct PlatformDesc {
  const char* title = "fluiddemo";
  int width = 1280;  // drawable size in pixels, clamped to [64, 8192]
  int height = 720;
  bool headless = false;       // SDL offscreen driver (EGL pbuffer); sets SDL_VIDEODRIVER=offscreen if unset
  bool vsync = true;           // ignored when headless
  bool debug_context = false;  // request a KHR_debug context (debug builds)
};

struct Platform {
  SDL_Window* window = nullptr;     // owned
  SDL_GLContext context = nullptr;  // owned
  bool headless = false;
  int width = 0;  // current drawable size
  int height = 0;
  int gl_major = 0;
  int gl_minor = 0;
  std::string gl_renderer;  // GL_RENDERER
  std::string gl_version;   // GL_VERSION
};

// Per-frame input. Mouse deltas accumulate between pollInput() calls.
struct InputState {
  bool quit = false;
  bool forward = false, back = false, left = false, right = false, up = false, down = false;
  bool fast = false;                       // shift
  float mouse_dx = 0.0f, mouse_dy = 0.0f;  // pixels since the last poll (relative mode)
  bool mouse_look = false;                 // right button held, or relative mode toggled with Tab
  bool left_click = false;                 // a left press happened this frame
  bool aiming = false;                     // G or the middle button held: the aim arc shows
  bool throw_explosive = false;            // G or the middle button released this frame: the throw
  bool toggle_ui = false;                  // F1 pressed this frame
  bool screenshot = false;                 // F12 pressed this frame
  bool toggle_mute = false;                // M pressed this frame (the audio effect's mute)
  bool resized = false;
};

// Returns false and fills `error` (SDL's message) on failure; `out` is then empty.
bool createPlatform(const PlatformDesc& desc, Platform& out, std::string& error);
void destroyPlatform(Platform& platform);

// Drains SDL's event queue into `input` (edge flags are reset first, held keys persist).
// `ui_wants_mouse`/`ui_wants_keyboard` stop clicks/keys from reaching the game when ImGui uses them.
// `event_hook` (may be null) sees every event first, e.g. the ImGui backend.
void pollInput(Platform& platform, InputState& input, bool ui_wants_mouse, bool ui_wants_keyboard,
               bool (*event_hook)(const SDL_Event*));

void swapWindow(Platform& platform);

}  // namespace engine
