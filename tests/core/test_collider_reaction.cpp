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

TEST(ResolveCollision, CaughtParticleIsPushedOutHeadingOutside) {
  const auto result = fluid::resolveCollision({0, 0, -0.3f}, sample(-0.3f), {0, 0, -0.4f}, {1.0f, 0, -1.0f},
                                              sample(-0.4f), {}, 0.1f, 0.0f, {});
  EXPECT_EQ(result.outcome, fluid::CollisionOutcome::pushed_out);
  EXPECT_GE(result.position.z, 0.0f);
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

// A depth map's distance is measured along an axis, so a point just inside a concave corner can
// read far deeper than it is: a particle that was outside 5 cm before cannot be 50 cm inside.
TEST(ResolveCollision, SampleDeeperThanThePathIsHeldBackWithASlack) {
  const fluid::CollisionMaterial material{0.0f, 0.5f, 0.0f};
  const glm::vec3 from{0, 0, 0.1f}, to{0, 0, 0.05f}, velocity{0, 0, -0.5f};
  const fluid::ColliderSample axis_error = sample(-0.5f, glm::vec3(1, 0, 0));
  const auto held =
      fluid::resolveCollision(from, sample(0.1f), to, velocity, axis_error, {}, 0.1f, 0.01f, material, 0.04f);
  EXPECT_TRUE(held.held_back);
  EXPECT_EQ(held.outcome, fluid::CollisionOutcome::reacted);
  EXPECT_EQ(held.position, from);
  // Stopped on its way down: the way it came is the blocking normal (resilience 0.5).
  EXPECT_NEAR(held.velocity.z, 0.25f, 1e-6f);
  EXPECT_FLOAT_EQ(held.velocity.x, 0.0f);
  // Without a slack (the paper's rule) the sample's normal and depth throw it half a metre sideways.
  const auto paper = fluid::resolveCollision(from, sample(0.1f), to, velocity, axis_error, {}, 0.1f, 0.01f, material);
  EXPECT_FALSE(paper.held_back);
  EXPECT_NEAR(paper.position.x, 0.51f, 1e-6f);
  // A depth within the path plus skin and slack is a penetration: projected as before.
  const auto within =
      fluid::resolveCollision(from, sample(0.1f), to, velocity, sample(-0.08f), {}, 0.1f, 0.01f, material, 0.04f);
  EXPECT_FALSE(within.held_back);
  EXPECT_NEAR(within.position.z, 0.05f + 0.09f, 1e-6f);
  // Closer than the skin before: it stays exactly there (next to a concave corner a skin's push can
  // land where the field reads deep inside again).
  const auto grazing = fluid::resolveCollision(from, sample(0.0001f), to, velocity, axis_error, {}, 0.1f, 0.01f,
                                               material, 0.04f);
  EXPECT_TRUE(grazing.held_back);
  EXPECT_EQ(grazing.position, from);
  // Caught (inside before): the previous sample says nothing about the depth, no hold.
  const auto caught =
      fluid::resolveCollision(from, sample(-0.01f), to, velocity, axis_error, {}, 0.1f, 0.01f, material, 0.04f);
  EXPECT_FALSE(caught.held_back);
  EXPECT_EQ(caught.outcome, fluid::CollisionOutcome::pushed_out);
}

// Held back next to a moving collider: the particle is carried along with it.
TEST(ResolveCollision, HeldBackParticleMovesWithTheCollider) {
  const glm::vec3 wall_velocity{0, 0, 1.0f};
  const auto held = fluid::resolveCollision({0, 0, 0.2f}, sample(0.2f), {0, 0, 0.25f}, {0, 0, 0.5f}, sample(-0.6f),
                                            wall_velocity, 0.1f, 0.0f, {}, 0.04f);
  EXPECT_TRUE(held.held_back);
  EXPECT_NEAR(held.position.z, 0.3f, 1e-6f);  // previous position + wall velocity * dt
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
