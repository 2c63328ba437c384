#pragma once
// The contract between the command line (play/smoke commands) and the running game:
// runScene() builds the world a SceneConfig asks for (only the effects it lists), runs the
// engine loop with a window or headless, and reports what happened.

#include "game/scene/scene_config.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace game {

struct World;

// What RunOptions::after_frame is told about the frame just finished.
struct FrameInfo {
  int frame = 0;  // index of the frame (0 = first)
  int steps = 0;  // simulation steps taken during it
};

struct RunOptions {
  int width = 1280;  // framebuffer size in pixels, clamped to [64, 8192]
  int height = 720;
  bool headless = false;             // no window: SDL offscreen/EGL context, render into an FBO only
  int frames = 0;                    // render this many frames then exit; 0 = until the window is closed
  std::filesystem::path screenshot;  // if set, the last frame is written here as PNG
  bool show_ui = true;               // ImGui overlay (toggled at run time with a key)
  bool capture_last_frame = false;   // fill RunReport::last_frame_rgba / blank_frame_rgba
  bool fixed_frame_time = false;     // headless runs feed the loop exactly one step per frame
  // Hooks for tools that drive or watch a run (soak, replays); empty = not called.
  // before_step: before each simulation step, with the step's index (world.steps before it).
  std::function<void(World&, std::uint64_t step)> before_step;
  // after_frame: once per frame, after its steps, the meshing and the render; false ends the run
  // after this frame.
  std::function<bool(const World&, const FrameInfo&)> after_frame;
};

// Statistics of one profiler phase over the run, in milliseconds.
struct PhaseTiming {
  std::string phase;  // "input", "physics", "fluid", "meshing", "render", "ui", ...
  double mean_ms = 0.0;
  double max_ms = 0.0;
  std::uint64_t samples = 0;
};

struct RunReport {
  int frames_rendered = 0;
  std::uint64_t simulation_steps = 0;
  std::vector<std::string> systems_constructed;  // effect names whose systems were built, in order
  std::vector<PhaseTiming> phases;
  double mean_frame_ms = 0.0;
  std::string gl_renderer;      // GL_RENDERER string of the context used
  int gl_errors = 0;            // GL errors seen by the engine's checks
  std::string nonfinite_state;  // empty, or which system/value went NaN/inf at which step
  // Filled when RunOptions::capture_last_frame: RGBA8, bottom row first, width*height*4 bytes.
  int frame_width = 0;
  int frame_height = 0;
  std::vector<std::uint8_t> last_frame_rgba;
  std::vector<std::uint8_t> blank_frame_rgba;  // the same camera and passes with nothing drawn but the clear
};

// Returns 0 on success. On failure returns non-zero and sets `error` to a complete message
// (e.g. a shader file:line, a missing asset path); never throws or crashes on bad content.
int runScene(const SceneConfig& scene, const RunOptions& options, RunReport& report, std::string& error);

}  // namespace game
