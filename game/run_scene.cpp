// runScene(): builds the world a scene asks for, runs the engine loop (window or headless) with
// a fixed simulation step and interpolated rendering, and reports what happened. One frame
// (docs/architecture.md): input -> fixed steps (stepWorld) -> meshing (meshWorld) -> the level
// and every effect submit batches -> engine::renderFrame draws them -> images -> present -> UI.
// No GL here: the engine owns the passes.
#include "game/run_scene.hpp"

#include "engine/camera/camera.hpp"
#include "engine/loop/fixed_step.hpp"
#include "engine/platform/platform.hpp"
#include "engine/profile/profiler.hpp"
#include "engine/render/frame.hpp"
#include "engine/render/image_write.hpp"
#include "engine/render/renderer.hpp"
#include "engine/ui/overlay.hpp"
#include "game/explosives/explosives.hpp"
#include "game/graphics_settings.hpp"
#include "game/paths.hpp"
#include "game/scene_panel.hpp"
#include "game/world/level_assets.hpp"
#include "game/world/world.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace game {
namespace {

std::filesystem::path shaderDirectory() {
  if (const char* dir = std::getenv("FLUIDDEMO_SHADER_DIR"); dir != nullptr && *dir != '\0') return dir;
  return shadersDir();
}

// Everything one run keeps between frames (the GL objects live in runScene's inner scope).
// An explosion's flash: a point light at the newest blast, brightest when it goes off and gone
// within half a second. Rendering only: the game state never reads it.
struct BlastFlash {
  glm::vec3 position{0.0f};
  double age = 1e9;  // s since the blast
};

void advanceFlash(BlastFlash& flash, const World& world) {
  flash.age += world.step_seconds;
  if (const Explosives* explosives = findState<Explosives>(world); explosives && !explosives->detonations.empty()) {
    flash.position = explosives->detonations.back().centre;
    flash.age = 0.0;
  }
}

void lightFlash(const BlastFlash& flash, engine::Lighting& lighting) {
  constexpr double kDecay = 0.08;  // s: a detonation's light dies in a few tenths of a second
  constexpr float kPeak = 60.0f;   // radiance at 1 m, ~20x the sun's
  const float strength = flash.age < 0.5 ? kPeak * static_cast<float>(std::exp(-flash.age / kDecay)) : 0.0f;
  lighting.flash_position = flash.position + glm::vec3(0.0f, 0.3f, 0.0f);
  lighting.flash_colour = strength * glm::vec3(1.0f, 0.62f, 0.28f);
}

struct Session {
  Session(const RunOptions& run_options, const SceneConfig& run_scene, RunReport& run_report, World& run_world,
          engine::Platform& run_platform, engine::Renderer& run_renderer, engine::Overlay& run_overlay,
          const LevelAssets& level, const GraphicsSettings& run_graphics)
      : options(run_options),
        loaded(run_scene),
        report(run_report),
        world(run_world),
        platform(run_platform),
        renderer(run_renderer),
        overlay(run_overlay),
        assets(level),
        graphics(run_graphics) {}

