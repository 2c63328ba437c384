#include "fluid/core/parallel.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sprite_particles.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <limits>
#include <random>
#include <thread>

namespace {

game::SpriteParticleParams params() {
  game::SpriteParticleParams p;
  p.rate = 600.0f;
  p.lifetime = 3.0f;
  return p;
}

TEST(FountainShape, DistancesMatchTheGeometry) {
  const game::FountainShape shape;
  const game::FountainGeometry& g = shape.geometry();
  EXPECT_NEAR(shape.distance({10.0f, 0.5f, 0.0f}), 0.5f, 1e-5f);                 // above the ground
  EXPECT_NEAR(shape.distance({2.0f, g.basin_floor + 0.1f, 0.0f}), 0.1f, 1e-5f);  // above the basin floor
  EXPECT_LT(shape.distance({0.5f * (g.basin_inner_radius + g.basin_outer_radius), 0.5f, 0.0f}), 0.0f);  // in the wall
  EXPECT_LT(shape.distance({0.0f, 1.0f, 0.0f}), 0.0f);  // inside the column
  EXPECT_GT(shape.distance(g.nozzle), 0.0f);            // the nozzle is outside
  std::vector<glm::vec3> points = {{10.0f, 0.5f, 0.0f}};
  std::vector<fluid::ColliderSample> samples(1);
  shape.query(points, samples);
  EXPECT_TRUE(samples[0].valid);
  EXPECT_NEAR(samples[0].normal.y, 1.0f, 1e-3f);
}

TEST(FountainShape, AnalyticNormalsMatchTheFieldsDifferences) {
  // Away from CSG joins (where the field has a kink) the normal must equal the field's gradient.
  const game::FountainShape shape;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> xz(-4.0f, 4.0f), y(-0.5f, 3.0f);
  int compared = 0;
  for (int i = 0; i < 4000; ++i) {
    const glm::vec3 p(xz(rng), y(rng), xz(rng));
    constexpr float h = 1e-3f;
    const glm::vec3 g(shape.distance(p + glm::vec3(h, 0, 0)) - shape.distance(p - glm::vec3(h, 0, 0)),
                      shape.distance(p + glm::vec3(0, h, 0)) - shape.distance(p - glm::vec3(0, h, 0)),
                      shape.distance(p + glm::vec3(0, 0, h)) - shape.distance(p - glm::vec3(0, 0, h)));
    if (std::abs(glm::length(g) / (2.0f * h) - 1.0f) > 1e-2f) continue;  // on a kink
    std::vector<glm::vec3> points{p};
    std::vector<fluid::ColliderSample> samples(1);
    shape.query(points, samples);
    ASSERT_NEAR(samples[0].distance, shape.distance(p), 1e-6f);
    ASSERT_GT(glm::dot(samples[0].normal, glm::normalize(g)), 0.999f) << p.x << ", " << p.y << ", " << p.z;
    ++compared;
  }
  EXPECT_GT(compared, 3000);
}

TEST(SpriteParticles, EmitsAtTheRateAndRespectsTheBudget) {
  game::SpriteParticles s;
  game::initSpriteParticles(s, params(), 100000, 1);
  const game::FountainShape shape;
  for (int i = 0; i < 60; ++i) game::stepSpriteParticles(s, shape, 1.0f / 60.0f);
  EXPECT_EQ(s.count, 600u);  // 600/s for 1 s, none old enough to retire
  game::SpriteParticles small;
  game::initSpriteParticles(small, params(), 50, 1);
  for (int i = 0; i < 60; ++i) game::stepSpriteParticles(small, shape, 1.0f / 60.0f);
  EXPECT_EQ(small.count, 50u);
}

TEST(SpriteParticles, BounceStayOutsideTheFountainAndRetire) {
  game::SpriteParticles s;
  game::initSpriteParticles(s, params(), 4000, 3);
  const game::FountainShape shape;
  for (int i = 0; i < 300; ++i) {  // 5 s: longer than the lifetime
    game::stepSpriteParticles(s, shape, 1.0f / 60.0f);
    for (std::size_t k = 0; k < s.count; ++k) {
      const glm::vec3 q = s.position[k];
      ASSERT_GE(shape.distance(q), -2e-3f)
          << "particle " << k << " inside at step " << i << " at " << q.x << ", " << q.y << ", " << q.z;
    }
  }
  EXPECT_GT(s.bounces, 0u);
  // Retirement keeps the population at rate * lifetime.
  EXPECT_NEAR(static_cast<double>(s.count), 600.0 * 3.0, 20.0);
  // Retirement runs at the start of a step, so an age can exceed the lifetime by one step.
  for (std::size_t k = 0; k < s.count; ++k) EXPECT_LT(s.age[k], 3.0f + 1.0f / 60.0f + 1e-4f);
  // Some water has come to rest in the basin or the dish.
  int resting = 0;
  for (std::size_t k = 0; k < s.count; ++k) resting += glm::length(s.velocity[k]) < 0.5f;
  EXPECT_GT(resting, 0);
}

TEST(SpriteParticles, SameSeedSameResultOtherSeedDifferent) {
  const game::FountainShape shape;
  auto run = [&](std::uint32_t seed) {
    game::SpriteParticles s;
    game::initSpriteParticles(s, params(), 4000, seed);
    for (int i = 0; i < 90; ++i) game::stepSpriteParticles(s, shape, 1.0f / 60.0f);
    return std::vector<glm::vec3>(s.position.begin(), s.position.begin() + static_cast<std::ptrdiff_t>(s.count));
  };
  EXPECT_EQ(run(5), run(5));
  EXPECT_NE(run(5), run(6));
}

TEST(SpriteParticles, ResultsDoNotDependOnTheThreadCount) {
  const game::FountainShape shape;
  auto run = [&](std::size_t threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    game::SpriteParticles s;
    game::initSpriteParticles(s, params(), 6000, 9);
    for (int i = 0; i < 150; ++i) game::stepSpriteParticles(s, shape, 1.0f / 60.0f);
    EXPECT_GT(s.count, 1024u);  // more than one parallel range
    return std::make_pair(
        std::vector<glm::vec3>(s.position.begin(), s.position.begin() + static_cast<std::ptrdiff_t>(s.count)),
        s.bounces);
  };
  const auto one = run(1);
  const auto four = run(4);
  EXPECT_EQ(one.first, four.first);
  EXPECT_EQ(one.second, four.second);
}

// The sprite loop runs through fluid::par, whose cap is oneTBB's max_allowed_parallelism in every
// build (`simulate --threads N`, the test above): the most bodies running at once never exceeds
// it, including in TSan builds where fluid::par starts std::threads of its own.
TEST(SpriteParticles, ParallelLoopsHonourTheThreadCap) {
  for (const std::size_t cap : {1u, 2u, 3u}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cap);
    std::atomic<int> running{0}, most{0};
    std::atomic<std::size_t> visited{0};
    fluid::par::parallel_for(fluid::par::Range<std::size_t>(0, 48, 1), [&](const fluid::par::Range<std::size_t>& r) {
      const int now = ++running;
      int seen = most.load();
      while (now > seen && !most.compare_exchange_weak(seen, now)) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // long enough for bodies to overlap
      visited += r.size();
      --running;
    });
    EXPECT_EQ(visited.load(), 48u);
    EXPECT_GE(most.load(), 1);
    EXPECT_LE(most.load(), static_cast<int>(cap)) << "cap " << cap;
  }
}

TEST(SpriteParticles, NonFiniteValuesAreNamed) {
  game::SpriteParticles s;
  game::initSpriteParticles(s, params(), 100, 1);
  const game::FountainShape shape;
  game::stepSpriteParticles(s, shape, 1.0f / 60.0f);
  ASSERT_GT(s.count, 3u);
  EXPECT_EQ(game::findNonFiniteParticle(s), "");
  s.velocity[3].z = std::numeric_limits<float>::infinity();
  const std::string message = game::findNonFiniteParticle(s);
  EXPECT_NE(message.find("particle 3 velocity.z"), std::string::npos) << message;
}

}  // namespace
