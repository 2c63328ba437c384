// The soak's checks (game/soak_checks.hpp, game/soak_monitor.hpp) on crafted cases: each check
// passes a healthy case and fires on a bad one, so none of them is a check that cannot fail.
#include "game/soak_checks.hpp"
#include "game/soak_monitor.hpp"
#include "tests/support/fountain_shape.hpp"

#include "fluid/sph/analytic_colliders.hpp"
#include "game/explosives/explosives.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace {

constexpr std::uint64_t kMB = 1ull << 20;

// 96 samples (a 3,600-step run after 20 % warm-up, one sample per 30 steps) around `level` with
// +-1.5 MiB of alternating noise, plus `slope` bytes per sample.
std::vector<std::uint64_t> samples(std::uint64_t level, double slope) {
  std::vector<std::uint64_t> out;
  for (int i = 0; i < 96; ++i) {
    const double noise = (i % 2 == 0 ? 1.5 : -1.5) * static_cast<double>(kMB);
    out.push_back(static_cast<std::uint64_t>(static_cast<double>(level) + noise + slope * i));
  }
  return out;
}

TEST(SoakMemory, FlatNoisyResidentSetPasses) {
  const game::MemoryGrowth m = game::checkMemoryGrowth(samples(300 * kMB, 0.0));
  EXPECT_TRUE(m.failure.empty()) << m.failure;
  EXPECT_EQ(m.bound, static_cast<std::uint64_t>(0.05 * static_cast<double>(m.first_level)));  // 5 % of ~300 MiB > 8 MiB
}

TEST(SoakMemory, SteadyGrowthFails) {
  // 0.3 MiB per sample: about 19 MiB between the thirds' medians, above max(8 MiB, 5 % of 100 MiB).
  const game::MemoryGrowth m = game::checkMemoryGrowth(samples(100 * kMB, 0.3 * kMB));
  EXPECT_NE(m.failure.find("memory grows after warm-up"), std::string::npos) << m.failure;
  EXPECT_GT(m.last_level, m.first_level + 8 * kMB);
}

TEST(SoakMemory, GrowthBelowTheFloorPasses) {
  // 0.1 MiB per sample: about 6 MiB between the medians, under the 8 MiB floor (5 % of 100 MiB = 5 MiB).
  const game::MemoryGrowth m = game::checkMemoryGrowth(samples(100 * kMB, 0.1 * kMB));
  EXPECT_TRUE(m.failure.empty()) << m.failure;
  EXPECT_EQ(m.bound, 8 * kMB);
}

TEST(SoakMemory, TheRelativeBoundScalesWithTheLevel) {
  // 1 GiB process: 5 % = 51 MiB allowed. 40 MiB of growth passes, 80 MiB fails.
  EXPECT_TRUE(game::checkMemoryGrowth(samples(1024 * kMB, 40.0 * kMB / 64.0)).failure.empty());
  EXPECT_FALSE(game::checkMemoryGrowth(samples(1024 * kMB, 80.0 * kMB / 64.0)).failure.empty());
}

TEST(SoakMemory, ALateJumpFailsOnTheFinalLevel) {
  std::vector<std::uint64_t> s = samples(200 * kMB, 0.0);
  s.back() += 30 * kMB;  // the median of the last third does not see one sample
  const game::MemoryGrowth m = game::checkMemoryGrowth(s);
  EXPECT_NE(m.failure.find("memory ends high"), std::string::npos) << m.failure;
}

TEST(SoakMemory, WithoutTheFinalLevelOnlyTheTrendIsJudged) {
  std::vector<std::uint64_t> jump = samples(200 * kMB, 0.0);
  jump.back() += 30 * kMB;
  EXPECT_TRUE(game::checkMemoryGrowth(jump, {}, false).failure.empty());
  const game::MemoryGrowth m = game::checkMemoryGrowth(samples(100 * kMB, 0.3 * kMB), {}, false);
  EXPECT_NE(m.failure.find("memory grows after warm-up"), std::string::npos) << m.failure;
}

