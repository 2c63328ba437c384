// fluid_surface.field: how the game's mesher finds the surface (fluid::SurfaceFieldRoute). The
// exact routes may change what a frame costs but never what the player sees: the walking routes'
// meshes are compared bit for bit, the dense scan's vertex by vertex (it emits the same triangles
// in another order within a slab); the value scan cuts the same lattice edges with other normals;
// and the stats show which route ran.
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fluid_surface.hpp"
#include "game/world/world.hpp"
#include "tests/support/mesh_bits.hpp"
#include "tests/surface/mesh_checks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

namespace {

// Triangles with their vertices' bits (edge key, position, normal), and as edge-key triples alone;
// both sorted, so meshes emitted in another order compare equal.
using surface_test::canonicalTriangles;
using surface_test::trianglesWithVertexBits;

game::SceneStatus parseFountain(const std::string& field, game::SceneConfig& scene) {
  const std::string text = R"({"effects": {"sph_fluid": {"max_particles": 900},
                                           "fluid_surface": {"async": false)" +
                           (field.empty() ? std::string() : ", \"field\": \"" + field + "\"") + "}}}";
  return game::parseSceneText(text, "field_test.json", scene);
}

// Fountain worlds, one per route name, stepped and meshed together frame by frame (the
// simulation is deterministic, so they mesh the same particles).
struct RouteWorlds {
  std::vector<std::unique_ptr<game::World>> worlds;
  std::vector<const game::FluidSurface*> surfaces;
  void stepAndMesh() {
    for (auto& w : worlds) {
      game::stepWorld(*w, nullptr);
      game::meshWorld(*w, nullptr);
    }
  }
};
::testing::AssertionResult buildRouteWorlds(std::initializer_list<const char*> routes, RouteWorlds& out) {
  for (const char* route : routes) {
    game::SceneConfig scene;
    if (const game::SceneStatus status = parseFountain(route, scene); !status.ok())
      return ::testing::AssertionFailure() << route << ": " << status.error;
    auto world = std::make_unique<game::World>();
    std::string error;
    if (!game::buildWorld(scene, game::contentDir(), *world, error))
      return ::testing::AssertionFailure() << route << ": " << error;
    out.surfaces.push_back(game::findState<game::FluidSurface>(*world));
    out.worlds.push_back(std::move(world));
  }
  return ::testing::AssertionSuccess();
}

TEST(FluidSurfaceField, DenseScanByDefaultAndEachNameReachesTheMesher) {
  const game::FluidSurfaceParams defaults;
  EXPECT_EQ(defaults.field, fluid::SurfaceFieldRoute::denseScan);
  const struct {
    const char* name;
    fluid::SurfaceFieldRoute route;
  } cases[] = {{"", fluid::SurfaceFieldRoute::denseScan},
               {"dense", fluid::SurfaceFieldRoute::denseScan},
               {"splat", fluid::SurfaceFieldRoute::sliceSplat},
               {"cache", fluid::SurfaceFieldRoute::particleCache},
               {"value", fluid::SurfaceFieldRoute::valueScan},
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
  RouteWorlds w;
  ASSERT_TRUE(buildRouteWorlds({"splat", "cache"}, w));
  const game::FluidSurface &splat = *w.surfaces[0], &cache = *w.surfaces[1];
  int meshed = 0;
  for (int frame = 0; frame < 120; ++frame) {
    w.stepAndMesh();
    ASSERT_EQ(splat.error, "") << "frame " << frame;
    ASSERT_EQ(cache.error, "") << "frame " << frame;
    ASSERT_EQ(test_support::meshBitsDiffer(splat.job.mesh, cache.job.mesh), "") << "frame " << frame;
    if (splat.job.mesh.indices.empty()) continue;
    ++meshed;
    // Which route ran: every block of the splat world by slice splat, none of the cache world's.
    EXPECT_EQ(splat.job.mesh.stats.splatBlocks, splat.job.mesh.stats.blocks) << "frame " << frame;
    EXPECT_EQ(cache.job.mesh.stats.splatBlocks, 0u) << "frame " << frame;
  }
  EXPECT_GE(meshed, 100) << "the jet has a surface in almost every frame";
}

TEST(FluidSurfaceField, DenseScanDrawsTheSplatWalksTrianglesOnTheGamesFrames) {
  RouteWorlds w;
  ASSERT_TRUE(buildRouteWorlds({"dense", "splat"}, w));
  const game::FluidSurface &dense = *w.surfaces[0], &splat = *w.surfaces[1];
  int meshed = 0;
  for (int frame = 0; frame < 120; ++frame) {
    w.stepAndMesh();
    ASSERT_EQ(dense.error, "") << "frame " << frame;
    ASSERT_EQ(dense.job.mesh.indices.size(), splat.job.mesh.indices.size()) << "frame " << frame;
    ASSERT_TRUE(trianglesWithVertexBits(dense.job.mesh) == trianglesWithVertexBits(splat.job.mesh))
        << "frame " << frame;
    if (dense.job.mesh.indices.empty()) continue;
    ++meshed;
    EXPECT_EQ(dense.job.mesh.stats.scannedBlocks, dense.job.mesh.stats.blocks) << "frame " << frame;
    EXPECT_EQ(splat.job.mesh.stats.scannedBlocks, 0u) << "frame " << frame;
  }
  EXPECT_GE(meshed, 100) << "the jet has a surface in almost every frame";
}

TEST(FluidSurfaceField, ValueScanCutsTheDenseScansEdgesOnTheGamesFrames) {
  // The value scan's corner values are the dense scan's up to float rounding (a float predicate
  // and another order of additions), so the same lattice edges are cut unless a corner sits
  // within rounding of T; its normals come from central differences, so only edges are compared.
  RouteWorlds w;
  ASSERT_TRUE(buildRouteWorlds({"dense", "value"}, w));
  const game::FluidSurface &dense = *w.surfaces[0], &value = *w.surfaces[1];
  int meshed = 0, same = 0;
  for (int frame = 0; frame < 120; ++frame) {
    w.stepAndMesh();
    ASSERT_EQ(value.error, "") << "frame " << frame;
    if (dense.job.mesh.indices.empty()) continue;
    ++meshed;
    EXPECT_EQ(value.job.mesh.stats.scannedBlocks, value.job.mesh.stats.blocks) << "frame " << frame;
    same += canonicalTriangles(value.job.mesh) == canonicalTriangles(dense.job.mesh);
    for (const glm::vec3& n : value.job.mesh.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-3f) << "frame " << frame;
  }
  EXPECT_GE(meshed, 100) << "the jet has a surface in almost every frame";
  EXPECT_GE(same, meshed - 2) << "the value scan cut other edges than the dense scan on " << meshed - same << " frames";
}

// The key is live (the overlay's combo): switching the route between frames of one world, the
// extractor's scratch switching with it, meshes exactly what a world on one route meshes: the
// splat walk's bits on splat and cache frames, its triangles and vertex bits in the dense scan's
// order on dense frames, and a world fixed on the value scan's bits on value frames.
TEST(FluidSurfaceField, SwitchingTheRouteLiveEveryFrameKeepsTheMeshes) {
  RouteWorlds w;
  ASSERT_TRUE(buildRouteWorlds({"splat", "value", "splat"}, w));  // fixed, fixed, switching
  game::World& switching_world = *w.worlds[2];
  game::SectionConfig* section = nullptr;
  for (game::SectionConfig& effect : switching_world.scene.effects)
    if (effect.name == "fluid_surface") section = &effect;
  ASSERT_NE(section, nullptr);
  const game::FluidSurface &fixed = *w.surfaces[0], &value = *w.surfaces[1], &switching = *w.surfaces[2];
  const struct {
    const char* name;
    fluid::SurfaceFieldRoute route;
  } cycle[] = {{"splat", fluid::SurfaceFieldRoute::sliceSplat},
               {"cache", fluid::SurfaceFieldRoute::particleCache},
               {"dense", fluid::SurfaceFieldRoute::denseScan},
               {"splat", fluid::SurfaceFieldRoute::sliceSplat},
               {"value", fluid::SurfaceFieldRoute::valueScan}};
  int frames_by_route[5] = {};
  for (int frame = 0; frame < 100; ++frame) {
    const auto& pick = cycle[frame % 5];
    section->params["field"].text = pick.name;
    game::applyLiveParams(switching_world);
    ASSERT_EQ(switching.params.field, pick.route) << "frame " << frame;
    w.stepAndMesh();
    ASSERT_EQ(switching.error, "") << "frame " << frame;
    const fluid::SurfaceMesh& got = switching.job.mesh;
    if (pick.route == fluid::SurfaceFieldRoute::valueScan) {
      ASSERT_EQ(test_support::meshBitsDiffer(got, value.job.mesh), "") << "frame " << frame;
    } else if (pick.route == fluid::SurfaceFieldRoute::denseScan) {
      ASSERT_TRUE(trianglesWithVertexBits(got) == trianglesWithVertexBits(fixed.job.mesh)) << "frame " << frame;
    } else {
      ASSERT_EQ(test_support::meshBitsDiffer(got, fixed.job.mesh), "") << "frame " << frame;
    }
    if (got.indices.empty()) continue;
    ++frames_by_route[frame % 5];
    const bool walked = pick.route == fluid::SurfaceFieldRoute::sliceSplat ||
                        pick.route == fluid::SurfaceFieldRoute::particleCache;
    EXPECT_EQ(got.stats.scannedBlocks, walked ? 0u : got.stats.blocks) << "frame " << frame;
    EXPECT_EQ(got.stats.splatBlocks, pick.route == fluid::SurfaceFieldRoute::particleCache ? 0u : got.stats.blocks)
        << "frame " << frame;
  }
  for (int k = 0; k < 5; ++k) EXPECT_GE(frames_by_route[k], 15) << cycle[k].name;
}

TEST(FluidSurfaceField, AnUnknownRouteIsRefusedNamingTheKeyAndValue) {
  game::SceneConfig scene;
  const game::SceneStatus status = parseFountain("flying_edges", scene);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error.find("field"), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("flying_edges"), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("dense"), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("splat"), std::string::npos) << status.error;
}

}  // namespace
