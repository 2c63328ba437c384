// fluid/core/impacts.hpp: what counts as an impact (a step's speed loss beyond free flight), the
// merging per cell, and independence from the particles' order in the store.
#include "fluid/core/impacts.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <vector>

namespace {

const glm::vec3 kGravity(0.0f, -9.81f, 0.0f);
constexpr float kDt = 1.0f / 60.0f;

struct Particles {
  std::vector<glm::vec3> position, velocity;
  std::vector<std::uint32_t> id;
};

void find(const Particles& p, fluid::ImpactTracker& tracker, std::vector<fluid::Impact>& out,
          const fluid::ImpactParams& params = {}) {
  fluid::findImpacts(p.position.data(), sizeof(glm::vec3), p.velocity.data(), sizeof(glm::vec3), p.id.data(),
                     p.position.size(), kGravity, kDt, params, tracker, out);
}

TEST(Impacts, FreeFlightIsNoImpactAndAStopIs) {
  Particles p{{glm::vec3(0.0f, 1.0f, 0.0f)}, {glm::vec3(0.0f, -4.0f, 0.0f)}, {5}};
  fluid::ImpactTracker tracker;
  std::vector<fluid::Impact> out;
  find(p, tracker, out);  // first sight: nothing to compare with
  EXPECT_TRUE(out.empty());
  p.velocity[0] += kGravity * kDt;  // falling freely
  find(p, tracker, out);
  EXPECT_TRUE(out.empty());
  const float before = -p.velocity[0].y;
  p.velocity[0] = glm::vec3(0.3f, 0.0f, 0.0f);  // landed
  find(p, tracker, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].speed, before, 1e-5f);
  EXPECT_EQ(out[0].particles, 1u);
  EXPECT_GT(out[0].speed_loss, 3.0f);
  // Slow particles make no impact, however they stop.
  p.velocity[0] = glm::vec3(0.0f, -0.5f, 0.0f);
  find(p, tracker, out);
  p.velocity[0] = glm::vec3(0.0f);
  find(p, tracker, out);
  EXPECT_TRUE(out.empty());
}

TEST(Impacts, ParticlesInOneCellMergeAndTheStoreOrderDoesNotMatter) {
  Particles p;
  for (std::uint32_t i = 0; i < 6; ++i) {
    // Three in one cell near the origin, three in a cell 2 m away.
    const float x = i < 3 ? 0.01f * i : 2.0f + 0.01f * i;
    p.position.push_back(glm::vec3(x, 0.1f, 0.1f));
    p.velocity.push_back(glm::vec3(0.0f, -3.0f - i, 0.0f));
    p.id.push_back(100 + i);
  }
  fluid::ImpactTracker tracker;
  std::vector<fluid::Impact> out, reversed_out;
  find(p, tracker, out);
  Particles reversed = p;
  std::reverse(reversed.position.begin(), reversed.position.end());
  std::reverse(reversed.velocity.begin(), reversed.velocity.end());
  std::reverse(reversed.id.begin(), reversed.id.end());
  fluid::ImpactTracker tracker2 = tracker;
  for (glm::vec3& v : p.velocity) v = glm::vec3(0.0f);
  for (glm::vec3& v : reversed.velocity) v = glm::vec3(0.0f);
  find(p, tracker, out);
  find(reversed, tracker2, reversed_out);
  ASSERT_EQ(out.size(), 2u);
  ASSERT_EQ(reversed_out.size(), 2u);
  EXPECT_EQ(out[0].particles + out[1].particles, 6u);
  EXPECT_EQ(out[0].particles, 3u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(out[i].speed, reversed_out[i].speed, 1e-5f);
    EXPECT_NEAR(out[i].position.x, reversed_out[i].position.x, 1e-5f);
  }
  // The mean speed of the first cell's three (3, 4, 5 m/s).
  EXPECT_NEAR(out[0].position.x < 1.0f ? out[0].speed : out[1].speed, 4.0f, 1e-5f);
}

TEST(Impacts, AnIdThatLeftAndCameBackIsNotAnImpact) {
  Particles p{{glm::vec3(0.0f)}, {glm::vec3(0.0f, -5.0f, 0.0f)}, {3}};
  fluid::ImpactTracker tracker;
  std::vector<fluid::Impact> out;
  find(p, tracker, out);
  Particles none;
  find(none, tracker, out);         // in the pump
  p.velocity[0] = glm::vec3(0.0f);  // given back at rest
  find(p, tracker, out);
  EXPECT_TRUE(out.empty());
}

}  // namespace