TEST(SoakMemory, HeapInUseSeesAnAllocationAndItsRelease) {
  const std::uint64_t before = game::heapInUseBytes();
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // The sanitizers' own allocators answer glibc's mallinfo2 with zeros: the soak then judges the
  // resident set alone (and sanitizer soaks leave memory to LeakSanitizer).
  GTEST_SKIP() << "heap in use " << before << " under a sanitizer's allocator";
#elif defined(__GLIBC__)
  ASSERT_GT(before, 0u);
  auto block = std::make_unique<char[]>(64 * kMB);
  block[0] = 1;
  EXPECT_GE(game::heapInUseBytes(), before + 64 * kMB);
  block.reset();
  EXPECT_LT(game::heapInUseBytes(), before + 8 * kMB);
#else
  EXPECT_EQ(before, 0u);
#endif
}

TEST(SoakMemory, TooFewSamplesJudgeNothing) {
  const std::vector<std::uint64_t> s = {10 * kMB, 500 * kMB};
  EXPECT_TRUE(game::checkMemoryGrowth(s).failure.empty());
}

TEST(SoakMemory, ResidentSetIsReadAndSeesAnAllocation) {
  const std::uint64_t before = game::residentBytes();
  ASSERT_GT(before, 0u);
  std::vector<char> block(64 * kMB, 1);  // touched: resident
  const std::uint64_t after = game::residentBytes();
  EXPECT_GE(after, before + 60 * kMB);
  EXPECT_EQ(block[12345], 1);
}

// A gauge (the pool's level) judged over a run's samples: `first` for the first half of 300 samples,
// `last` for the rest, +-1 % of alternating noise (the thirds' medians take the upper of their
// middle pair: 1.01 x the level), spanning `seconds` of game time.
game::SoakMonitor gaugeRun(double first, double last, double seconds) {
  game::SoakDesc desc;
  desc.steps = static_cast<std::uint64_t>(seconds * 60.0);
  game::SoakMonitor m = game::makeSoakMonitor(desc, 1.0 / 60.0);
  m.probe.gauges = {{"pool level", "m", 0.0}};
  m.gauge_samples.resize(1);
  for (int i = 0; i < 300; ++i) m.gauge_samples[0].push_back((i < 150 ? first : last) * (i % 2 == 0 ? 1.01 : 0.99));
  m.gauge_first_step = 0;
  m.stats.steps = desc.steps;
  return m;
}

TEST(SoakGauge, ALevelThatHoldsOverALongRunPasses) {
  game::SoakMonitor m = gaugeRun(0.24, 0.24 * 0.99, 3600.0);  // -1 %
  game::finishSoak(m);
  EXPECT_TRUE(m.failure.empty()) << m.failure;
  ASSERT_EQ(m.stats.gauges.size(), 1u);
  EXPECT_TRUE(m.stats.gauges[0].judged);
  EXPECT_NEAR(m.stats.gauges[0].last / m.stats.gauges[0].first, 0.99, 1e-9);
  EXPECT_NE(game::soakSummary(m).find("pool level 0.2424 -> 0.24 m (-1.00 %, judged)"), std::string::npos)
      << game::soakSummary(m);
}

TEST(SoakGauge, ALevelThatSinksOverALongRunFails) {
  game::SoakMonitor m = gaugeRun(0.24, 0.24 * 0.97, 3600.0);  // -3 %
  game::finishSoak(m);
  EXPECT_NE(m.failure.find("pool level drifts from 0.2424 to 0.2351 m (-3.00 %, allowed 2.00 %)"), std::string::npos)
      << m.failure;
  game::SoakMonitor rising = gaugeRun(0.24, 0.24 * 1.03, 3600.0);  // +3 %
  game::finishSoak(rising);
  EXPECT_NE(rising.failure.find("pool level drifts"), std::string::npos) << rising.failure;
}

