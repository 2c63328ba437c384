// The sprite_particles effect on the GPU (engine/gpu_particles) inside the game, headless GL:
// gating of its GL resources, the fountain's sprites alive, finite, outside the baked colliders
// and visible in the frame, and blast sprites in the blob street outside its colliders.
#include "engine/gl/gl.hpp"
#include "engine/platform/platform.hpp"
#include "game/explosives/explosives.hpp"
#include "game/paths.hpp"
#include "game/run_scene.hpp"
#include "game/soak_checks.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

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

// Blasts in the blob street where its solids overlap: charges lying on the street (centre 0.1 m up)
// inside the building fronts, whose boxes reach 0.2 m down into the street slab (the first two are
// where `soak --scene blob_monster --seed 5` had charges detonate). A sprite born inside a front near
// its foot was pushed out through the front's bottom into the slab and back (Kolb et al. 2004
// §3.3.2, one collider at a time) and ended its steps 0.2 m inside the street. Every live sprite
// must end every step outside every collider by the soak's measure, the burst's part in the air
// must still be born, and a blast in the air must lose none of its sprites. The blasts are 3 m or
// more apart, so none throws the sprites of another at the 40 m/s cap.
TEST_F(SpriteGl, BlastSpritesInTheBlobStreetEndEveryStepOutsideItsColliders) {
  game::SpriteParticleParams params;  // the blob_monster scene's section: blast fire and smoke only
  params.rate = 0.0f;
  params.spray_rate = 0.0f;
  params.foam_trapped_air_rate = 0.0f;
  params.foam_wave_crest_rate = 0.0f;
  params.blast_debris = false;
  params.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  game::SpriteParticles s;
  game::initSpriteParticles(s, params, 2048, 11u ^ 0x9e3779b9u);
  s.level = "blob_monster";
  const float dt = 1.0f / 60.0f;
  ASSERT_TRUE(game::attachSpriteGpu(s, kShaders, game::contentDir(), dt)) << s.gpu_error;
  s.readback_every = 1;
  const glm::vec3 inside_fronts[] = {
      {-0.9283f, 0.1f, 6.9271f}, {-7.1005f, 0.1f, -0.4538f}, {2.5f, 0.1f, 7.2f},
      {-4.0f, 0.1f, 7.05f},      {-7.35f, 0.1f, 3.0f},       {7.3f, 0.1f, -3.0f},
      {7.1f, 0.1f, 2.0f},        {1.0f, 0.1f, -9.8f},        {-3.0f, 0.1f, -9.6f},
  };
  const game::ExplosiveParams charge;
  game::PenetrationScratch scratch;
  std::vector<glm::vec3> points;
  float worst = 0.0f;
  std::string where;
  auto stepAndCheck = [&](std::span<const fluid::Blast> blasts) {
    game::stepSpriteParticles(s, nullptr, dt, blasts);
    engine::runPendingWork(s.gpu);  // the frame's sprite pass: runs the step and the read-back
    ASSERT_EQ(s.gpu.readback.step, s.steps);
    points.clear();
    for (const glm::vec4& p : s.gpu.readback.positions) points.emplace_back(p);
    for (std::size_t c = 0; c < s.level_colliders->parts.size(); ++c) {
      const game::Penetration p = game::worstPenetration(points, s.level_colliders->parts[c].collider,
                                                         fluid::ColliderPose{}, params.size, 0.0f, scratch);
      if (p.ratio > worst) {
        worst = p.ratio;
        where = game::describePenetration(s.collider_names[c] + " step " + std::to_string(s.steps), p, 0.25f);
      }
    }
  };
  std::uint64_t born = 0;
  for (const glm::vec3& centre : inside_fronts) {
    const fluid::Blast blast = game::blastOf(charge, centre);
    stepAndCheck(std::span(&blast, 1));
    for (int i = 0; i < 3; ++i) stepAndCheck({});
    born = s.born_blast;
  }
  EXPECT_LE(worst, 0.25f) << where;
  EXPECT_GT(s.buried_blast, 0u);
  EXPECT_GT(born, 0u) << "no sprite of a blast against a front was born in the air";
  // In the air, clear of every solid, the whole burst is born: 70 fire and 90 smoke.
  const std::uint64_t buried = s.buried_blast;
  const fluid::Blast open = game::blastOf(charge, glm::vec3(3.0f, 1.5f, -3.0f));
  stepAndCheck(std::span(&open, 1));
  EXPECT_EQ(s.buried_blast, buried);
  EXPECT_EQ(s.born_blast - born, 160u);
  EXPECT_LE(worst, 0.25f) << where;
  std::printf("[ metric ] blob street blasts: %llu sprites born, %llu not born inside a collider, worst %.3f radii\n",
              static_cast<unsigned long long>(s.born_blast), static_cast<unsigned long long>(s.buried_blast), worst);
  game::detachSpriteGpu(s);
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
