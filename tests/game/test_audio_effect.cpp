// The `audio` effect in a World (no GL, no device): the mixer is rendered step by step as
// `replay --wav` does. Silence when nothing moves, a knock when a crate lands, a blast's noise and
// boom, a splash when a crate drops into the pool, and the same samples at any thread count.
#include "engine/audio/synth.hpp"
#include "game/paths.hpp"
#include "game/replay/replay_file.hpp"
#include "game/replay/replay_runner.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace {

using engine::audio::SoundKind;

game::World buildFrom(const std::string& text) {
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  return world;
}

// Steps the world `steps` times, rendering each step's samples after it (the offline path).
std::vector<float> stepAndRender(game::World& world, int steps) {
  engine::audio::Mixer& mixer = *world.links.audio;
  std::vector<float> out;
  for (int i = 0; i < steps; ++i) {
    engine::audio::setListener(mixer, {world.camera.position, engine::cameraForward(world.camera)});
    game::stepWorld(world, nullptr);
    const std::size_t n = game::audioStepFrames(world.steps - 1, world.step_seconds, mixer.params.sample_rate);
    const std::size_t at = out.size();
    out.resize(at + 2 * n);
    engine::audio::renderMixer(mixer, out.data() + at, n);
  }
  return out;
}

double rms(const std::vector<float>& samples) {
  double sum = 0.0;
  for (float x : samples) sum += static_cast<double>(x) * x;
  return samples.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(samples.size()));
}

bool allFiniteUnderFullScale(const std::vector<float>& samples) {
  for (float x : samples)
    if (!std::isfinite(x) || std::abs(x) > 1.0f) return false;
  return true;
}

const engine::audio::KindStats& stats(const game::World& world, SoundKind kind) {
  return world.links.audio->stats[static_cast<std::size_t>(kind)];
}

TEST(AudioEffect, IsSilentWhenNothingMoves) {
  game::World world = buildFrom(R"({"effects": {"rigid_bodies": {"crates": 3}, "audio": {}}})");
  ASSERT_NE(world.links.audio, nullptr);
  stepAndRender(world, 240);  // the stack settles (its first contacts may knock)
  const std::uint64_t knocks = stats(world, SoundKind::crate).events;
  const std::vector<float> later = stepAndRender(world, 120);
  EXPECT_EQ(stats(world, SoundKind::crate).events, knocks);
  for (float x : later) ASSERT_EQ(x, 0.0f);
}

// Live, the listener is each rendered frame's camera (prepareFrame, called by meshWorld).
TEST(AudioEffect, TheListenerFollowsEachRenderedFramesCamera) {
  game::World world = buildFrom(R"({"effects": {"audio": {}}})");
  world.camera.position = glm::vec3(1.0f, 2.0f, 3.0f);
  world.camera.yaw_degrees = 0.0f;  // looking along +x
  world.camera.pitch_degrees = 0.0f;
  game::meshWorld(world, nullptr);
  const engine::audio::Listener listener = [&world] {
    const std::lock_guard<std::mutex> hold(world.links.audio->lock);
    return world.links.audio->listener;
  }();
  EXPECT_EQ(listener.position, world.camera.position);
  EXPECT_NEAR(glm::dot(glm::normalize(listener.forward), engine::cameraForward(world.camera)), 1.0f, 1e-6f);
}

TEST(AudioEffect, ACrateLandingKnocks) {
  game::World world = buildFrom(R"({"effects": {"rigid_bodies": {"crates": 0}, "audio": {}}})");
  world.camera.position = glm::vec3(0.0f, 3.0f, 6.0f);
  world.camera.yaw_degrees = -90.0f;
  world.camera.pitch_degrees = -20.0f;
  const std::vector<float> before = stepAndRender(world, 30);
  EXPECT_EQ(rms(before), 0.0);
  game::playerThrow(world);
  const std::vector<float> after = stepAndRender(world, 120);
  EXPECT_GT(stats(world, SoundKind::crate).events, 0u);
  EXPECT_GT(stats(world, SoundKind::crate).max_frequency, 0.0f);
  EXPECT_GT(rms(after), 1e-4);  // above -80 dBFS
  EXPECT_TRUE(allFiniteUnderFullScale(after));
}

TEST(AudioEffect, ABlastIsHeard) {
  game::World world = buildFrom(
      R"({"effects": {"rigid_bodies": {"crates": 0}, "explosives": {"fuse_seconds": 0.5, "throw_speed": 0},
          "audio": {"speed_of_sound": 34.3}}})");
  world.camera.position = glm::vec3(0.0f, 1.0f, 0.0f);
  game::playerThrowExplosive(world);
  std::vector<float> out = stepAndRender(world, 90);
  ASSERT_EQ(stats(world, SoundKind::blast).events, 1u);
  EXPECT_GT(rms(out), 1e-3);  // above -60 dBFS
  EXPECT_TRUE(allFiniteUnderFullScale(out));
  EXPECT_EQ(world.links.audio->clipped, 0u);
}