  const RunOptions& options;
  const SceneConfig& loaded;  // the scene as the run was asked for (before the graphics preset)
  RunReport& report;
  World& world;
  engine::Platform& platform;
  engine::Renderer& renderer;
  engine::Overlay& overlay;
  const LevelAssets& assets;
  GraphicsSettings graphics;
  engine::Profiler profiler;
  engine::InputState input;
  engine::Lighting lighting;
  BlastFlash flash;
  std::vector<std::uint8_t> pixels;
  std::vector<std::uint8_t> scene_pixels;  // the scene FBO before it is scaled to the view's size
  std::vector<PlayerAction> actions;
  std::filesystem::path hook_screenshot;
};

// The size the player sees: the requested frame headless, the window's drawable otherwise. The
// scene renders at the graphics' resolution scale of it.
int viewWidth(const RunOptions& options, const engine::Platform& platform) {
  return options.headless ? std::clamp(options.width, 64, 8192) : platform.width;
}
int viewHeight(const RunOptions& options, const engine::Platform& platform) {
  return options.headless ? std::clamp(options.height, 64, 8192) : platform.height;
}
int viewWidth(const Session& s) { return viewWidth(s.options, s.platform); }
int viewHeight(const Session& s) { return viewHeight(s.options, s.platform); }
int scaled(int size, const GraphicsSettings& graphics) {
  return std::max(16, static_cast<int>(std::lround(static_cast<float>(size) * graphics.resolution_scale)));
}

// The graphics preset of world.scene on this renderer (game/graphics_settings.hpp): its
// render-only keys set from the loaded scene's and applied live. At the start and on a restart.
GraphicsSettings presetWorld(World& world, const SceneConfig& loaded, const std::string& gl_renderer) {
  GraphicsSettings graphics = resolveGraphics(world.scene.graphics, gl_renderer);
  applyGraphics(graphics, loaded, world.scene);
  applyLiveParams(world);
  return graphics;
}

// A restart's preset, and the scene target resized to its resolution scale. False when the
// resize failed.
bool applyGraphicsPreset(Session& s, std::string& error) {
  s.graphics = presetWorld(s.world, s.loaded, s.platform.gl_renderer);
  return engine::resizeRenderer(s.renderer, scaled(viewWidth(s), s.graphics), scaled(viewHeight(s), s.graphics), error);
}

// The scene FBO at the view's size (scaled up when the graphics render it smaller) into s.pixels.
void readView(Session& s) {
  const int width = viewWidth(s), height = viewHeight(s);
  if (s.renderer.width == width && s.renderer.height == height) {
    engine::readSceneRgba(s.renderer, s.pixels);
    return;
  }
  engine::readSceneRgba(s.renderer, s.scene_pixels);
  engine::resizeRgba(s.scene_pixels, s.renderer.width, s.renderer.height, width, height, s.pixels);
}

// Input phase: SDL events move the camera; the mouse and the hooks decide the player's actions.
// False when a resize failed (error set).
bool readInput(Session& s, int frame, double frame_dt, std::string& error) {
  const engine::ScopedPhase phase(s.profiler, engine::Phase::input);
  engine::InputState& input = s.input;
  engine::pollInput(s.platform, input, engine::overlayWantsMouse(s.overlay), engine::overlayWantsKeyboard(s.overlay),
                    &engine::overlayProcessEvent);
  if (input.toggle_ui) s.overlay.mode = engine::nextOverlayMode(s.overlay.mode);
  // M mutes: the audio effect's `mute` key, flipped live as the overlay's knobs are.
  if (const SectionConfig* audio = s.world.scene.effect("audio"); input.toggle_mute && audio != nullptr)
    if (applyOverride(s.world.scene, audio->boolean("mute") ? "audio.mute=false" : "audio.mute=true").ok())
      applyLiveParams(s.world);
  engine::CameraInput camera_input;
  camera_input.forward = (input.forward ? 1.0f : 0.0f) - (input.back ? 1.0f : 0.0f);
  camera_input.right = (input.right ? 1.0f : 0.0f) - (input.left ? 1.0f : 0.0f);
  camera_input.up = (input.up ? 1.0f : 0.0f) - (input.down ? 1.0f : 0.0f);
  camera_input.fast = input.fast;
  camera_input.look_dx = input.mouse_dx;
  camera_input.look_dy = input.mouse_dy;
  engine::updateCamera(s.world.camera, camera_input, static_cast<float>(frame_dt));
  s.actions.clear();
  if (input.left_click) s.actions.push_back(PlayerAction::throw_crate);
  if (input.throw_explosive) s.actions.push_back(PlayerAction::throw_explosive);
  s.world.player_aiming = input.aiming;
  FrameInput frame_input{s.world, frame, s.actions, {}};
  if (s.options.hooks.before_steps) s.options.hooks.before_steps(frame_input);
  for (PlayerAction action : s.actions) applyPlayerAction(s.world, action);
  s.hook_screenshot = std::move(frame_input.screenshot);
  if (input.resized && !s.options.headless)
    return engine::resizeRenderer(s.renderer, scaled(s.platform.width, s.graphics),
                                  scaled(s.platform.height, s.graphics), error);
  return true;
}

// Screenshots of the drawn frame (F12, a hook's, the last frame's) and the smoke test's capture.
// False when a required image could not be written (error set).
bool writeImages(Session& s, const engine::FrameView& view, bool last_frame, std::string& error) {
  engine::Renderer& renderer = s.renderer;
  const RunOptions& options = s.options;
  if (s.input.screenshot || !s.hook_screenshot.empty() ||
      (last_frame && (!options.screenshot.empty() || options.capture_last_frame))) {
    readView(s);
  }
  const int width = viewWidth(s), height = viewHeight(s);
  bool ok = true;
  if (!s.hook_screenshot.empty() && !engine::writePngBottomUp(s.hook_screenshot, width, height, s.pixels, error)) {
    ok = false;
  }
  if (s.input.screenshot) {
    const std::filesystem::path path = engine::nextFreeScreenshotPath(".", "fluiddemo");
    std::string write_error;
    if (engine::writePngBottomUp(path, width, height, s.pixels, write_error)) {
      std::printf("screenshot: %s\n", path.string().c_str());
    } else {
      std::fprintf(stderr, "fluiddemo: %s\n", write_error.c_str());
    }
  }
  if (!last_frame) return ok;
  if (!options.screenshot.empty() && !engine::writePngBottomUp(options.screenshot, width, height, s.pixels, error)) {
    ok = false;
  }
  if (options.capture_last_frame) {
    s.report.frame_width = width;
    s.report.frame_height = height;
    s.report.last_frame_rgba = s.pixels;
    // The same passes with nothing drawn but the clear, for the smoke test's blank check.
    engine::renderScene(renderer, view, s.lighting, {}, false);
    readView(s);
    s.report.blank_frame_rgba = s.pixels;
  }
  return ok;
}

// UI phase: the overlay's windows; a knob edit applies live, "Restart" rebuilds the world.
void drawUi(Session& s, const std::filesystem::path& content_dir) {
  const engine::ScopedPhase phase(s.profiler, engine::Phase::ui);
  if (s.overlay.mode == engine::OverlayMode::hidden) return;
  engine::beginOverlayFrame(s.overlay);
  char graphics[160];
  std::snprintf(graphics, sizeof graphics, "%s; graphics %s, %dx%d of %dx%d", s.platform.gl_renderer.c_str(),
                s.graphics.preset.c_str(), s.renderer.width, s.renderer.height, viewWidth(s), viewHeight(s));
  const auto [changed, restart] = drawGameOverlay(s.world, s.overlay, s.profiler, graphics);
  if (s.options.hooks.draw_overlay) s.options.hooks.draw_overlay();
  engine::endOverlayFrame(s.overlay);
  engine::checkGl(s.renderer.errors, "overlay");
  if (changed) applyLiveParams(s.world);
  if (!restart) return;
  const SceneConfig edited = s.world.scene;
  const engine::FpsCamera camera = s.world.camera;
  std::string rebuild_error;
  detachWorldGpu(s.world);
  if (buildWorld(edited, content_dir, s.world, rebuild_error) && applyGraphicsPreset(s, rebuild_error)) {
    s.world.camera = camera;
    s.report.systems_constructed = s.world.systems;
    attachWorldGpu(s.world, shaderDirectory(), content_dir);
  } else {
    std::fprintf(stderr, "fluiddemo: restart failed: %s\n", rebuild_error.c_str());
  }
}

// After the frame: the hook sees its steps and timings; false ends the run.
bool afterFrame(Session& s, int frame, int steps) {
  if (!s.options.hooks.after_frame) return true;
  FrameResult result{s.world, frame, steps, {}, 0.0};
  for (int p = 0; p < engine::kPhaseCount; ++p) result.phase_ms[p] = s.profiler.current_ms[p];
  const int last = (s.profiler.head - 1 + engine::Profiler::kHistory) % engine::Profiler::kHistory;
  result.frame_ms = s.profiler.frame_history[last];
  if (s.options.hooks.after_frame(result)) return true;
  s.report.stopped_by_hook = true;
  return false;
}

void fillReport(const Session& s, std::uint64_t steps_done, RunReport& report) {
  report.simulation_steps = steps_done;
  report.graphics_preset = s.graphics.preset;
  report.scene_width = s.renderer.width;
  report.scene_height = s.renderer.height;
  report.nonfinite_state = s.world.nonfinite_state;
  report.runtime_failures = s.world.failures.count;
  report.first_failure = s.world.failures.first;
  report.last_failure = s.world.failures.last;
  report.mean_frame_ms = engine::frameMeanMs(s.profiler);
  fillSphHealth(s.world, s.profiler, report);
  for (int p = 0; p < engine::kPhaseCount; ++p) {
    const auto phase = static_cast<engine::Phase>(p);
    PhaseTiming timing;
    timing.phase = std::string(engine::phaseName(phase));
    timing.mean_ms = engine::phaseMeanMs(s.profiler, phase);
    timing.max_ms = s.profiler.stats[p].max_ms;
    timing.samples = s.profiler.stats[p].frames;
    report.phases.push_back(timing);
  }
}

// The frame loop, with the renderer, the level's assets and the overlay created. Returns the
// exit code.
int runFrames(Session& s, const std::filesystem::path& content_dir, engine::FramePasses& passes, std::string& error) {
  const RunOptions& options = s.options;
  World& world = s.world;
  engine::FixedStepDesc clock_desc;
  clock_desc.step_seconds = world.step_seconds;
  clock_desc.substeps = world.substeps;
  clock_desc.max_steps_per_frame = world.scene.scene.integer("max_steps_per_frame");
  engine::FixedStepClock clock = engine::makeFixedStepClock(clock_desc);
  engine::FrameBatches batches;
  std::vector<engine::WaterStats> water_stats;  // what each frame's water passes tell back
  auto last_time = std::chrono::steady_clock::now();
  std::uint64_t steps_done = 0;
  int code = 0;
  for (int frame = 0; options.frames <= 0 || frame < options.frames; ++frame) {
    engine::beginFrame(s.profiler);
    const auto now = std::chrono::steady_clock::now();
    const double real_dt = std::chrono::duration<double>(now - last_time).count();
    last_time = now;
    const double frame_dt = options.fixed_frame_time ? world.step_seconds : real_dt;
    if (!readInput(s, frame, frame_dt, error)) code = 1;
    if (s.input.quit || code != 0) {
      engine::endFrame(s.profiler);
      break;
    }
    const int steps = engine::advanceFrame(clock, frame_dt);
    for (int i = 0; i < steps; ++i) {
      stepWorld(world, &s.profiler);
      advanceFlash(s.flash, world);
    }
    lightFlash(s.flash, s.lighting);
    steps_done += static_cast<std::uint64_t>(steps);
    // With a fixed frame time the accumulator is always empty: show the newest state.
    const float alpha = options.fixed_frame_time ? 1.0f : static_cast<float>(engine::interpolationAlpha(clock));
    meshWorld(world, &s.profiler);  // meshing phase; no-op without fluid_surface
    const bool last_frame = options.frames > 0 && frame + 1 == options.frames;
    {
      const engine::ScopedPhase phase(s.profiler, engine::Phase::render);
      engine::FrameView view;
      view.view = engine::cameraView(world.camera);
      view.projection = engine::cameraProjection(
          world.camera, static_cast<float>(s.renderer.width) / static_cast<float>(s.renderer.height));
      view.eye = world.camera.position;
      view.near_plane = world.camera.near_plane;
      view.far_plane = world.camera.far_plane;
      batches.clear();
      submitLevel(s.assets, batches);
      submitWorld(world, batches, s.assets, alpha);
      engine::renderFrame(s.renderer, passes, view, s.lighting, batches);
      engine::lastWaterStats(passes, water_stats);
      readWorldRenderStats(world, water_stats);
      if (!writeImages(s, view, last_frame, error)) code = 1;
      // Headless there is nobody to show the window to; the scene FBO is the output.
      if (!s.platform.headless) engine::presentToWindow(s.renderer, s.platform.width, s.platform.height);
    }
    drawUi(s, content_dir);
    engine::swapWindow(s.platform);
    engine::endFrame(s.profiler);
    ++s.report.frames_rendered;
    if (code != 0 || !afterFrame(s, frame, steps)) break;
  }
  fillReport(s, steps_done, s.report);
  engine::checkGl(s.renderer.errors, "end of run");
  return code;
}

}  // namespace

