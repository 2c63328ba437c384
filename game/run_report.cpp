// What runScene reports and the player's actions: the run summary `play` and `replay` print,
// the display check, and the actions replay files name (contract: run_scene.hpp).
#include "game/run_scene.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"

#include <cstdlib>

namespace game {

bool displayAvailable() {
  const char* driver = std::getenv("SDL_VIDEODRIVER");
  if (driver != nullptr && (std::string_view(driver) == "offscreen" || std::string_view(driver) == "dummy"))
    return false;
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 != nullptr && *x11 != '\0') || (wayland != nullptr && *wayland != '\0');
}

void printRunSummary(std::FILE* out, const SceneConfig& scene, const RunOptions& options, const RunReport& report) {
  std::fprintf(out, "fluiddemo: scene '%s', %d frames, %llu simulation steps, %dx%d %s\n", scene.name.c_str(),
               report.frames_rendered, static_cast<unsigned long long>(report.simulation_steps), options.width,
               options.height, options.headless ? "headless" : "window");
  std::fprintf(out, "renderer: %s (graphics %s, scene %dx%d)\n", report.gl_renderer.c_str(),
               report.graphics_preset.c_str(), report.scene_width, report.scene_height);
  std::string systems;
  for (const std::string& system : report.systems_constructed) systems += (systems.empty() ? "" : ", ") + system;
  std::fprintf(out, "systems running: %s\n", systems.empty() ? "(none)" : systems.c_str());
  std::fprintf(out, "%-10s %10s %10s %10s\n", "phase", "mean ms", "max ms", "samples");
  for (const PhaseTiming& phase : report.phases) {
    std::fprintf(out, "%-10s %10.3f %10.3f %10llu\n", phase.phase.c_str(), phase.mean_ms, phase.max_ms,
                 static_cast<unsigned long long>(phase.samples));
  }
  std::fprintf(out, "%-10s %10.3f\n", "frame", report.mean_frame_ms);
  if (report.runtime_failures > 0) {
    std::fprintf(out, "run-time failures: %llu (the frames went on); first: %s; last: %s\n",
                 static_cast<unsigned long long>(report.runtime_failures), report.first_failure.c_str(),
                 report.last_failure.c_str());
  }
  if (report.has_sph) {
    const fluid::SphStepTotals& t = report.sph_totals;
    const auto ull = [](std::size_t v) { return static_cast<unsigned long long>(v); };
    std::fprintf(
        out,
        "sph health: %llu sub-steps, density error mean %.4f %% p99 %.3f %% max %.3f %%, pushed out of colliders %llu "
        "(deepest %.2f mm), speed clamps %llu, dt held at min %llu, dt cut to the step's end %llu, "
        "NaN/inf %llu; frames warned %llu\n",
        ull(t.steps), 100.0 * t.meanDensityError(), 100.0 * t.p99_density_error, 100.0 * t.max_density_error,
        ull(t.pushed_out), 1000.0 * t.max_push_depth, ull(t.speed_clamps), ull(t.dt_min_clamps), ull(t.dt_request_cuts),
        ull(t.nonfinite), static_cast<unsigned long long>(report.warned_frames));
  }
}

void fillSphHealth(const World& world, const engine::Profiler& profiler, RunReport& report) {
  report.warned_frames = profiler.flagged_frames;
  if (const SphFluid* fluid = findState<SphFluid>(world)) {
    report.has_sph = true;
    report.sph_totals = fluid->run_totals;
  }
}

std::string_view playerActionName(PlayerAction action) {
  switch (action) {
    case PlayerAction::throw_crate:
      return "throw_crate";
    case PlayerAction::throw_explosive:
      return "throw_explosive";
  }
  return "?";
}

bool parsePlayerAction(std::string_view name, PlayerAction& out) {
  for (PlayerAction action : {PlayerAction::throw_crate, PlayerAction::throw_explosive}) {
    if (name == playerActionName(action)) {
      out = action;
      return true;
    }
  }
  return false;
}

void applyPlayerAction(World& world, PlayerAction action) {
  switch (action) {
    case PlayerAction::throw_crate:
      playerThrow(world);
      break;
    case PlayerAction::throw_explosive:
      playerThrowExplosive(world);
      break;
  }
}

}  // namespace game