TEST(SoakGauge, ARunShorterThanTheJudgedSpanIsNotJudged) {
  game::SoakMonitor m = gaugeRun(0.24, 0.24 * 0.9, 60.0);  // a blast's dip over a minute's run
  game::finishSoak(m);
  EXPECT_TRUE(m.failure.empty()) << m.failure;
  ASSERT_EQ(m.stats.gauges.size(), 1u);
  EXPECT_FALSE(m.stats.gauges[0].judged);
  EXPECT_NE(game::soakSummary(m).find("not judged"), std::string::npos) << game::soakSummary(m);
}

TEST(SoakPenetration, PointsOutsideTheFountainAreNotInside) {
  const fountainref::FountainShape shape;
  game::PenetrationScratch scratch;
  const std::vector<glm::vec3> outside = {{0.0f, 3.0f, 0.0f}, {5.0f, 0.5f, 0.0f}, {2.0f, 0.5f, 0.0f}};
  const game::Penetration p = game::worstPenetration(outside, shape, {}, 0.04f, 0.0f, scratch);
  EXPECT_EQ(p.depth, 0.0f);
  EXPECT_EQ(p.ratio, 0.0f);
}

TEST(SoakPenetration, APointInTheBasinWallIsFoundWithItsDepth) {
  const fountainref::FountainShape shape;
  const game::FountainGeometry& g = shape.geometry();
  game::PenetrationScratch scratch;
  // The middle of the basin wall (0.3 m thick, top at 0.7): 0.15 m from both sides, 0.3 from the top.
  const float mid = 0.5f * (g.basin_inner_radius + g.basin_outer_radius);
  const std::vector<glm::vec3> points = {{2.0f, 0.5f, 0.0f}, {0.0f, 0.4f, mid}, {0.0f, 3.0f, 0.0f}};
  const game::Penetration p = game::worstPenetration(points, shape, {}, 0.04f, 0.0f, scratch);
  EXPECT_EQ(p.index, 1u);
  EXPECT_NEAR(p.depth, 0.15f, 1e-4f);
  EXPECT_NEAR(p.ratio, 0.15f / 0.04f, 1e-2f);
  EXPECT_EQ(p.position, points[1]);
}

