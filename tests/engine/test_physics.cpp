#include "engine/physics/physics_world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

// A 20 m square floor at y = 0 as two triangles.
engine::MeshData floorMesh() {
  engine::MeshData mesh;
  mesh.positions = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
  mesh.normals.assign(4, glm::vec3(0, 1, 0));
  mesh.uvs.assign(4, glm::vec2(0));
  mesh.indices = {0, 2, 1, 0, 3, 2};
  return mesh;
}

engine::BodyDesc box(glm::vec3 position) {
  engine::BodyDesc desc;
  desc.mass = 2.0f;
  desc.position = position;
  return desc;
}

TEST(Physics, BoxFallsAndRestsOnAPrimitivePlane) {
  auto world = engine::createPhysicsWorld({});
  engine::addStaticPlane(*world, {0, 1, 0}, 0.0f);
  const engine::BodyId id = engine::addBox(*world, box({0, 3, 0}), glm::vec3(0.25f));
  engine::stepPhysics(*world, 1.0 / 60.0, 2);
  EXPECT_LT(engine::bodyState(*world, id).position.y, 3.0f);  // gravity acts
  for (int i = 0; i < 240; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 2);
  const engine::BodyState state = engine::bodyState(*world, id);
  EXPECT_NEAR(state.position.y, 0.25f, 0.02f);
  EXPECT_LT(glm::length(state.linear_velocity), 0.05f);
  EXPECT_EQ(world->steps, 241u * 2u);
}

TEST(Physics, BoxRestsOnAStaticTriangleMesh) {
  auto world = engine::createPhysicsWorld({});
  std::string error;
  ASSERT_GE(engine::addStaticTriangleMesh(*world, {}, floorMesh(), error), 0) << error;
  const engine::BodyId id = engine::addBox(*world, box({1, 2, -1}), glm::vec3(0.3f));
  for (int i = 0; i < 240; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 2);
  EXPECT_NEAR(engine::bodyState(*world, id).position.y, 0.3f, 0.03f);
}

TEST(Physics, TriangleMeshBodiesMustBeStaticAndNonEmpty) {
  auto world = engine::createPhysicsWorld({});
  std::string error;
  engine::BodyDesc dynamic;
  dynamic.mass = 1.0f;
  EXPECT_EQ(engine::addStaticTriangleMesh(*world, dynamic, floorMesh(), error), -1);
  EXPECT_NE(error.find("static"), std::string::npos) << error;
  error.clear();
  EXPECT_EQ(engine::addStaticTriangleMesh(*world, {}, engine::MeshData{}, error), -1);
  EXPECT_NE(error.find("empty"), std::string::npos) << error;
  EXPECT_EQ(engine::bodyCount(*world), 0);
}

TEST(Physics, SameInputsGiveBitIdenticalResults) {
  auto run = [] {
    auto world = engine::createPhysicsWorld({});
    engine::addStaticPlane(*world, {0, 1, 0}, 0.0f);
    std::vector<engine::BodyId> ids;
    for (int i = 0; i < 5; ++i) {
      engine::BodyDesc desc = box({0.1f * i, 1.0f + 0.7f * i, 0.05f * i});
      desc.rotation = glm::angleAxis(0.3f * i, glm::vec3(0, 1, 0));
      ids.push_back(engine::addBox(*world, desc, glm::vec3(0.3f)));
    }
    for (int i = 0; i < 120; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 3);
    std::vector<engine::BodyState> out;
    for (engine::BodyId id : ids) out.push_back(engine::bodyState(*world, id));
    return out;
  };
  const auto a = run();
  const auto b = run();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].position, b[i].position) << "body " << i;
    EXPECT_EQ(a[i].rotation, b[i].rotation) << "body " << i;
  }
}

TEST(Physics, ResetTeleportsAndNonFiniteBodiesAreFound) {
  auto world = engine::createPhysicsWorld({});
  engine::addStaticPlane(*world, {0, 1, 0}, 0.0f);
  const engine::BodyId a = engine::addBox(*world, box({0, 1, 0}), glm::vec3(0.2f));
  const engine::BodyId b = engine::addSphere(*world, box({2, 1, 0}), 0.2f);
  engine::BodyState moved;
  moved.position = {5, 4, 3};
  moved.linear_velocity = {1, 0, 0};
  engine::resetBody(*world, a, moved);
  EXPECT_EQ(engine::bodyState(*world, a).position, moved.position);
  EXPECT_EQ(engine::findNonFiniteBody(*world), -1);
  engine::BodyState bad;
  bad.position = {0, std::numeric_limits<float>::quiet_NaN(), 0};
  engine::resetBody(*world, b, bad);
  EXPECT_EQ(engine::findNonFiniteBody(*world), b);
}