TEST(AudioEffect, ACrateDroppedIntoThePoolSplashes) {
  game::World world = buildFrom(
      R"({"effects": {"rigid_bodies": {"crates": 0, "throw_speed": 6},
          "sph_fluid": {"max_particles": 4000, "cfl": 0.9, "max_time_step": 0.0167, "density_error": 0.005,
                        "force_bound": 0},
          "audio": {}}})");
  // Over the pool between the statue's plinth and the basin wall, throwing straight down.
  world.camera.position = glm::vec3(1.8f, 2.5f, 0.0f);
  world.camera.pitch_degrees = -89.0f;
  stepAndRender(world, 2);
  game::playerThrow(world);
  const std::vector<float> out = stepAndRender(world, 60);
  EXPECT_GT(stats(world, SoundKind::crate_splash).events, 0u);
  EXPECT_GT(stats(world, SoundKind::crate_splash).peak, 0.0f);
  EXPECT_TRUE(allFiniteUnderFullScale(out));
}

// A blast in the pool throws water up: what falls back splashes louder than the running fountain.
// Compared per step (the water's own mix, drop and jet, before the limiter): the loudest step and
// the bubbles per step, over 60 calm steps and over the 120 steps from the throw on.
TEST(AudioEffect, SplashesAreLouderAfterABlastInThePool) {
  game::World world = buildFrom(
      R"({"effects": {"rigid_bodies": {"crates": 0},
          "explosives": {"fuse_seconds": 0.4, "throw_speed": 8, "lob_degrees": 0},
          "sph_fluid": {"max_particles": 4000, "cfl": 0.9, "max_time_step": 0.0167, "density_error": 0.005,
                        "force_bound": 0},
          "audio": {}}})");
  world.camera.position = glm::vec3(1.8f, 2.5f, 0.0f);
  world.camera.pitch_degrees = -89.0f;
  stepAndRender(world, 90);  // the jet reaches the pool
  struct Window {
    double loudest = 0.0;  // the largest one-step energy, drops and jet
    // The drops' bubbles: the jet's bed in the dish (SoundKind::jet) runs on the same before and
    // after; a blast's rain is drops.
    std::uint64_t bubbles = 0;
  };
  const auto run = [&world](int steps) {
    Window w;
    for (int i = 0; i < steps; ++i) {
      const engine::audio::KindStats &drop = stats(world, SoundKind::drop), &jet = stats(world, SoundKind::jet);
      const double energy = drop.sum_squares + jet.sum_squares;
      const std::uint64_t events = drop.events;
      stepAndRender(world, 1);
      w.loudest = std::max(w.loudest, drop.sum_squares + jet.sum_squares - energy);
      w.bubbles += drop.events - events;
    }
    return w;
  };
  const Window calm = run(60);
  game::playerThrowExplosive(world);
  const Window blasted = run(120);  // it lands in the pool, goes off, and the water falls back
  ASSERT_EQ(stats(world, SoundKind::blast).events, 1u);
  std::printf("[ metric ] drop bubbles: %llu in 1 s calm, %llu in the 2 s after the blast\n",
              static_cast<unsigned long long>(calm.bubbles), static_cast<unsigned long long>(blasted.bubbles));
  EXPECT_GT(blasted.bubbles, 10u);
  EXPECT_GT(static_cast<double>(blasted.bubbles) / 120.0, 1.5 * static_cast<double>(calm.bubbles) / 60.0);
  EXPECT_GT(blasted.loudest, 2.0 * calm.loudest);
}

// The goo (issue 39 item 4): the blob's particle impacts squelch, with the water's bubble machinery
// shifted down (goo_pitch) and damped more: every goo bubble sounds below the water's highest note.
TEST(AudioEffect, TheGooSquelchesLowerThanTheWater) {
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile(game::scenesDir() / "blob_monster.json", scene).ok());
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  ASSERT_NE(world.links.blob, nullptr);
  const std::vector<float> out = stepAndRender(world, 600);  // it rises out of the sewer and reaches out
  const engine::audio::KindStats& goo = stats(world, SoundKind::goo);
  EXPECT_GT(goo.events, 0u);
  EXPECT_GT(goo.peak, 0.0f);
  EXPECT_GT(goo.min_frequency, 0.0f);
  // The water's top note is its smallest bubble's Minnaert pitch; the goo's smallest is radius_min / goo_pitch.
  EXPECT_LT(goo.max_frequency, 0.5f * engine::audio::minnaertFrequency(0.0012f));
  EXPECT_TRUE(allFiniteUnderFullScale(out));
}

// The fountain tour's first 150 steps offline, through the replay runner as `replay --wav` runs
// it, at 1 and at 2 threads: the same samples, bit for bit, and water is heard.
TEST(AudioEffect, TheOfflineRenderIsTheSameAtAnyThreadCount) {
  game::ReplayFile replay;
  ASSERT_TRUE(game::loadReplayFile(game::contentDir() / "replays" / "fountain_tour.replay", replay).ok());
  const auto run = [&](int threads) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    game::ReplayRunOptions options;
    options.render = false;
    options.audio = true;
    options.frames = 150;
    options.allow_scene_change = true;
    game::ReplayResult result;
    std::string error;
    EXPECT_EQ(game::runReplay(replay, options, result, error), 0) << error;
    return result.audio;
  };
  const game::ReplayAudio one = run(1), two = run(2);
  ASSERT_TRUE(one.present);
  EXPECT_EQ(one.samples.size(), 2u * 150u * 22050u / 60u);
  EXPECT_EQ(one.samples, two.samples);
  EXPECT_GT(one.stats[static_cast<std::size_t>(SoundKind::jet)].events, 0u);
  EXPECT_GT(rms(one.samples), 1e-5);
  EXPECT_TRUE(allFiniteUnderFullScale(one.samples));
}

}  // namespace