TEST(SoakPenetration, AMovedColliderIsQueriedAtItsPose) {
  // A 0.2 m cube turned 45 degrees about y and moved to (1, 1, 1): a point 0.25 m along x from its
  // centre is outside the unturned cube's face but inside the turned one (corner at 0.283 m).
  const fluid::BoxShape box(glm::vec3(0.2f));
  fluid::ColliderPose pose;
  pose.rotation = glm::angleAxis(glm::radians(45.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  pose.translation = glm::vec3(1.0f);
  game::PenetrationScratch scratch;
  const std::vector<glm::vec3> points = {glm::vec3(1.25f, 1.0f, 1.0f)};
  EXPECT_GT(game::worstPenetration(points, box, pose, 0.04f, 0.0f, scratch).depth, 0.0f);
  EXPECT_EQ(
      game::worstPenetration(points, box, fluid::ColliderPose{.translation = glm::vec3(1.0f)}, 0.04f, 0.0f, scratch)
          .depth,
      0.0f);
}

TEST(SoakPenetration, ACrateCentreNearerThanItsHalfEdgeCountsAsSunk) {
  const fountainref::FountainShape shape;
  game::PenetrationScratch scratch;
  const float size = 0.7f;
  // Resting on the ground: centre at half the edge, nothing inside.
  const std::vector<glm::vec3> resting = {{6.0f, 0.35f, 0.0f}};
  EXPECT_NEAR(game::worstPenetration(resting, shape, {}, size, 0.5f * size, scratch).depth, 0.0f, 1e-6f);
  // Sunk to y = 0.1: the box reaches 0.25 m below the ground, 0.36 edges (under the tolerance: an
  // impact's transient); sunk to y = -0.05, 0.57 edges: the centre went through the surface.
  const std::vector<glm::vec3> impact = {{6.0f, 0.1f, 0.0f}};
  const game::Penetration p = game::worstPenetration(impact, shape, {}, size, 0.5f * size, scratch);
  EXPECT_NEAR(p.depth, 0.25f, 1e-5f);
  EXPECT_LT(p.ratio, game::SoakDesc{}.crate_tolerance);
  const std::vector<glm::vec3> sunk = {{6.0f, -0.05f, 0.0f}};
  const game::Penetration q = game::worstPenetration(sunk, shape, {}, size, 0.5f * size, scratch);
  EXPECT_NEAR(q.depth, 0.4f, 1e-5f);
  EXPECT_GT(q.ratio, game::SoakDesc{}.crate_tolerance);
}

// A 0.6 m crate whose bottom reaches 2 cm into the ground (y = 0). A particle just above the
// ground inside its bottom has no free position (its way out of the crate is under the ground):
// left out and counted as squeezed. A particle as deep inside the crate's side, well above the
// ground, could leave: it counts.
TEST(SoakPenetration, InsideACrateCountsOnlyWhereTheCrateDoesNotReachIntoAStillCollider) {
  const fluid::BoxShape crate(glm::vec3(0.3f));
  const fluid::ColliderPose pose{.translation = glm::vec3(6.0f, 0.28f, 0.0f)};
  const fountainref::FountainShape fountain;
  const std::vector<game::PlacedShape> still = {{&fountain, {}}};
  game::PenetrationScratch scratch;
  std::size_t squeezed = 0;
  const std::vector<glm::vec3> squeezed_point = {{6.0f, 0.001f, 0.0f}};  // 2.1 cm inside the bottom face
  EXPECT_EQ(game::worstFreePenetration(squeezed_point, crate, pose, still, 0.01f, scratch, squeezed).depth, 0.0f);
  EXPECT_EQ(squeezed, 1u);
  // Without the ground as a still collider the same point counts, 2.1 radii deep.
  EXPECT_NEAR(game::worstFreePenetration(squeezed_point, crate, pose, {}, 0.01f, scratch, squeezed).ratio, 2.1f, 1e-3f);
  EXPECT_EQ(squeezed, 0u);
  const std::vector<glm::vec3> free_point = {{6.0f + 0.3f - 0.019f, 0.3f, 0.0f}, squeezed_point[0]};
  const game::Penetration p = game::worstFreePenetration(free_point, crate, pose, still, 0.01f, scratch, squeezed);
  EXPECT_NEAR(p.depth, 0.019f, 1e-5f);
  EXPECT_EQ(p.index, 0u);
  EXPECT_EQ(squeezed, 1u);
}

std::vector<game::PlayerThrow> allThrows(std::uint32_t seed, std::uint64_t steps, double mean_interval = 2.0,
                                         double explosive_share = 0.25) {
  game::ThrowScheduleDesc desc;
  desc.mean_interval_s = mean_interval;
  desc.explosive_share = explosive_share;
  game::ThrowSchedule schedule = game::makeThrowSchedule(desc, seed);
  std::vector<game::PlayerThrow> out;
  for (std::uint64_t step = 0; step < steps; ++step)
    if (auto t = game::throwDue(schedule, step)) out.push_back(*t);
  return out;
}

TEST(SoakThrows, TheSameSeedThrowsTheSameCratesAtTheSameSteps) {
  const std::vector<game::PlayerThrow> a = allThrows(42, 3600), b = allThrows(42, 3600), c = allThrows(43, 3600);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].step, b[i].step);
    EXPECT_EQ(a[i].from, b[i].from);
    EXPECT_EQ(a[i].target, b[i].target);
  }
  bool differs = a.size() != c.size();
  for (std::size_t i = 0; !differs && i < a.size(); ++i) differs = a[i].step != c[i].step || a[i].from != c[i].from;
  EXPECT_TRUE(differs) << "seeds 42 and 43 gave the same schedule";
}

