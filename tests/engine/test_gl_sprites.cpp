// The sprite_particles effect on the GPU (engine/gpu_particles) inside the game, headless GL:
// gating of its GL resources, and the fountain's sprites alive, finite, outside the baked
// colliders and visible in the frame.
#include "engine/gl/gl.hpp"
#include "engine/platform/platform.hpp"
#include "game/paths.hpp"
#include "game/run_scene.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace {

namespace fs = std::filesystem;

const fs::path kShaders = fs::path(FLUIDDEMO_SOURCE_DIR) / "shaders";

game::SceneConfig parse(const std::string& text) {
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

// GL objects that exist in the current context among the names 1..4095 (Mesa hands out small
// names first): textures, framebuffers, buffers, programs and vertex arrays.
int countGlObjects() {
  int n = 0;
  for (GLuint id = 1; id < 4096; ++id) {
    n += glIsTexture(id) + glIsFramebuffer(id) + glIsBuffer(id) + glIsProgram(id) + glIsVertexArray(id);
  }
  return n;
}

class SpriteGl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { setenv("SDL_VIDEODRIVER", "offscreen", 0); }
  void SetUp() override {
    engine::PlatformDesc desc;
    desc.width = 64;
    desc.height = 64;
    desc.headless = true;
    std::string error;
    ASSERT_TRUE(engine::createPlatform(desc, platform_, error)) << error;
  }
  void TearDown() override { engine::destroyPlatform(platform_); }
  engine::Platform platform_;
};

TEST_F(SpriteGl, ASceneWithoutSpritesCreatesNoGlParticleResources) {
  const int before = countGlObjects();
  std::string error;
  {
    game::World world;
    ASSERT_TRUE(
        game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 1}}})"), game::contentDir(), world, error))
        << error;
    game::attachWorldGpu(world, kShaders, game::contentDir());
    for (int i = 0; i < 3; ++i) game::stepWorld(world, nullptr);
    EXPECT_EQ(game::findState<game::SpriteParticles>(world), nullptr);
    EXPECT_EQ(countGlObjects(), before) << "a scene without sprite_particles created GL objects";
    game::detachWorldGpu(world);
  }
  {
    // A zero budget is "no sprites" too: the effect is listed but creates nothing on the GPU.
    game::World world;
    ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {"sprite_particles": {"max_particles": 0}}})"),
                                 game::contentDir(), world, error))
        << error;
    game::attachWorldGpu(world, kShaders, game::contentDir());
    game::stepWorld(world, nullptr);
    EXPECT_EQ(countGlObjects(), before);
    EXPECT_EQ(game::liveSprites(*game::findState<game::SpriteParticles>(world)), 0u);
  }
  // The positive control: the same count sees the sprites' textures, FBOs and programs, and
  // detaching frees every one of them.
  game::World world;
  ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {"sprite_particles": {"max_particles": 1000}}})"),
                               game::contentDir(), world, error))
      << error;
  game::attachWorldGpu(world, kShaders, game::contentDir());
  ASSERT_TRUE(game::findState<game::SpriteParticles>(world)->gpu.ready)
      << game::findState<game::SpriteParticles>(world)->gpu_error;
  for (int i = 0; i < 3; ++i) game::stepWorld(world, nullptr);
  EXPECT_GT(countGlObjects(), before + 10);
  EXPECT_GT(game::liveSprites(*game::findState<game::SpriteParticles>(world)), 0u);
  game::detachWorldGpu(world);
  EXPECT_EQ(countGlObjects(), before) << "detachWorldGpu left GL objects behind";
}

