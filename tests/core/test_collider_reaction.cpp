// Kolb et al. 2004 §3.3.2 collision reaction and double check.
#include "fluid/core/collider.hpp"

#include <gtest/gtest.h>

namespace {

constexpr glm::vec3 kUp{0.0f, 0.0f, 1.0f};

fluid::ColliderSample sample(float distance, glm::vec3 normal = kUp) { return {distance, normal, true}; }

TEST(CollisionResponse, SplitsIntoFrictionAndResilience) {
  const fluid::CollisionMaterial material{0.25f, 0.5f, 0.01f};
  const glm::vec3 v = fluid::collisionResponse({2.0f, 0.0f, -4.0f}, kUp, material);
  EXPECT_FLOAT_EQ(v.x, 1.5f);  // (1 - ν) v∥
  EXPECT_FLOAT_EQ(v.z, 2.0f);  // −ε v⊥
  EXPECT_FLOAT_EQ(v.y, 0.0f);
}

TEST(CollisionResponse, LeavesOutgoingVelocityAlone) {
  const glm::vec3 v = fluid::collisionResponse({1.0f, 2.0f, 3.0f}, kUp, {});
  EXPECT_EQ(v, glm::vec3(1.0f, 2.0f, 3.0f));
}

TEST(CollisionResponse, SkipsFrictionBelowSpeedThreshold) {
  const fluid::CollisionMaterial material{0.5f, 0.0f, 1.0f};
  const glm::vec3 v = fluid::collisionResponse({0.3f, 0.0f, -0.1f}, kUp, material);
  EXPECT_FLOAT_EQ(v.x, 0.3f);
  EXPECT_FLOAT_EQ(v.z, 0.0f);
}

TEST(ResolveCollision, NoCollisionWhenPredictedOutsideOrInvalid) {
  const auto outside =
      fluid::resolveCollision({0, 0, 1}, sample(1.0f), {0, 0, 0.5f}, {0, 0, -1}, sample(0.5f), {}, 0.5f, 0.01f, {});
  EXPECT_EQ(outside.outcome, fluid::CollisionOutcome::none);
  EXPECT_EQ(outside.position, glm::vec3(0, 0, 0.5f));
  const auto invalid = fluid::resolveCollision({0, 0, 1}, sample(1.0f), {0, 0, -0.5f}, {0, 0, -1},
                                               fluid::ColliderSample{}, {}, 0.5f, 0.01f, {});
  EXPECT_EQ(invalid.outcome, fluid::CollisionOutcome::none);
}

TEST(ResolveCollision, AboutToCollideReactsAndEndsOutside) {
  const fluid::CollisionMaterial material{0.0f, 0.5f, 0.0f};
  const auto result = fluid::resolveCollision({0, 0, 0.1f}, sample(0.1f), {0, 0, -0.2f}, {0, 0, -3.0f}, sample(-0.2f),
                                              {}, 0.1f, 0.01f, material);
  EXPECT_EQ(result.outcome, fluid::CollisionOutcome::reacted);
  EXPECT_NEAR(result.position.z, 0.01f, 1e-6f);
  EXPECT_NEAR(result.velocity.z, 1.5f, 1e-6f);
}

// A depth map's inside distance is measured along a map axis: 3 cm below the statue dish's top it
// can read half a metre (the dish's radius, from the side maps). A particle that entered from
// outside during its step is no deeper than its path is long, and is pushed out by no more.
TEST(ResolveCollision, AboutToCollideIsPushedNoFurtherThanItsPath) {
  const auto result = fluid::resolveCollision({0, 0, 0.02f}, sample(0.02f), {0, 0, -0.01f}, {0, 0, -1.8f},
                                              sample(-0.55f), {}, 1.0f / 60.0f, 0.01f, {});
  EXPECT_EQ(result.outcome, fluid::CollisionOutcome::reacted);
  EXPECT_NEAR(result.depth, 0.03f, 1e-6f);                // |step| = 3 cm, not 55 cm
  EXPECT_NEAR(result.position.z, -0.01f + 0.03f + 0.01f, 1e-6f);  // + the skin
  // A collider moving into the particle adds its own path: |v| dt = 2 m/s * 0.05 s = 10 cm.
  const auto moving = fluid::resolveCollision({0, 0, 0.02f}, sample(0.02f), {0, 0, -0.01f}, {0, 0, -1.8f},
                                              sample(-0.55f), {0, 0, 2.0f}, 0.05f, 0.0f, {});
  EXPECT_NEAR(moving.depth, 0.13f, 1e-6f);
  // An exact distance never reaches the cap: pushed by its depth, as before.
  const auto exact = fluid::resolveCollision({0, 0, 0.02f}, sample(0.02f), {0, 0, -0.01f}, {0, 0, -1.8f},
                                             sample(-0.01f), {}, 1.0f / 60.0f, 0.0f, {});
  EXPECT_NEAR(exact.depth, 0.01f, 1e-7f);
  EXPECT_NEAR(exact.position.z, 0.0f, 1e-7f);
}

TEST(ResolveCollision, CaughtParticleIsPushedOutHeadingOutside) {
  const auto result = fluid::resolveCollision({0, 0, -0.3f}, sample(-0.3f), {0, 0, -0.4f}, {1.0f, 0, -1.0f},
                                              sample(-0.4f), {}, 0.1f, 0.0f, {});
  EXPECT_EQ(result.outcome, fluid::CollisionOutcome::pushed_out);
  EXPECT_GE(result.position.z, 0.0f);
  EXPECT_FLOAT_EQ(result.depth, 0.4f);  // caught: the full depth, however short its step
  EXPECT_GT(result.velocity.z, 0.0f);
  EXPECT_FLOAT_EQ(result.velocity.x, 1.0f);
}

TEST(ResolveCollision, MovingColliderPushesRestingParticle) {
  // A wall moving up at 2 m/s hits a particle at rest: in the wall's frame the particle
  // heads inside at 2 m/s, so afterwards it must move up at least as fast as the wall.
  const fluid::CollisionMaterial material{0.0f, 0.0f, 0.0f};
  const auto result = fluid::resolveCollision({0, 0, 0.0f}, sample(0.01f), {0, 0, 0.0f}, {0, 0, 0}, sample(-0.05f),
                                              {0, 0, 2.0f}, 0.1f, 0.0f, material);
  EXPECT_EQ(result.outcome, fluid::CollisionOutcome::reacted);
  EXPECT_NEAR(result.velocity.z, 2.0f, 1e-6f);
}

TEST(ColliderPose, RoundTripsPointsAndRigidVelocity) {
  fluid::ColliderPose pose;
  pose.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 0, 1));
  pose.translation = {1, 2, 3};
  pose.angular_velocity = {0, 0, 1};
  const glm::vec3 local = fluid::toColliderSpace(pose, {1, 3, 3});
  EXPECT_NEAR(local.x, 1.0f, 1e-6f);
  EXPECT_NEAR(local.y, 0.0f, 1e-6f);
  const glm::vec3 v = fluid::colliderVelocityAt(pose, {2, 2, 3});
  EXPECT_NEAR(v.y, 1.0f, 1e-6f);  // ω × r with r = +x
}

}  // namespace
