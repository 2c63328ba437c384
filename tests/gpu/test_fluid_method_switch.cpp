// The fluid_surface.method switch end to end: the schema accepts the three methods and refuses
// others naming the key, the CPU mesher is skipped for the particle renderers, and the fountain
// runs headless with each method drawing water (frame differs from the same run without
// fluid_surface) and no GL error.
#include "game/paths.hpp"
#include "game/run_scene.hpp"
#include "game/scene/scene_config.hpp"
#include "engine/fluid_render/water_backend.hpp"
#include "game/world/fluid_surface.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>

namespace {

game::SceneConfig fountain() {
  game::SceneConfig scene;
  const game::SceneStatus st = game::loadSceneFile(game::scenesDir() / "fountain.json", scene);
  EXPECT_TRUE(st.ok()) << st.error;
  return scene;
}

// A headless run of `frames` fixed steps at 160x90 that keeps its last frame.
game::RunOptions headlessCapture(int frames) {
  setenv("SDL_VIDEODRIVER", "offscreen", 1);
  game::RunOptions options;
  options.width = 160;
  options.height = 90;
  options.headless = true;
  options.frames = frames;
  options.show_ui = false;
  options.capture_last_frame = true;
  options.fixed_frame_time = true;
  return options;
}

}  // namespace

// The scene key's choices are the engine's water backends (engine/fluid_render/water_backends.cpp):
// a backend added there is a method here, with nothing else to edit.
TEST(FluidMethodSwitch, SchemaAcceptsTheEnginesWaterBackendsOnly) {
  ASSERT_GE(engine::waterBackendNames().size(), 3u);
  for (std::string_view m : engine::waterBackendNames()) {
    game::SceneConfig scene = fountain();
    const game::SceneStatus st = game::applyOverride(scene, "fluid_surface.method=" + std::string(m));
    ASSERT_TRUE(st.ok()) << st.error;
    game::FluidSurfaceParams p;
    std::string error;
    ASSERT_TRUE(game::surfaceParamsFrom(*scene.effect("fluid_surface"), p, error)) << error;
    EXPECT_EQ(p.method, m);
  }
  game::SceneConfig scene = fountain();
  const game::SceneStatus st = game::applyOverride(scene, "fluid_surface.method=voxels");
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.error.find("voxels"), std::string::npos) << st.error;
}

// Frames of the fountain at 160x90 after 90 steps (the jet has water in the dish by then).
TEST(FluidMethodSwitch, EachMethodRunsTheFountainHeadless) {
  const game::RunOptions options = headlessCapture(90);
  auto run = [&](const char* method, game::RunReport& report) {
    game::SceneConfig scene = fountain();
    if (method != nullptr) {
      ASSERT_TRUE(game::applyOverride(scene, std::string("fluid_surface.method=") + method).ok());
    } else {
      scene.effects.erase(std::remove_if(scene.effects.begin(), scene.effects.end(),
                                         [](const game::SectionConfig& s) { return s.name == "fluid_surface"; }),
                          scene.effects.end());
    }
    std::string error;
    ASSERT_EQ(game::runScene(scene, options, report, error), 0) << error;
    EXPECT_EQ(report.gl_errors, 0);
    EXPECT_TRUE(report.nonfinite_state.empty()) << report.nonfinite_state;
  };
  game::RunReport dry;
  run(nullptr, dry);
  for (std::string_view name : engine::waterBackendNames()) {
    const std::string method(name);
    game::RunReport report;
    run(method.c_str(), report);
    ASSERT_EQ(report.last_frame_rgba.size(), dry.last_frame_rgba.size());
    std::size_t changed = 0;
    for (std::size_t p = 0; p < report.last_frame_rgba.size(); p += 4)
      for (std::size_t c = 0; c < 3; ++c)
        if (std::abs(int(report.last_frame_rgba[p + c]) - int(dry.last_frame_rgba[p + c])) > 8) {
          ++changed;
          break;
        }
    std::printf("[ metric ] %s: %zu of %zu px differ from the run without fluid_surface\n", method.c_str(), changed,
                report.last_frame_rgba.size() / 4);
    EXPECT_GT(changed, 20u) << method;
    double meshing_ms = 0.0;
    for (const game::PhaseTiming& t : report.phases)
      if (t.phase == "meshing") meshing_ms = t.mean_ms;
    if (!engine::findWaterBackend(method)->needs_mesh) {
      EXPECT_LT(meshing_ms, 0.05) << method << ": the mesher should be skipped";
    }
  }
}

// The graphics preset (game/graphics_settings.hpp): auto draws llvmpipe at low, the scene at half
// the frame's size, yet the captured frame is the requested size; the water is drawn at every
// preset and no GL error occurs.
TEST(GraphicsPresets, EachPresetDrawsTheFountainAtTheRequestedSize) {
  const game::RunOptions options = headlessCapture(60);
  for (const char* preset : {"auto", "low", "medium", "high"}) {
    game::SceneConfig scene = fountain();
    ASSERT_TRUE(game::applyOverride(scene, std::string("graphics.preset=") + preset).ok());
    game::RunReport report;
    std::string error;
    ASSERT_EQ(game::runScene(scene, options, report, error), 0) << error;
    EXPECT_EQ(report.gl_errors, 0) << preset;
    EXPECT_EQ(report.frame_width, 160) << preset;
    EXPECT_EQ(report.frame_height, 90) << preset;
    EXPECT_EQ(report.last_frame_rgba.size(), 160u * 90u * 4u) << preset;
    const bool software = report.gl_renderer.find("llvmpipe") != std::string::npos;
    const std::string expected = std::string(preset) == "auto" ? (software ? "low" : "high") : preset;
    EXPECT_EQ(report.graphics_preset, expected) << report.gl_renderer;
    std::printf("[ metric ] preset %s -> %s on %s\n", preset, report.graphics_preset.c_str(), report.gl_renderer.c_str());
  }
}
