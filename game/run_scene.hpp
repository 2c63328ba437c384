#pragma once
// The contract between the command line (play/smoke commands) and the running game:
// runScene() builds the world a SceneConfig asks for (only the effects it lists), runs the
// engine loop with a window or headless, and reports what happened.

#include "engine/profile/profiler.hpp"
#include "fluid/sph/sph.hpp"
#include "game/scene/scene_config.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace game {

struct World;

// What a player can do to the simulation besides moving the camera. Replay files name them
// (playerActionName); later effects add theirs here (throw_explosive, blob triggers).
enum class PlayerAction : std::uint8_t { throw_crate, throw_explosive };
std::string_view playerActionName(PlayerAction action);
bool parsePlayerAction(std::string_view name, PlayerAction& out);  // false for an unknown name
void applyPlayerAction(World& world, PlayerAction action);

// Before this frame's simulation steps, after the player's own input moved the camera.
struct FrameInput {
  World& world;
  int frame = 0;                       // 0-based frame index
  std::vector<PlayerAction>& actions;  // this frame's actions (the mouse's so far); hooks may add/remove
  std::filesystem::path screenshot;    // if set, this frame (after its steps) is written here as PNG
};

// After the frame (its steps, meshing, rendering, UI) has ended in the profiler.
struct FrameResult {
  const World& world;
  int frame = 0;
  int steps = 0;                                       // simulation steps taken this frame
  std::array<double, engine::kPhaseCount> phase_ms{};  // this frame's time per profiler phase
  double frame_ms = 0.0;                               // this frame's wall time, beginFrame..endFrame
};

// Optional per-frame hooks: scripted input and recording (game/replay), per-frame observers.
// Every member may be empty.
struct FrameHooks {
  std::function<void(FrameInput&)> before_steps;
  std::function<bool(const FrameResult&)> after_frame;  // return false to end the run after this frame
  std::function<void()> draw_overlay;                   // inside the F1 overlay (ImGui calls), when visible
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
  FrameHooks hooks;
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
  std::string graphics_preset;  // the graphics preset the run drew with (low, medium, high)
  int scene_width = 0, scene_height = 0;  // the scene target it rendered at (the preset's resolution scale)
  int gl_errors = 0;            // GL errors seen by the engine's checks
  std::string nonfinite_state;  // empty, or which system/value went NaN/inf at which step
  // Systems that refused content at run time while the frames went on (World::failures).
  std::uint64_t runtime_failures = 0;
  std::string first_failure, last_failure;
  // Filled when RunOptions::capture_last_frame: RGBA8, bottom row first, width*height*4 bytes.
  int frame_width = 0;
  int frame_height = 0;
  std::vector<std::uint8_t> last_frame_rgba;
  std::vector<std::uint8_t> blank_frame_rgba;  // the same camera and passes with nothing drawn but the clear
  bool stopped_by_hook = false;                // FrameHooks::after_frame ended the run
  // The SPH solver's health counters over the whole run (has_sph: an sph_fluid effect ran), and
  // the frames the profiler flagged (the overlay's red markers).
  bool has_sph = false;
  fluid::SphStepTotals sph_totals;
  std::uint64_t warned_frames = 0;
};

struct World;
// Copies the sph_fluid effect's run totals (when it is built) and the flagged frame count into
// `report` (run_report.cpp).
void fillSphHealth(const World& world, const engine::Profiler& profiler, RunReport& report);

// True when a window can be opened (DISPLAY or WAYLAND_DISPLAY set, SDL_VIDEODRIVER not offscreen/dummy).
bool displayAvailable();

// The run summary `play` and `replay` print: scene, frames, steps, size, renderer, systems, and
// mean/max per profiler phase.
void printRunSummary(std::FILE* out, const SceneConfig& scene, const RunOptions& options, const RunReport& report);

// Returns 0 on success. On failure returns non-zero and sets `error` to a complete message
// (e.g. a shader file:line, a missing asset path); never throws or crashes on bad content.
int runScene(const SceneConfig& scene, const RunOptions& options, RunReport& report, std::string& error);

}  // namespace game