TEST(SoakThrows, IntervalsAndPlacesStayInTheirRanges) {
  const game::ThrowScheduleDesc desc;
  const std::vector<game::PlayerThrow> throws = allThrows(7, 36000);
  // 10 minutes at a 2 s mean: about 300 throws.
  EXPECT_GT(throws.size(), 270u);
  EXPECT_LT(throws.size(), 330u);
  for (std::size_t i = 0; i < throws.size(); ++i) {
    const std::uint64_t gap = throws[i].step - (i == 0 ? 0 : throws[i - 1].step);
    EXPECT_GE(gap, 60u);   // 1 s
    EXPECT_LE(gap, 180u);  // 3 s
    const float stand = std::hypot(throws[i].from.x, throws[i].from.z);
    EXPECT_GE(stand, desc.stand_radius_min - 1e-4f);
    EXPECT_LE(stand, desc.stand_radius_max + 1e-4f);
    EXPECT_LE(std::hypot(throws[i].target.x, throws[i].target.z), desc.target_radius + 1e-4f);
  }
}

TEST(SoakThrows, ZeroIntervalNeverThrows) { EXPECT_TRUE(allThrows(1, 3600, 0.0).empty()); }

TEST(SoakThrows, TheExplosiveShareDecidesWhatIsThrownAndNothingElse) {
  const std::vector<game::PlayerThrow> crates = allThrows(7, 36000, 2.0, 0.0), mixed = allThrows(7, 36000, 2.0, 0.25),
                                       bombs = allThrows(7, 36000, 2.0, 1.0);
  ASSERT_EQ(crates.size(), mixed.size());
  ASSERT_EQ(crates.size(), bombs.size());
  std::size_t explosives = 0;
  for (std::size_t i = 0; i < crates.size(); ++i) {
    EXPECT_EQ(crates[i].step, mixed[i].step);
    EXPECT_EQ(crates[i].from, mixed[i].from);
    EXPECT_EQ(crates[i].target, bombs[i].target);
    EXPECT_FALSE(crates[i].explosive);
    EXPECT_TRUE(bombs[i].explosive);
    explosives += mixed[i].explosive ? 1 : 0;
  }
  // About 300 throws at a quarter each: 75 expected, standard deviation 7.5.
  EXPECT_GT(explosives, 45u);
  EXPECT_LT(explosives, 105u);
}

// The monitor on the real fountain world: a healthy world after a few steps passes; a particle,
// a sprite or a crate moved into the fountain, or a recorded NaN, fails naming the step and what.
class SoakMonitorOnFountain : public ::testing::Test {
 protected:
  void SetUp() override {
    game::SceneConfig scene;
    ASSERT_TRUE(game::loadSceneFile(game::scenesDir() / "fountain.json", scene).ok());
    std::string error;
    ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
    game::SoakDesc desc;
    desc.steps = 1000;
    desc.throws.mean_interval_s = 0.1;  // a throw within the first steps
    monitor = game::makeSoakMonitor(desc, world.step_seconds);
    for (int i = 0; i < 40; ++i) {
      game::soakBeforeStep(monitor, world, world.steps);
      game::stepWorld(world, nullptr);
    }
    ASSERT_GT(game::findState<game::SphFluid>(world)->world.particles.size(), 0u);
    // No GL here: the sprites' colliders are baked on the CPU, their read-back is set by hand.
    ASSERT_TRUE(game::loadSpriteColliders(*game::findState<game::SpriteParticles>(world), game::contentDir(), error))
        << error;
  }
  // A monitor without warm-up or throws that samples memory and gauges after every frame.
  game::SoakMonitor sampledEveryFrame() const {
    game::SoakDesc desc;
    desc.steps = 1000;
    desc.warmup_fraction = 0.0;
    desc.min_warmup_seconds = 0.0;
    desc.memory_every = 1;
    desc.throws.mean_interval_s = 0.0;
    return game::makeSoakMonitor(desc, world.step_seconds);
  }
  game::World world;
  game::SoakMonitor monitor;
};

TEST_F(SoakMonitorOnFountain, AHealthyWorldPasses) {
  EXPECT_TRUE(game::soakAfterFrame(monitor, world)) << monitor.failure;
  EXPECT_TRUE(monitor.failure.empty());
  EXPECT_GT(monitor.stats.throws, 0);
  ASSERT_NE(monitor.probe.range("sph"), nullptr);
  EXPECT_GT(monitor.probe.range("sph")->max, 0u);
  EXPECT_GT(monitor.probe.max_particle_speed, 1.0f);
}

