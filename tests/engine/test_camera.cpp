#include "engine/camera/camera.hpp"

#include <gtest/gtest.h>

namespace {

TEST(Camera, YawMinus90LooksAlongNegativeZAndMovesThere) {
  engine::FpsCamera camera;
  camera.position = glm::vec3(0.0f);
  camera.pitch_degrees = 0.0f;
  const glm::vec3 forward = engine::cameraForward(camera);
  EXPECT_NEAR(forward.z, -1.0f, 1e-6f);
  engine::CameraInput input;
  input.forward = 1.0f;
  engine::updateCamera(camera, input, 0.5f);
  EXPECT_NEAR(camera.position.z, -0.5f * camera.move_speed, 1e-5f);
  EXPECT_NEAR(camera.position.x, 0.0f, 1e-5f);
}

TEST(Camera, PitchIsClampedAndBadDtIsIgnored) {
  engine::FpsCamera camera;
  engine::CameraInput input;
  input.look_dy = -100000.0f;  // mouse far up
  engine::updateCamera(camera, input, 0.016f);
  EXPECT_FLOAT_EQ(camera.pitch_degrees, 89.0f);
  const glm::vec3 before = camera.position;
  input = {};
  input.forward = 1.0f;
  engine::updateCamera(camera, input, std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(camera.position, before);
}

// A player sprinting for ten seconds at each of the eight compass headings (and up, and down)
// stays inside the level's box and slides along its walls.
TEST(Camera, SprintingNeverLeavesTheBounds) {
  for (int heading = 0; heading < 10; ++heading) {
    engine::FpsCamera camera;
    camera.position = glm::vec3(0.0f, 2.6f, 9.5f);
    camera.bounds_min = glm::vec3(-15.0f, 0.4f, -15.0f);
    camera.bounds_max = glm::vec3(15.0f, 10.0f, 15.0f);
    camera.yaw_degrees = 45.0f * static_cast<float>(heading);
    engine::CameraInput input;
    input.forward = heading < 8 ? 1.0f : 0.0f;
    input.right = heading < 8 ? 0.3f : 0.0f;
    input.up = heading == 8 ? 1.0f : (heading == 9 ? -1.0f : 0.0f);
    input.fast = true;
    for (int frame = 0; frame < 600; ++frame) {
      engine::updateCamera(camera, input, 1.0f / 60.0f);
      for (int axis = 0; axis < 3; ++axis) {
        ASSERT_GE(camera.position[axis], camera.bounds_min[axis]) << "heading " << heading << " frame " << frame;
        ASSERT_LE(camera.position[axis], camera.bounds_max[axis]) << "heading " << heading << " frame " << frame;
      }
    }
    // 10 s at 15 m/s would have carried it 150 m: it ends on the box's face.
    const bool on_a_face = camera.position.x == -15.0f || camera.position.x == 15.0f || camera.position.z == -15.0f ||
                           camera.position.z == 15.0f || camera.position.y == 0.4f || camera.position.y == 10.0f;
    EXPECT_TRUE(on_a_face) << "heading " << heading;
  }
}

}  // namespace
