// The blob hunts (issue 35 item 2; paper §7: a goo creature whose tentacles reach for you): its
// tentacles grow toward the target, point at it, curl and sway, and retract when it is out of
// reach; the body stretches along its motion while chasing; the chase keeps to the street's box.
// Each as a number, printed as "[blob] ..." for the README's table.
#include "blob_test_level.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace {

using fluid::BlobBehaviour;
using fluid::BlobBehaviourKind;

constexpr float kDegrees = 57.2957795f;

float mean(const std::vector<float>& v) {
  return v.empty() ? 0.0f : std::accumulate(v.begin(), v.end(), 0.0f) / static_cast<float>(v.size());
}
float largest(const std::vector<float>& v) { return v.empty() ? 0.0f : *std::max_element(v.begin(), v.end()); }

void run(fluid::BlobWorld& w, const BlobBehaviour& b, glm::vec3 target, float seconds) {
  const int steps = static_cast<int>(std::lround(seconds / w.params.step));
  for (int s = 0; s < steps; ++s) {
    fluid::updateBlobBehaviour(w, b, target, w.params.step);
    const fluid::BlobStatus st = fluid::stepBlob(w);
    ASSERT_TRUE(st.ok()) << st.error;
  }
}

// The hunting tentacles as the shipped program's chase has them (content/blob/monster.program.json).
BlobBehaviour hunter(BlobBehaviourKind kind) {
  BlobBehaviour b;
  b.kind = kind;
  b.tentacles = 4;
  b.tentacle_particles = 30;
  b.tentacle_length = 1.6f;
  b.tentacle_spread = 0.35f;
  b.reach_range = 3.5f;
  b.grow_speed = 1.5f;
  b.curl = 0.35f;
  b.speed = 1.2f;
  b.stretch = 0.5f;
  return b;
}

TEST(BlobHunting, TentaclesGrowTowardThePlayerPointAtHimCurlAndRetract) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const BlobBehaviour b = hunter(BlobBehaviourKind::tentacles);
  const glm::vec3 eye(2.6f, 1.6f, 0.4f);  // a player's eye 2.6 m away, above the goo
  fluid::startBlobBehaviour(w, b, eye);
  const float tips0 = mean(fluid::blobTentacleTipDistances(w, eye));
  run(w, b, eye, 0.5f);
  const float tips05 = mean(fluid::blobTentacleTipDistances(w, eye));
  run(w, b, eye, 1.5f);
  const float tips2 = mean(fluid::blobTentacleTipDistances(w, eye));
  const std::vector<float> angles = fluid::blobTentacleAimAngles(w, eye);
  // Curl and sway: the tips' sideways wander (across the direction to the eye) over 2 s of reaching.
  const glm::vec3 to = glm::normalize(eye - fluid::blobCentroid(w.particles.position));
  float wander = 0.0f;
  std::vector<glm::vec3> first;
  for (int s = 0; s < 120; ++s) {
    run(w, b, eye, w.params.step);
    for (std::size_t k = 0; k < w.target.tentacle_particles.size(); ++k) {
      glm::vec3 tip = w.particles.position[w.target.tentacle_particles[k].back()];
      tip -= glm::dot(tip, to) * to;
      if (s == 0) first.push_back(tip);
      wander = std::max(wander, glm::length(tip - first[k]));
    }
  }
  const float reach_before = mean(fluid::blobTentacleReach(w));
  // The player runs off, out of reach: the tentacles retract to stubs.
  const glm::vec3 far(9.0f, 1.6f, 0.4f);
  run(w, b, far, 1.5f);
  const float reach_after = mean(fluid::blobTentacleReach(w));
  std::printf(
      "[blob] hunt: tentacle tips %.2f m from the eye at the start, %.2f m after 0.5 s, %.2f m after 2 s; "
      "aim off the line to the eye mean %.1f deg, worst %.1f deg; tips wander %.2f m across it in 2 s; "
      "reach %.2f m -> %.2f m 1.5 s after the player left (%.1f m away)\n",
      tips0, tips05, tips2, mean(angles) * kDegrees, largest(angles) * kDegrees, wander, reach_before, reach_after,
      glm::length(far - fluid::blobCentroid(w.particles.position)));
  EXPECT_LT(tips05, tips0 - 0.4f);  // they grow toward him, not all at once
  EXPECT_LT(tips2, tips0 - 1.0f);   // and come over a metre closer
  ASSERT_EQ(angles.size(), 4u);
  // They point at him: the tips are fanned by half the 0.35 rad spread, plus the curl.
  EXPECT_LT(mean(angles) * kDegrees, 20.0f);
  EXPECT_LT(largest(angles) * kDegrees, 25.0f);
  EXPECT_GT(wander, 0.05f);  // not rigid spikes
  EXPECT_LT(reach_after, 0.5f * reach_before);
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
  EXPECT_LE(fluid::blobMaxSpeed(w.particles.velocity), 20.0f);
}