TEST_F(SoakMonitorOnFountain, AnSphParticleInTheBasinWallFails) {
  const game::FountainGeometry& g = world.links.level;
  game::findState<game::SphFluid>(world)->world.particles.position[0] = {
      0.5f * (g.basin_inner_radius + g.basin_outer_radius), 0.4f, 0.0f};
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("step 40: sph particle id"), std::string::npos) << monitor.failure;
}

// Two moving 0.6 m crates a blast pressed 5 cm into each other, out in the yard. A particle in
// their overlap whose way out of one is inside the other has no free position: counted as
// squeezed, not a failure. A particle as deep inside the first crate's free side fails, and the
// report names that crate and every collider within a radius of the particle.
TEST_F(SoakMonitorOnFountain, InsideTwoOverlappingCratesIsSqueezedButInsideOneFreeSideFails) {
  fluid::SphWorld& sph = game::findState<game::SphFluid>(world)->world;
  const std::size_t first = sph.colliders.size();
  for (float x : {6.0f, 6.55f}) {
    fluid::SphCollider crate;
    crate.shape = std::make_shared<fluid::BoxShape>(glm::vec3(0.3f));
    crate.pose.translation = {x, 1.0f, 0.0f};
    crate.pose.linear_velocity = {0.0f, -0.5f, 0.0f};
    sph.colliders.push_back(crate);
  }
  ASSERT_TRUE(fluid::sphColliderMoves(sph.colliders[first]));
  // 2 cm inside the first crate's +x face, which lies 5 cm inside the second crate.
  sph.particles.position[0] = {6.28f, 1.0f, 0.0f};
  EXPECT_TRUE(game::soakAfterFrame(monitor, world)) << monitor.failure;
  EXPECT_GT(monitor.probe.squeezed_max, 0u);
  // 2 cm inside its -x face, in the open.
  sph.particles.position[0] = {5.72f, 1.0f, 0.0f};
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("(SPH collider " + std::to_string(first) + ", moving)"), std::string::npos)
      << monitor.failure;
  EXPECT_NE(monitor.failure.find("within a radius of collider " + std::to_string(first) + " (moving) -0.02"),
            std::string::npos)
      << monitor.failure;
}

// The first blast's allocations are warm-up: the memory samples start again at it, once.
TEST_F(SoakMonitorOnFountain, MemorySamplesStartAgainAtTheFirstBlast) {
  game::SoakMonitor m = sampledEveryFrame();
  ASSERT_NE(world.links.explosives, nullptr);
  ASSERT_EQ(world.links.explosives->detonated, 0u);
  ASSERT_TRUE(game::soakAfterFrame(m, world)) << m.failure;
  ASSERT_TRUE(game::soakAfterFrame(m, world)) << m.failure;
  EXPECT_EQ(m.rss_samples.size(), 2u);
  world.links.explosives->detonated = 1;
  ASSERT_TRUE(game::soakAfterFrame(m, world)) << m.failure;
  EXPECT_EQ(m.rss_samples.size(), 1u);
  EXPECT_EQ(m.heap_samples.size(), 1u);
  EXPECT_EQ(m.stats.memory_restart_step, world.steps);
  world.links.explosives->detonated = 2;  // later blasts: the samples go on
  ASSERT_TRUE(game::soakAfterFrame(m, world)) << m.failure;
  EXPECT_EQ(m.rss_samples.size(), 2u);
  EXPECT_NE(game::soakSummary(m).find("memory from step"), std::string::npos) << game::soakSummary(m);
}

TEST_F(SoakMonitorOnFountain, ASpriteUnderTheGroundFails) {
  // A read-back sprite 2.8 radii under the ground (the fountain's sprites are 0.018 m).
  game::findState<game::SpriteParticles>(world)->gpu.readback.positions = {glm::vec4(4.0f, 0.5f, 0.0f, 1.0f),
                                                                           glm::vec4(5.0f, -0.05f, 0.0f, 1.0f)};
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("live sprite 1 (ground)"), std::string::npos) << monitor.failure;
}

