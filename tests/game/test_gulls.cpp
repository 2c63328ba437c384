// The gulls effect (game/effects/gulls.cpp), the one-file example of an effect: through the same
// loops every effect goes through (the World's step, the replay hash, the CSV columns, the soak
// checks), never through its own type. They circle, a blast scatters the ones near it, they come
// back, and a seeded flock is the same flock every run.
#include "game/effects/effect.hpp"
#include "game/paths.hpp"
#include "game/replay/state_hash.hpp"
#include "game/soak_checks.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

game::World gullWorld(int seed = 1) {
  game::SceneConfig scene;
  const std::string text = R"({"scene": {"seed": )" + std::to_string(seed) + R"(},
    "camera": {"position": [0.0, 1.7, 9.0], "yaw_degrees": -90, "pitch_degrees": 0},
    "effects": {"rigid_bodies": {"crates": 0}, "explosives": {"fuse_seconds": 0.5}, "gulls": {}}})";
  const game::SceneStatus st = game::parseSceneText(text, "gulls.json", scene);
  EXPECT_TRUE(st.ok()) << st.error;
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  return world;
}

const game::Effect& gulls(const game::World& world) {
  for (const auto& effect : world.effects)
    if (effect->name() == "gulls") return *effect;
  ADD_FAILURE() << "no gulls effect";
  return *world.effects.front();
}

double fleeing(const game::World& world) {
  game::FrameColumns row;
  gulls(world).reportColumns(row);
  return row.get("gulls_fleeing");
}

std::uint64_t gullHash(const game::World& world) {
  game::StateHashScratch scratch;
  game::StateHash hash;
  game::hashWorldState(world, scratch, hash);
  for (const game::SubsystemHash& part : hash.parts)
    if (part.name == "gulls") return part.value;
  ADD_FAILURE() << "gulls are not in the state hash";
  return 0;
}

TEST(Gulls, ABlastScattersThemAndTheyComeBack) {
  game::World world = gullWorld();
  for (int i = 0; i < 120; ++i) game::stepWorld(world, nullptr);
  EXPECT_EQ(fleeing(world), 0.0);
  // A charge thrown from the eye toward the fountain goes off 0.5 s later, under the flock's circles.
  game::playerThrowExplosive(world);
  double most = 0.0;
  for (int i = 0; i < 60; ++i) {
    game::stepWorld(world, nullptr);
    most = std::max(most, fleeing(world));
  }
  EXPECT_GE(most, 3.0) << "of 7 gulls circling 6 m around the fountain, 7 m up, a blast there scatters most";
  // Four seconds of fleeing, then they fly back to their circles.
  for (int i = 0; i < 60 * 12; ++i) game::stepWorld(world, nullptr);
  EXPECT_EQ(fleeing(world), 0.0);
  game::SoakProbe probe;
  gulls(world).soakCheck(probe);
  EXPECT_EQ(probe.failure, "");
  EXPECT_EQ(world.nonfinite_state, "");
}

TEST(Gulls, TheSameSeedFliesTheSameFlockAndTheHashSeesIt) {
  game::World a = gullWorld(1), b = gullWorld(1), c = gullWorld(2);
  for (int i = 0; i < 90; ++i) {
    game::stepWorld(a, nullptr);
    game::stepWorld(b, nullptr);
    game::stepWorld(c, nullptr);
  }
  EXPECT_EQ(gullHash(a), gullHash(b));
  EXPECT_NE(gullHash(a), gullHash(c));
  // A blast in one of two equal worlds: the gulls' part of the hash tells them apart.
  game::playerThrowExplosive(a);
  for (int i = 0; i < 60; ++i) {
    game::stepWorld(a, nullptr);
    game::stepWorld(b, nullptr);
  }
  EXPECT_NE(gullHash(a), gullHash(b));
}

TEST(Gulls, TheSoakCheckCatchesAGullThatLeavesTheSky) {
  game::World world = gullWorld();
  game::stepWorld(world, nullptr);
  game::SoakProbe probe;
  gulls(world).soakCheck(probe);
  EXPECT_EQ(probe.failure, "");
  // Gulls sent fleeing at 40 m/s for 30 s are some 400 m away after 10 s; with the flight then
  // cut back to the default (2.5 s at 8 m/s) the check's bound is their circle plus that flight
  // (about 60 m), and every gull far out of it is named.
  auto set = [&](double flee_speed, double scare_seconds) {
    for (game::SectionConfig& section : world.scene.effects)
      if (section.name == "gulls") {
        section.params["flee_speed"].number = flee_speed;
        section.params["scare_seconds"].number = scare_seconds;
      }
    game::applyLiveParams(world);
  };
  set(40.0, 30.0);
  game::playerThrowExplosive(world);
  for (int i = 0; i < 60 * 10; ++i) game::stepWorld(world, nullptr);
  game::SoakProbe fleeing_far;
  gulls(world).soakCheck(fleeing_far);
  EXPECT_EQ(fleeing_far.failure, "") << "while their own flight is 1.2 km, 400 m is within it";
  set(8.0, 2.5);
  game::SoakProbe after;
  gulls(world).soakCheck(after);
  EXPECT_NE(after.failure.find("left the sky over the fountain"), std::string::npos) << after.failure;
}

}  // namespace
