#pragma once
// First-person camera, y up. yaw = -90 degrees looks along -z; pitch is clamped to ±89.

#include <glm/glm.hpp>

namespace engine {

struct FpsCamera {
  glm::vec3 position{0.0f, 2.0f, 12.0f};  // metres
  float yaw_degrees = -90.0f;
  float pitch_degrees = -8.0f;
  float fov_degrees = 60.0f;        // vertical
  float move_speed = 5.0f;          // m/s
  float mouse_sensitivity = 0.12f;  // degrees per pixel
  float near_plane = 0.05f;
  float far_plane = 400.0f;
  // The box the player may move in (the level's edges); updateCamera keeps the position inside.
  // By default a 2 km box around the origin, the largest a scene may give.
  glm::vec3 bounds_min{-1000.0f};
  glm::vec3 bounds_max{1000.0f};
};

struct CameraInput {
  float forward = 0.0f;  // -1..1 along the view heading (horizontal)
  float right = 0.0f;    // -1..1
  float up = 0.0f;       // -1..1 world up
  bool fast = false;     // x3 speed
  float look_dx = 0.0f;  // mouse pixels (right = positive)
  float look_dy = 0.0f;  // mouse pixels (down = positive)
};

void updateCamera(FpsCamera& camera, const CameraInput& input, float dt_seconds);
glm::vec3 cameraForward(const FpsCamera& camera);
glm::mat4 cameraView(const FpsCamera& camera);
glm::mat4 cameraProjection(const FpsCamera& camera, float aspect);

}  // namespace engine
