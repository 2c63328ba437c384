// A system not listed in the scene is never constructed: checked through the world's list and
// null pointers, through the profiler (its phase never runs), and through Bullet's allocator
// (no Bullet object is ever allocated when rigid_bodies is absent).
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <LinearMath/btAlignedAllocator.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>

namespace {

std::atomic<long> g_bullet_allocations{0};

void* countingAlloc(size_t size) {
  ++g_bullet_allocations;
  return std::malloc(size);
}
void countingFree(void* memory) { std::free(memory); }

// Routes Bullet's allocations through the counter for the test's lifetime.
struct BulletAllocationCounter {
  BulletAllocationCounter() {
    g_bullet_allocations = 0;
    btAlignedAllocSetCustom(countingAlloc, countingFree);
  }
  ~BulletAllocationCounter() { btAlignedAllocSetCustom(nullptr, nullptr); }
  long count() const { return g_bullet_allocations.load(); }
};

game::SceneConfig parse(const std::string& text) {
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

void runSteps(game::World& world, engine::Profiler& profiler, int steps) {
  for (int i = 0; i < steps; ++i) {
    engine::beginFrame(profiler);
    game::stepWorld(world, &profiler);
    engine::endFrame(profiler);
  }
}

TEST(EffectGating, WithoutRigidBodiesNoBulletObjectIsEverAllocated) {
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"sprite_particles": {"rate": 300}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 30);
  game::playerThrow(world);  // left click without the effect: nothing happens
  runSteps(world, profiler, 1);
  EXPECT_EQ(world.systems, std::vector<std::string>{"sprite_particles"});
  EXPECT_EQ(world.rigid_bodies, nullptr);
  EXPECT_NE(world.sprite_particles, nullptr);
  EXPECT_GT(world.sprite_particles->count, 0u);
  EXPECT_EQ(counter.count(), 0) << "Bullet allocated memory although rigid_bodies is not listed";
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 0u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 31u);
}

TEST(EffectGating, WithRigidBodiesTheCounterSeesBullet) {
  // The positive control: the same counter does see Bullet when the effect is listed.
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 3}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 10);
  EXPECT_EQ(world.systems, std::vector<std::string>{"rigid_bodies"});
  EXPECT_EQ(world.sprite_particles, nullptr);
  ASSERT_NE(world.rigid_bodies, nullptr);
  EXPECT_EQ(world.rigid_bodies->crates.size(), 3u);
  EXPECT_GT(counter.count(), 0);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 10u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 0u);
  const std::size_t before = world.rigid_bodies->crates.size();
  game::playerThrow(world);
  EXPECT_EQ(world.rigid_bodies->crates.size(), before + 1);
  world = game::World{};  // destroy before the counter restores Bullet's allocator
}

TEST(EffectGating, AnEmptyEffectListBuildsNothing) {
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {}})"), game::contentDir(), world, error)) << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 5);
  EXPECT_TRUE(world.systems.empty());
  EXPECT_EQ(world.rigid_bodies, nullptr);
  EXPECT_EQ(world.sprite_particles, nullptr);
  EXPECT_EQ(counter.count(), 0);
  for (const engine::PhaseStats& stats : profiler.stats) EXPECT_EQ(stats.frames, 0u);
}

TEST(EffectGating, ThrownCratesAreCappedAndRecycled) {
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 2}}})"), game::contentDir(), world, error))
      << error;
  for (int i = 0; i < game::RigidBodies::kMaxThrown + 5; ++i) {
    game::playerThrow(world);
    game::stepWorld(world, nullptr);
  }
  EXPECT_EQ(world.rigid_bodies->crates.size(), 2u + game::RigidBodies::kMaxThrown);
  EXPECT_EQ(world.nonfinite_state, "");
}

TEST(EffectGating, MissingModelIsNamed) {
  game::World world;
  std::string error;
  EXPECT_FALSE(game::buildWorld(parse(R"({"effects": {"rigid_bodies": {}}})"), "/nonexistent/content", world, error));
  EXPECT_NE(error.find("/nonexistent/content/models/basin.obj"), std::string::npos) << error;
}

}  // namespace