TEST(BlobHunting, TheBodyStretchesAlongItsChaseAndRelaxesAtRest) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  BlobBehaviour b = hunter(BlobBehaviourKind::chase);
  const glm::vec3 heading(1.0f, 0.0f, 0.0f);
  glm::vec3 target(12.0f, 1.6f, 0.0f);
  fluid::startBlobBehaviour(w, b, target);
  run(w, b, target, 1.0f);
  float moving = 0.0f;
  for (int s = 0; s < 60; ++s) {
    run(w, b, target, w.params.step);
    moving += fluid::blobCoreAspect(w, heading) / 60.0f;
  }
  // The player stands still on the blob's far side: it arrives and stops.
  target = fluid::blobCentroid(w.particles.position) + glm::vec3(0.5f, 1.2f, 0.0f);
  run(w, b, target, 2.5f);
  const float rest = fluid::blobCoreAspect(w, heading);
  // The same chase without squash and stretch, moving.
  fluid::BlobWorld rigid = blobtest::restingBlob();
  rigid.colliders.push_back(blobtest::ground());
  b.stretch = 0.0f;
  const glm::vec3 far(12.0f, 1.6f, 0.0f);
  fluid::startBlobBehaviour(rigid, b, far);
  run(rigid, b, far, 2.0f);
  const float unstretched = fluid::blobCoreAspect(rigid, heading);
  std::printf(
      "[blob] squash and stretch: core aspect (extent along the heading / height) %.2f moving at 1.2 m/s, %.2f at "
      "rest, %.2f moving with stretch 0\n",
      moving, rest, unstretched);
  EXPECT_GT(moving, 1.2f * rest);
  EXPECT_GT(moving, 1.2f * unstretched);
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
}

TEST(BlobHunting, TheChaseKeepsToTheStreet) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  w.keep_min = glm::vec3(-3.0f, -1.0f, -3.0f);
  w.keep_max = glm::vec3(3.0f, 5.0f, 3.0f);
  const BlobBehaviour b = hunter(BlobBehaviourKind::chase);
  const glm::vec3 outside(10.0f, 1.6f, -6.0f);  // the player is beyond the street's corner
  fluid::startBlobBehaviour(w, b, outside);
  run(w, b, outside, 8.0f);
  const glm::vec3 c = fluid::blobCentroid(w.particles.position);
  const float radius = fluid::blobBodyRadius(w.params);
  std::printf(
      "[blob] street edge: chasing a player at (10, -6) the centroid stops at (%.2f, %.2f) inside x, z <= 3 "
      "(body radius %.2f m)\n",
      c.x, c.z, radius);
  EXPECT_GT(c.x, 1.5f);  // it did go after him
  EXPECT_LE(c.x, 3.0f - 0.7f * radius);
  EXPECT_GE(c.z, -3.0f + 0.7f * radius);
}

TEST(BlobHunting, TheHunterStaysOnTheGroundWhileItsTentaclesReachUp) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const BlobBehaviour b = hunter(BlobBehaviourKind::chase);
  // A player standing 1.5 m away, his eye 3.2 m up (the scene's start height), within reach_range:
  // the tentacles reach up for it, and the body must not climb them.
  const glm::vec3 eye(1.5f, 3.2f, 0.0f);
  fluid::startBlobBehaviour(w, b, eye);
  const float start_y = fluid::blobCentroid(w.particles.position).y;
  float highest = start_y, core_highest = -1e30f;
  for (int s = 0; s < 4 * 60; ++s) {
    run(w, b, eye, w.params.step);
    highest = std::max(highest, fluid::blobCentroid(w.particles.position).y);
    float core = 0.0f;
    int n = 0;
    for (std::size_t i = 0; i < w.particles.size(); ++i)
      if (w.particles.tentacle[i] < 0) core += w.particles.position[i].y, ++n;
    core_highest = std::max(core_highest, core / static_cast<float>(n));
  }
  const float reach = mean(fluid::blobTentacleReach(w));
  std::printf(
      "[blob] hunter on the ground: centroid %.2f m high at the start, at most %.2f m (core at most %.2f m) "
      "in 4 s while its tentacles reach %.2f m for an eye 3.2 m up\n",
      start_y, highest, core_highest, reach);
  EXPECT_GT(reach, 1.0f);  // they do reach for it
  EXPECT_LT(core_highest, start_y + 0.15f);
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
}

}  // namespace