// colliderPoseOf: a point fixed in the body, mapped by the pose (world = rotation * local +
// translation), moves over one physics step as colliderVelocityAt says it does.
TEST(Physics, ColliderPoseOfFollowsTheBody) {
  auto world = engine::createPhysicsWorld({glm::vec3(0.0f)});
  const engine::BodyId id = engine::addBox(*world, box({0, 0, 0}), glm::vec3(0.2f));
  engine::BodyState state;
  state.position = {1, 2, 3};
  state.rotation = glm::angleAxis(0.5f, glm::vec3(0, 1, 0));
  state.linear_velocity = {1, 0, 0};
  state.angular_velocity = {0, 0, 2};
  engine::resetBody(*world, id, state);
  const glm::vec3 corner(0.2f, 0.2f, 0.2f);  // body space
  const fluid::ColliderPose pose = engine::colliderPoseOf(engine::bodyState(*world, id));
  const glm::vec3 at = pose.rotation * corner + pose.translation;
  EXPECT_LT(glm::length(fluid::toColliderSpace(pose, at) - corner), 1e-6f);
  const glm::vec3 velocity = fluid::colliderVelocityAt(pose, at);
  const double dt = 1.0 / 240.0;
  engine::stepPhysics(*world, dt, 1);
  const fluid::ColliderPose after = engine::colliderPoseOf(engine::bodyState(*world, id));
  const glm::vec3 moved = (after.rotation * corner + after.translation - at) / static_cast<float>(dt);
  // Second order: the centripetal term |w|^2 |r| dt / 2 ~ 3e-3 m/s.
  EXPECT_LT(glm::length(moved - velocity), 0.01f) << moved.x << " " << moved.y << " " << moved.z;
  EXPECT_GT(glm::length(velocity - state.linear_velocity), 0.5f);  // the spin adds to the corner's speed
}

}  // namespace

namespace {

fluid::Blast blastAt(glm::vec3 centre) {
  fluid::Blast blast;
  blast.centre = centre;
  blast.impulse_at_1m = 60.0f;
  blast.core_radius = 0.25f;
  blast.reach = 4.0f;
  return blast;
}

TEST(PhysicsBlast, PushesNearerBodiesHarderAndAwayFromTheCentre) {
  auto world = engine::createPhysicsWorld({});
  engine::addStaticPlane(*world, {0, 1, 0}, 0.0f);
  const engine::BodyId near_box = engine::addBox(*world, box({1.0f, 0.25f, 0.0f}), glm::vec3(0.25f));
  const engine::BodyId far_box = engine::addBox(*world, box({-2.5f, 0.25f, 0.0f}), glm::vec3(0.25f));
  const engine::BodyId out_of_reach = engine::addBox(*world, box({0.0f, 0.25f, 6.0f}), glm::vec3(0.25f));
  EXPECT_EQ(engine::applyBlast(*world, blastAt({0.0f, 0.25f, 0.0f})), 2);
  const glm::vec3 v_near = engine::bodyState(*world, near_box).linear_velocity;
  const glm::vec3 v_far = engine::bodyState(*world, far_box).linear_velocity;
  EXPECT_GT(v_near.x, 0.0f);
  EXPECT_LT(v_far.x, 0.0f);
  EXPECT_GT(std::abs(v_near.x), 4.0f * std::abs(v_far.x));  // nearest faces at 0.75 m and 2.25 m: 9x by 1/r^2
  // The impulse is I(r) * A / m: 60 / 0.75^2 * 0.5^2 / 2 kg = 13.3 m/s; Bullet's collision margin
  // grows the box a little, so allow 10 %.
  EXPECT_NEAR(v_near.x, 60.0f / (0.75f * 0.75f) * 0.25f / 2.0f, 1.4f);
  EXPECT_EQ(engine::bodyState(*world, out_of_reach).linear_velocity, glm::vec3(0.0f));
}

TEST(PhysicsBlast, AnOffCentreHitSpinsTheBodyAndItStaysFiniteAfterTenBlasts) {
  auto world = engine::createPhysicsWorld({});
  engine::addStaticPlane(*world, {0, 1, 0}, 0.0f);
  const engine::BodyId id = engine::addBox(*world, box({0.0f, 0.25f, 0.0f}), glm::vec3(0.25f));
  EXPECT_EQ(engine::applyBlast(*world, blastAt({0.6f, 0.45f, 0.3f})), 1);
  EXPECT_GT(glm::length(engine::bodyState(*world, id).angular_velocity), 0.1f);
  for (int i = 0; i < 10; ++i) engine::applyBlast(*world, blastAt({0.0f, 0.25f, 0.0f}));  // inside the box
  for (int i = 0; i < 120; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 2);
  EXPECT_EQ(engine::findNonFiniteBody(*world), -1);
}

TEST(PhysicsBlast, AnInvalidBlastIsRefusedAndMovesNothing) {
  auto world = engine::createPhysicsWorld({});
  const engine::BodyId id = engine::addBox(*world, box({0.0f, 1.0f, 0.0f}), glm::vec3(0.25f));
  fluid::Blast blast = blastAt({0.0f, 0.0f, 0.0f});
  blast.centre.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(engine::applyBlast(*world, blast), -1);
  EXPECT_EQ(engine::bodyState(*world, id).linear_velocity, glm::vec3(0.0f));
}

}  // namespace

TEST(Physics, ADisabledBodyStaysPutAndMovesAgainWhenEnabled) {
  auto world = engine::createPhysicsWorld({});
  const engine::BodyId id = engine::addBox(*world, box({0.0f, 2.0f, 0.0f}), glm::vec3(0.25f));
  engine::setBodyEnabled(*world, id, false);
  EXPECT_FALSE(engine::bodyEnabled(*world, id));
  for (int i = 0; i < 30; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 2);
  EXPECT_EQ(engine::bodyState(*world, id).position.y, 2.0f);
  fluid::Blast blast;
  blast.centre = {0.0f, 1.5f, 0.0f};
  EXPECT_EQ(engine::applyBlast(*world, blast), 0) << "a disabled body is out of the blast's reach too";
  engine::setBodyEnabled(*world, id, true);
  for (int i = 0; i < 30; ++i) engine::stepPhysics(*world, 1.0 / 60.0, 2);
  EXPECT_LT(engine::bodyState(*world, id).position.y, 1.0f);
}
