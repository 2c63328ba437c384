// Graphics presets (game/graphics_settings.hpp, issue 35 item 5): auto picks low on a software
// renderer and high on a GPU; an explicit resolution scale wins over the preset's; the preset sets
// only render-only keys, from the loaded scene's values, so applying it again changes nothing.
#include "game/graphics_settings.hpp"
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"

#include <gtest/gtest.h>

namespace {

game::SceneConfig fountain() {
  game::SceneConfig scene;
  const game::SceneStatus st = game::loadSceneFile(game::scenesDir() / "fountain.json", scene);
  EXPECT_TRUE(st.ok()) << st.error;
  return scene;
}

TEST(GraphicsSettings, AutoIsLowOnASoftwareRendererAndHighOnAGpu) {
  const game::SceneConfig scene = fountain();
  EXPECT_EQ(scene.graphics.text("preset"), "auto");
  const game::GraphicsSettings cpu = game::resolveGraphics(scene.graphics, "llvmpipe (LLVM 15.0.6, 256 bits)");
  EXPECT_EQ(cpu.preset, "low");
  EXPECT_FLOAT_EQ(cpu.resolution_scale, 0.5f);
  const game::GraphicsSettings gpu = game::resolveGraphics(scene.graphics, "NVIDIA H200/PCIe/SSE2");
  EXPECT_EQ(gpu.preset, "high");
  EXPECT_FLOAT_EQ(gpu.resolution_scale, 1.0f);
  EXPECT_TRUE(game::softwareRenderer("SwiftShader Device (Subzero)"));
  EXPECT_FALSE(game::softwareRenderer("AMD Radeon RX 7900 XTX"));
}

TEST(GraphicsSettings, AnExplicitPresetAndScaleWin) {
  game::SceneConfig scene = fountain();
  ASSERT_TRUE(game::applyOverride(scene, "graphics.preset=medium").ok());
  EXPECT_EQ(game::resolveGraphics(scene.graphics, "llvmpipe").preset, "medium");
  ASSERT_TRUE(game::applyOverride(scene, "graphics.resolution_scale=0.3").ok());
  EXPECT_FLOAT_EQ(game::resolveGraphics(scene.graphics, "llvmpipe").resolution_scale, 0.3f);
  const game::SceneStatus bad = game::applyOverride(scene, "graphics.preset=ultra");
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.error.find("ultra"), std::string::npos) << bad.error;
}

// Low coarsens the lattice to a spacing, turns refraction off and halves the sprites born (foam too); it
// touches nothing else, and a second application (a restart) gives the same scene.
TEST(GraphicsSettings, APresetSetsOnlyRenderOnlyKeysFromTheLoadedScene) {
  const game::SceneConfig loaded = fountain();
  game::SceneConfig scene = loaded;
  game::SceneConfig low_scene = loaded;
  ASSERT_TRUE(game::applyOverride(low_scene, "graphics.preset=low").ok());
  const game::GraphicsSettings low = game::resolveGraphics(low_scene.graphics, "any GPU");
  game::applyGraphics(low, loaded, scene);
  const game::SectionConfig& surface = *scene.effect("fluid_surface");
  const game::SectionConfig& sprites = *scene.effect("sprite_particles");
  EXPECT_DOUBLE_EQ(surface.number("cube"), 1.0);
  EXPECT_DOUBLE_EQ(surface.number("refraction"), 0.0);
  EXPECT_DOUBLE_EQ(sprites.number("rate"), 0.5 * loaded.effect("sprite_particles")->number("rate"));
  EXPECT_DOUBLE_EQ(sprites.number("spray_rate"), 0.5 * loaded.effect("sprite_particles")->number("spray_rate"));
  for (const char* foam : {"foam_trapped_air_rate", "foam_wave_crest_rate"}) {
    EXPECT_GT(loaded.effect("sprite_particles")->number(foam), 0.0) << foam;
    EXPECT_DOUBLE_EQ(sprites.number(foam), 0.5 * loaded.effect("sprite_particles")->number(foam)) << foam;
  }
  // Everything outside those six keys is the loaded scene's, value for value.
  for (std::size_t e = 0; e < loaded.effects.size(); ++e) {
    for (const auto& [key, value] : loaded.effects[e].params) {
      const std::string path = loaded.effects[e].name + "." + key;
      if (path == "fluid_surface.cube" || path == "fluid_surface.refraction" || path == "sprite_particles.rate" ||
          path == "sprite_particles.spray_rate" || path == "sprite_particles.foam_trapped_air_rate" ||
          path == "sprite_particles.foam_wave_crest_rate")
        continue;
      const game::ParamValue& now = scene.effects[e].params.at(key);
      EXPECT_TRUE(now.number == value.number && now.boolean == value.boolean && now.text == value.text &&
                  now.vec == value.vec)
          << path;
    }
  }
  game::SceneConfig again = scene;
  game::applyGraphics(low, loaded, again);
  EXPECT_DOUBLE_EQ(again.effect("sprite_particles")->number("rate"), sprites.number("rate"));
  EXPECT_DOUBLE_EQ(again.effect("fluid_surface")->number("cube"), 1.0);
  // High gives the loaded values back.
  const game::GraphicsSettings high = game::resolveGraphics(loaded.graphics, "any GPU");
  game::applyGraphics(high, loaded, again);
  EXPECT_DOUBLE_EQ(again.effect("fluid_surface")->number("cube"), loaded.effect("fluid_surface")->number("cube"));
  EXPECT_DOUBLE_EQ(again.effect("fluid_surface")->number("refraction"),
                   loaded.effect("fluid_surface")->number("refraction"));
}

}  // namespace
