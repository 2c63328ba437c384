// The pump (SphPump, SphSinkKind): water circulates through intakes, gutters and the nozzle, and
// the count of water never changes. A basin 1 m wide with an intake in its floor, a nozzle above
// the water fed by the pump, a gutter on a ledge outside the basin's wall.
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <set>
#include <vector>

namespace {

using namespace fluid;

SphScene pumpedBasin() {
  SphScene scene;
  SphWorld& w = scene.world;
  SphParams& p = w.params;
  p.particle_radius = 0.02f;
  p.viscosity = 0.01f;
  p.cfl = 0.6f;
  p.max_time_step = 0.004f;
  p.max_particles = 100000;
  p.domain_min = glm::vec3(-0.2f);
  p.domain_max = glm::vec3(1.2f, 2.0f, 1.2f);
  CollisionMaterial wall;
  wall.resilience = 0.0f;
  addSphContainer(scene, glm::vec3(0.0f), glm::vec3(1.0f, 1.5f, 1.0f), wall);
  addSphBlock(w, glm::vec3(0.0f), glm::vec3(1.0f, 0.2f, 1.0f));  // 25 x 5 x 25
  SphEmitter nozzle;
  nozzle.position = glm::vec3(0.5f, 0.5f, 0.5f);
  nozzle.direction = glm::vec3(0.0f, 1.0f, 0.0f);
  nozzle.speed = 2.0f;
  nozzle.radius = 0.05f;
  nozzle.rate = 400.0f;
  w.emitters.push_back(nozzle);
  // The intake: the floor's corner cell, one layer deep.
  w.sinks.push_back({glm::vec3(-1.0f, -1.0f, -1.0f), glm::vec3(0.12f, 0.04f, 0.12f), SphSinkKind::intake});
  w.pump.feeds_emitters = true;
  w.pump.delay = 0.25;
  w.pump.capacity = 120;  // 400/s for 0.25 s plus a layer
  return scene;
}

std::multiset<std::uint32_t> allIds(const SphWorld& w) {
  std::multiset<std::uint32_t> ids(w.particles.id.begin(), w.particles.id.end());
  for (std::size_t k = w.pump.head; k < w.pump.held.size(); ++k) ids.insert(w.pump.held[k].id);
  return ids;
}

TEST(SphPump, WaterCirculatesWithAConstantCountAndItsOwnIds) {
  SphScene scene = pumpedBasin();
  SphWorld& w = scene.world;
  const auto ids0 = allIds(w);
  ASSERT_EQ(ids0.size(), 3125u);
  std::size_t pumped = 0, emitted = 0, held_max = 0;
  for (int frame = 0; frame < 180; ++frame) {  // 3 s in calls of 1/60 s
    const SphStatus st = advanceSph(w, 1.0 / 60.0, [&](const SphStepStats& s) {
      pumped += s.pumped;
      emitted += s.emitted;
      EXPECT_EQ(s.removed, 0u);
      held_max = std::max(held_max, w.pump.size());
    });
    ASSERT_TRUE(st.ok()) << st.error;
    ASSERT_EQ(w.particles.size() + w.pump.size(), 3125u) << "frame " << frame;
  }
  EXPECT_EQ(allIds(w), ids0);  // the same water, each id once
  EXPECT_GT(pumped, 300u);     // it circulated: the jet ran the whole time (about 150 a second)
  EXPECT_NEAR(static_cast<double>(emitted), static_cast<double>(pumped), static_cast<double>(w.pump.capacity));
  EXPECT_LE(held_max, w.pump.capacity);  // an intake takes only what the pump has room for
  EXPECT_EQ(w.next_id, 3125u);           // no particle was made
  for (const glm::vec3& v : w.particles.velocity) ASSERT_LT(glm::length(v), 10.0f);
}

TEST(SphPump, AGutterReturnsWaterThrownOutOfTheBasin) {
  SphScene scene = pumpedBasin();
  SphWorld& w = scene.world;
  // Everything above 0.1 m is "thrown out" at once: a gutter box takes it whatever the pump holds.
  w.sinks.push_back({glm::vec3(-1.0f, 0.1f, -1.0f), glm::vec3(2.0f, 0.3f, 2.0f), SphSinkKind::pump});
  ASSERT_TRUE(stepSph(w, 0.002f).ok());
  EXPECT_GT(w.pump.size(), w.pump.capacity);
  w.sinks.pop_back();
  const std::size_t held = w.pump.size();
  ASSERT_TRUE(advanceSph(w, 3.0, [](const SphStepStats&) {}).ok());
  EXPECT_LT(w.pump.size() + 300, held);  // the nozzle gave it back (about 150 a second)
  EXPECT_EQ(w.particles.size() + w.pump.size(), 3125u);
}

TEST(SphPump, ThreadCountDoesNotChangeTheCirculation) {
  auto run = [](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    SphScene scene = pumpedBasin();
    EXPECT_TRUE(advanceSph(scene.world, 1.0, [](const SphStepStats&) {}).ok());
    return scene;
  };
  const SphScene one = run(1), two = run(2);
  ASSERT_EQ(one.world.particles.size(), two.world.particles.size());
  EXPECT_EQ(one.world.particles.id, two.world.particles.id);
  EXPECT_EQ(one.world.particles.position, two.world.particles.position);
  ASSERT_EQ(one.world.pump.size(), two.world.pump.size());
  for (std::size_t k = 0; k < one.world.pump.size(); ++k)
    EXPECT_EQ(one.world.pump.held[one.world.pump.head + k].id, two.world.pump.held[two.world.pump.head + k].id);
}

}  // namespace