TEST_F(SpriteGl, BudgetHoldsAndLiveCountFollowsBirthsAndDeaths) {
  std::string error;
  game::World world;
  // 300 sprites/s for 0.5 s lifetimes (±25 %): about 150 live, never more than the budget of 100.
  ASSERT_TRUE(game::buildWorld(
      parse(R"({"effects": {"sprite_particles": {"rate": 300, "lifetime": 0.5, "max_particles": 100}}})"),
      game::contentDir(), world, error))
      << error;
  game::attachWorldGpu(world, kShaders, game::contentDir());
  game::SpriteParticles& s = *game::findState<game::SpriteParticles>(world);
  ASSERT_TRUE(s.gpu.ready) << s.gpu_error;
  s.readback_every = 1;
  std::uint32_t most = 0;
  for (int i = 0; i < 90; ++i) {
    game::stepWorld(world, nullptr);
    most = std::max(most, game::liveSprites(s));
    engine::runPendingWork(s.gpu);  // what the frame's sprite pass does before it sorts and draws
    ASSERT_EQ(s.gpu.readback.step, s.steps);
    ASSERT_EQ(s.gpu.readback.positions.size(), game::liveSprites(s))
        << "read-back and allocator disagree at step " << i;
  }
  EXPECT_EQ(most, 100u);
  EXPECT_GT(s.dropped, 0u);
  EXPECT_LE(s.gpu.allocator.active_range, 100u);
  // The jet stops: every sprite dies within its longest lifetime (0.625 s).
  world.scene.effects[0].params["rate"].number = 0.0;
  game::applyLiveParams(world);
  for (int i = 0; i < 40; ++i) game::stepWorld(world, nullptr);
  EXPECT_EQ(game::liveSprites(s), 0u);
  EXPECT_EQ(world.nonfinite_state, "");
  game::detachWorldGpu(world);
}

// The fountain's sprites in the game loop: alive, finite, above the ground and outside the baked
// colliders (read back every step), and visible: the frame differs from the same scene without
// sprites in many pixels.
TEST(RunSceneSprites, FountainSpritesAreAliveFiniteOutsideAndDrawn) {
  setenv("SDL_VIDEODRIVER", "offscreen", 0);
  auto scene_text = [](int rate, int budget) {
    return R"({"camera": {"position": [0.0, 2.8, 4.5], "yaw_degrees": -90, "pitch_degrees": -12},
      "effects": {"sph_fluid": {"pump": false, "max_particles": 600}, "sprite_particles": {"size": 0.04, "rate": )" +
           std::to_string(rate) + R"(, "max_particles": )" + std::to_string(budget) + "}}}";
  };
  game::RunOptions options;
  options.headless = true;
  options.width = 96;
  options.height = 64;
  options.frames = 45;
  options.show_ui = false;
  options.fixed_frame_time = true;
  options.capture_last_frame = true;
  std::uint32_t live = 0, samples = 0;
  std::uint64_t spray = 0;
  float lowest = 1e9f, highest = -1e9f;
  bool finite = true;
  options.hooks.before_steps = [](game::FrameInput& input) {
    if (game::findState<game::SpriteParticles>(input.world))
      game::findState<game::SpriteParticles>(input.world)->readback_every = 1;
  };
  options.hooks.after_frame = [&](const game::FrameResult& frame) {
    const game::SpriteParticles& s = *game::findState<game::SpriteParticles>(frame.world);
    live = game::liveSprites(s);
    samples = static_cast<std::uint32_t>(s.gpu.readback.positions.size());
    spray = s.born_spray;
    for (const glm::vec4& p : s.gpu.readback.positions) {
      finite = finite && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      lowest = std::min(lowest, p.y);
      highest = std::max(highest, p.y);
    }
    return true;
  };
  game::RunReport with, without;
  std::string error;
  ASSERT_EQ(game::runScene(parse(scene_text(1500, 4000)), options, with, error), 0) << error;
  EXPECT_EQ(with.gl_errors, 0);
  EXPECT_EQ(with.nonfinite_state, "");
  EXPECT_GT(live, 500u);
  EXPECT_EQ(samples, live);
  EXPECT_TRUE(finite);
  EXPECT_GT(spray, 0u) << "no spray was born from the SPH jet";
  EXPECT_GT(lowest, -0.25f * 0.04f) << "a sprite fell through the baked ground";
  EXPECT_GT(highest, 2.5f) << "the mist does not rise from the nozzle";
  options.hooks = {};
  ASSERT_EQ(game::runScene(parse(scene_text(0, 0)), options, without, error), 0) << error;
  ASSERT_EQ(with.last_frame_rgba.size(), without.last_frame_rgba.size());
  int differing = 0;
  for (std::size_t i = 0; i < with.last_frame_rgba.size(); i += 4) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d += std::abs(int(with.last_frame_rgba[i + c]) - int(without.last_frame_rgba[i + c]));
    differing += d > 12;
  }
  std::printf("[ metric ] fountain sprites: %u live, %llu spray born, %d of %d pixels differ from no sprites\n", live,
              static_cast<unsigned long long>(spray), differing, 96 * 64);
  EXPECT_GT(differing, 50);
}

}  // namespace
