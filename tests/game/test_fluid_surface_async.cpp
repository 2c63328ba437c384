// fluid_surface.async (Janisz §3.2.6): the surface drawn at frame N is the one the synchronous
// mesher gives for frame N-1's particles, bit for bit (frame 0: its own), so the worker thread
// changes when a surface is shown, never what it is; with spheres and with anisotropic kernels.
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fluid_surface.hpp"
#include "game/world/world.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

game::SceneConfig fountainScene(bool async, bool anisotropic = false) {
  const std::string text = std::string(R"({"effects": {"sph_fluid": {"max_particles": 900},
                                                       "fluid_surface": {"async": )") +
                           (async ? "true" : "false") + (anisotropic ? R"(, "kernel": "anisotropic", "k_n": 8)" : "") + "}}}";
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "async_test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

class FluidSurfaceAsync : public ::testing::TestWithParam<bool> {};

// With kernel = anisotropic the worker makes the kernels itself from its copy of the positions
// (SurfaceKernelJob); the surface must still be the synchronous one of the frame before.
TEST_P(FluidSurfaceAsync, DrawsThePreviousFramesSurfaceBitForBit) {
  const bool anisotropic = GetParam();
  game::World sync_world, async_world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(fountainScene(false, anisotropic), game::contentDir(), sync_world, error)) << error;
  ASSERT_TRUE(game::buildWorld(fountainScene(true, anisotropic), game::contentDir(), async_world, error)) << error;
  const game::FluidSurface& sync_surface = *game::findState<game::FluidSurface>(sync_world);
  const game::FluidSurface& async_surface = *game::findState<game::FluidSurface>(async_world);
  fluid::SurfaceMesh previous;  // the synchronous surface of the frame before
  int compared = 0;
  for (int frame = 0; frame < 90; ++frame) {
    game::stepWorld(sync_world, nullptr);
    game::stepWorld(async_world, nullptr);
    game::meshWorld(sync_world, nullptr);
    game::meshWorld(async_world, nullptr);
    ASSERT_EQ(async_surface.error, "") << "frame " << frame;
    const fluid::SurfaceMesh& expected = frame == 0 ? sync_surface.job.mesh : previous;
    ASSERT_EQ(test_support::meshBitsDiffer(async_surface.job.mesh, expected), "") << "frame " << frame;
    compared += expected.indices.empty() ? 0 : 1;
    previous = sync_surface.job.mesh;
  }
  EXPECT_GE(compared, 80) << "the jet has a surface in almost every frame";
  EXPECT_EQ(async_surface.meshes, 90u);
  EXPECT_EQ(async_world.failures.count, 0u);
  if (anisotropic) {  // the kernels were made (on the worker) and stretch part of the thin 900-particle pool
    EXPECT_GT(async_surface.kernel_ms, 0.0);
    EXPECT_GT(sync_surface.kernels_stretched, 0u);
    EXPECT_GT(async_surface.kernels_stretched, 0u);
  } else {
    EXPECT_EQ(async_surface.kernel_ms, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, FluidSurfaceAsync, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "anisotropic" : "isotropic";
                         });

}  // namespace