int runScene(const SceneConfig& scene, const RunOptions& options, RunReport& report, std::string& error) {
  report = RunReport{};
  const std::filesystem::path content_dir = contentDir();
  World world;
  if (!buildWorld(scene, content_dir, world, error)) return 1;
  report.systems_constructed = world.systems;

  engine::PlatformDesc platform_desc;
  platform_desc.width = options.width;
  platform_desc.height = options.height;
  platform_desc.headless = options.headless;
#ifdef FLUIDDEMO_GL_DEBUG
  platform_desc.debug_context = true;
#endif
  engine::Platform platform;
  if (!engine::createPlatform(platform_desc, platform, error)) return 1;
  report.gl_renderer = platform.gl_renderer;
#ifdef FLUIDDEMO_GL_DEBUG
  engine::enableDebugOutput();
#endif
  int code = 1;
  {
    // GL objects live in this scope so they die before the context.
    const int fb_width = viewWidth(options, platform), fb_height = viewHeight(options, platform);
    engine::Renderer renderer;
    LevelAssets assets;
    engine::Overlay overlay;
    engine::FramePasses passes;
    passes.shader_dir = shaderDirectory();
    // The graphics preset for this renderer: the scene target's scale and the shadow map below.
    const GraphicsSettings graphics = presetWorld(world, scene, platform.gl_renderer);
    // Without a preset's own size: llvmpipe (headless CI) pays for every shadow texel it clears, and
    // 1024 is plenty at 720p there.
    const int shadow_size = graphics.shadow_size > 0 ? graphics.shadow_size : (options.headless ? 1024 : 2048);
    if (engine::createRenderer(shaderDirectory(), scaled(fb_width, graphics), scaled(fb_height, graphics), renderer,
                               error, shadow_size) &&
        loadLevelAssets(content_dir, world.scene.scene.text("level"), assets, error) &&
        engine::createOverlay(platform, overlay, error)) {
      attachWorldGpu(world, shaderDirectory(), content_dir);
      overlay.mode = options.show_ui ? engine::OverlayMode::compact : engine::OverlayMode::hidden;
      Session session{options, scene, report, world, platform, renderer, overlay, assets, graphics};
      code = runFrames(session, content_dir, passes, error);
      // The effects' GL objects are freed while the context is still current.
      detachWorldGpu(world);
    }
    engine::releaseFramePasses(passes);
    report.gl_errors = renderer.errors.count;
    if (renderer.errors.count > 0)
      std::fprintf(stderr, "fluiddemo: first GL error: %s\n", renderer.errors.first.c_str());
    engine::destroyOverlay(overlay);
  }
  engine::destroyPlatform(platform);
  return code;
}

}  // namespace game
