// fluid_surface.field: how the game's mesher sums a corner's field (fluid::SurfaceFieldRoute). The
// routes are exact, so the key may change what a frame costs but never what the player sees: the
// game's meshes are compared bit for bit, and the stats show which route ran.
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fluid_surface.hpp"
#include "game/world/world.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

game::SceneStatus parseFountain(const std::string& field, game::SceneConfig& scene) {
  const std::string text = R"({"effects": {"sph_fluid": {"max_particles": 900},
                                           "fluid_surface": {"async": false)" +
                           (field.empty() ? std::string() : ", \"field\": \"" + field + "\"") + "}}}";
  return game::parseSceneText(text, "field_test.json", scene);
}

TEST(FluidSurfaceField, SliceSplatByDefaultAndEachNameReachesTheMesher) {
  const game::FluidSurfaceParams defaults;
  EXPECT_EQ(defaults.field, fluid::SurfaceFieldRoute::sliceSplat);
  const struct {
    const char* name;
    fluid::SurfaceFieldRoute route;
  } cases[] = {{"splat", fluid::SurfaceFieldRoute::sliceSplat},
               {"cache", fluid::SurfaceFieldRoute::particleCache},
               {"auto", fluid::SurfaceFieldRoute::automatic}};
  for (const auto& c : cases) {
    game::SceneConfig scene;
    const game::SceneStatus status = parseFountain(c.name, scene);
    ASSERT_TRUE(status.ok()) << c.name << ": " << status.error;
    game::World world;
    std::string error;
    ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
    const game::FluidSurface& surface = *game::findState<game::FluidSurface>(world);
    EXPECT_EQ(surface.params.field, c.route) << c.name;
    EXPECT_EQ(game::surfaceParamsFor(surface.params, 0.08f, {}, {0, 0, -1}).fieldRoute, c.route) << c.name;
  }
}

TEST(FluidSurfaceField, SplatAndCacheMeshTheGamesFramesBitForBit) {
  game::SceneConfig splat_scene, cache_scene;
  ASSERT_TRUE(parseFountain("splat", splat_scene).ok());
  ASSERT_TRUE(parseFountain("cache", cache_scene).ok());
  game::World splat_world, cache_world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(splat_scene, game::contentDir(), splat_world, error)) << error;
  ASSERT_TRUE(game::buildWorld(cache_scene, game::contentDir(), cache_world, error)) << error;
  const game::FluidSurface& splat = *game::findState<game::FluidSurface>(splat_world);
  const game::FluidSurface& cache = *game::findState<game::FluidSurface>(cache_world);
  int meshed = 0;
  for (int frame = 0; frame < 120; ++frame) {
    game::stepWorld(splat_world, nullptr);
    game::stepWorld(cache_world, nullptr);
    game::meshWorld(splat_world, nullptr);
    game::meshWorld(cache_world, nullptr);
    ASSERT_EQ(splat.error, "") << "frame " << frame;
    ASSERT_EQ(cache.error, "") << "frame " << frame;
    ASSERT_EQ(test_support::meshBitsDiffer(splat.mesh, cache.mesh), "") << "frame " << frame;
    if (splat.mesh.indices.empty()) continue;
    ++meshed;
    // Which route ran: every block of the splat world by slice splat, none of the cache world's.
    EXPECT_EQ(splat.mesh.stats.splatBlocks, splat.mesh.stats.blocks) << "frame " << frame;
    EXPECT_EQ(cache.mesh.stats.splatBlocks, 0u) << "frame " << frame;
  }
  EXPECT_GE(meshed, 100) << "the jet has a surface in almost every frame";
}

TEST(FluidSurfaceField, AnUnknownRouteIsRefusedNamingTheKeyAndValue) {
  game::SceneConfig scene;
  const game::SceneStatus status = parseFountain("dense", scene);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error.find("field"), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("dense"), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("splat"), std::string::npos) << status.error;
}

}  // namespace
