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

}  // namespace