TEST_F(SoakMonitorOnFountain, ASpriteInTheAirPasses) {
  game::findState<game::SpriteParticles>(world)->gpu.readback.positions = {glm::vec4(4.0f, 0.5f, 0.0f, 1.0f)};
  EXPECT_TRUE(game::soakAfterFrame(monitor, world)) << monitor.failure;
}

TEST_F(SoakMonitorOnFountain, ASunkCrateFails) {
  game::findState<game::RigidBodies>(world)->current[2].position = {6.0f, -0.1f, 0.0f};  // centre under the ground
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("crate 2"), std::string::npos) << monitor.failure;
}

TEST_F(SoakMonitorOnFountain, ARecordedNonFiniteStateFails) {
  world.nonfinite_state = "sph_fluid particle id 3 position at step 40";
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("non-finite state: sph_fluid particle id 3"), std::string::npos) << monitor.failure;
}

// A system that refuses content at run time does not end the game: the world counts the failure
// (not as a NaN), the next frame meshes again, and the soak reports it.
TEST_F(SoakMonitorOnFountain, AMesherFailureIsCountedTheGameGoesOnAndTheSoakFails) {
  ASSERT_NE(game::findState<game::FluidSurface>(world), nullptr);
  const float threshold = game::findState<game::FluidSurface>(world)->params.threshold;
  game::findState<game::FluidSurface>(world)->params.threshold = -1.0f;  // refused by fluid::validateSurface
  game::meshWorld(world, nullptr);
  EXPECT_EQ(world.failures.count, 1u);
  EXPECT_NE(world.failures.first.find("fluid_surface: surface params: threshold"), std::string::npos)
      << world.failures.first;
  EXPECT_NE(world.failures.first.find("at step 40"), std::string::npos) << world.failures.first;
  EXPECT_TRUE(world.nonfinite_state.empty()) << world.nonfinite_state;
  EXPECT_TRUE(game::findState<game::FluidSurface>(world)->job.mesh.indices.empty());
  game::findState<game::FluidSurface>(world)->params.threshold = threshold;
  game::stepWorld(world, nullptr);
  game::meshWorld(world, nullptr);
  EXPECT_EQ(world.failures.count, 1u);
  EXPECT_GT(game::findState<game::FluidSurface>(world)->job.mesh.indices.size(), 0u);  // meshed again the next frame
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_NE(monitor.failure.find("run-time failure: fluid_surface: surface params"), std::string::npos)
      << monitor.failure;
}

// The fountain's water circulates through the pump: its effect reports the pool's level as a gauge,
// and the monitor samples it after warm-up with the memory.
TEST_F(SoakMonitorOnFountain, TheFountainReportsItsPoolLevelAndTheMonitorSamplesIt) {
  game::SoakMonitor m = sampledEveryFrame();
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(game::soakAfterFrame(m, world)) << m.failure;
    game::stepWorld(world, nullptr);
  }
  ASSERT_EQ(m.probe.gauges.size(), 1u);
  EXPECT_EQ(m.probe.gauges[0].name, "pool level");
  const float expected = game::waterWhereabouts(*game::findState<game::SphFluid>(world), world.links.level).pool_level;
  ASSERT_EQ(m.gauge_samples.size(), 1u);
  ASSERT_EQ(m.gauge_samples[0].size(), 3u);
  EXPECT_GE(m.gauge_samples[0][0], 0.15);  // issue 33: at least 15 cm of water in the basin
  EXPECT_NEAR(m.gauge_samples[0][2], expected, 0.02);
  EXPECT_NE(game::soakSummary(m).find("pool level "), std::string::npos) << game::soakSummary(m);
}

TEST_F(SoakMonitorOnFountain, TheRunStopsAfterItsSteps) {
  monitor.desc.steps = world.steps;
  EXPECT_FALSE(game::soakAfterFrame(monitor, world));
  EXPECT_TRUE(monitor.failure.empty()) << monitor.failure;
}

}  // namespace
