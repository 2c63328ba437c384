// CPU side of the GPU particles: the §3.3.1 index allocator and the emitters (no GL needed).
#include "engine/gpu_particles/gpu_particles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

using namespace engine;

TEST(GpuAllocator, NeverHandsOutALiveIndexAndAlwaysTheSmallestFree) {
  constexpr std::uint32_t capacity = 1000;
  IndexAllocator a;
  initAllocator(a, capacity);
  std::set<std::uint32_t> live;
  std::mt19937 rng(7);
  for (int round = 0; round < 20000; ++round) {
    const bool do_alloc = live.empty() || (live.size() < capacity && rng() % 3 != 0);
    if (do_alloc) {
      std::uint32_t expect = 0;  // smallest index not live
      while (live.count(expect) != 0) ++expect;
      std::uint32_t index = 0;
      ASSERT_TRUE(allocateIndex(a, index));
      ASSERT_EQ(live.count(index), 0u) << "live index handed out at round " << round;
      ASSERT_EQ(index, expect);
      live.insert(index);
    } else {
      auto it = live.begin();
      std::advance(it, static_cast<long>(rng() % live.size()));
      releaseIndex(a, *it);
      live.erase(it);
    }
    ASSERT_EQ(a.live_count, live.size());
    ASSERT_EQ(a.active_range, live.empty() ? 0u : *live.rbegin() + 1);
  }
}

TEST(GpuAllocator, FullAllocatorRefusesAndKeepsPacked) {
  IndexAllocator a;
  initAllocator(a, 16);
  std::uint32_t index = 0;
  for (std::uint32_t k = 0; k < 16; ++k) {
    ASSERT_TRUE(allocateIndex(a, index));
    EXPECT_EQ(index, k);
  }
  index = 12345;
  EXPECT_FALSE(allocateIndex(a, index));
  EXPECT_EQ(index, 12345u);
  releaseIndex(a, 15);
  releaseIndex(a, 14);
  EXPECT_EQ(a.active_range, 14u);
  releaseIndex(a, 3);
  EXPECT_EQ(a.active_range, 14u);
  ASSERT_TRUE(allocateIndex(a, index));
  EXPECT_EQ(index, 3u);
}

TEST(GpuEmitters, DeterministicCountsAndDirections) {
  for (EmitterKind kind : {EmitterKind::spray, EmitterKind::mist, EmitterKind::splash, EmitterKind::debris}) {
    EmitterDesc d;
    d.kind = kind;
    d.position = {1.0f, 2.0f, 3.0f};
    d.direction = {0.0f, 0.0f, 2.0f};
    d.count = 500;
    d.seed = 42;
    BirthBatch a, b;
    emit(d, a);
    emit(d, b);
    ASSERT_EQ(a.size(), 500u);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.velocities, b.velocities);
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_GT(a.lifetimes[k], 0.0f);
      EXPECT_LE(glm::length(a.positions[k] - d.position), d.radius * 1.0001f);
      EXPECT_TRUE(std::isfinite(glm::length(a.velocities[k])));
      if (kind == EmitterKind::spray) {
        // Inside the cone around +z.
        const glm::vec3 dir = glm::normalize(a.velocities[k]);
        EXPECT_GE(dir.z, std::cos(d.spread) - 1e-4f);
      }
    }
  }
  EmitterDesc zero_dir;
  zero_dir.direction = glm::vec3(0.0f);
  BirthBatch c;
  emit(zero_dir, c);  // falls back to +y instead of producing NaN
  for (const glm::vec3& v : c.velocities) EXPECT_GT(v.y, 0.0f);
}

TEST(GpuEmitters, SprayFromFastFluidParticlesOnly) {
  const std::vector<glm::vec3> pos{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {NAN, 0, 0}};
  const std::vector<glm::vec3> vel{{0.5f, 0, 0}, {3, 0, 0}, {0, 5, 0}, {0, 0, 1.9f}, {9, 9, 9}};
  BirthBatch batch;
  EXPECT_EQ(emitSprayFromFluid(pos, vel, 2.0f, 0.0f, 1.0f, 0, 100, 1, batch), 2u);
  ASSERT_EQ(batch.size(), 2u);
  EXPECT_EQ(batch.positions[0], pos[1]);
  EXPECT_EQ(batch.velocities[1], vel[2]);
  BirthBatch capped;
  EXPECT_EQ(emitSprayFromFluid(pos, vel, 0.0f, 0.0f, 1.0f, 0, 1, 1, capped), 1u);
}

TEST(GpuSort, PassCountIsHalfLogSquaredPlusHalfLog) {
  EXPECT_EQ(sortPassCount(8), 6u);                // figure 3 of the paper: 6 stages for 8 values
  EXPECT_EQ(sortPassCount(1024u * 1024u), 210u);  // §3.3.3: 210 passes for 1024²
  EXPECT_EQ(sortPassCount(1), 0u);
}
