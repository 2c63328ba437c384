#include "engine/camera/camera.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace engine {

glm::vec3 cameraForward(const FpsCamera& camera) {
  const float yaw = glm::radians(camera.yaw_degrees);
  const float pitch = glm::radians(camera.pitch_degrees);
  return {std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch)};
}

void updateCamera(FpsCamera& camera, const CameraInput& input, float dt_seconds) {
  if (!std::isfinite(dt_seconds) || dt_seconds < 0.0f) dt_seconds = 0.0f;
  camera.yaw_degrees += input.look_dx * camera.mouse_sensitivity;
  camera.yaw_degrees = std::remainder(camera.yaw_degrees, 360.0f);
  camera.pitch_degrees = std::clamp(camera.pitch_degrees - input.look_dy * camera.mouse_sensitivity, -89.0f, 89.0f);
  const float yaw = glm::radians(camera.yaw_degrees);
  const glm::vec3 heading(std::cos(yaw), 0.0f, std::sin(yaw));
  const glm::vec3 right(-heading.z, 0.0f, heading.x);
  glm::vec3 move = heading * input.forward + right * input.right + glm::vec3(0.0f, 1.0f, 0.0f) * input.up;
  const float length = glm::length(move);
  if (length > 1.0f) move /= length;
  camera.position += move * camera.move_speed * (input.fast ? 3.0f : 1.0f) * dt_seconds;
  camera.position = glm::clamp(camera.position, camera.bounds_min, camera.bounds_max);
}

glm::mat4 cameraView(const FpsCamera& camera) {
  return glm::lookAt(camera.position, camera.position + cameraForward(camera), glm::vec3(0.0f, 1.0f, 0.0f));
}

glm::mat4 cameraProjection(const FpsCamera& camera, float aspect) {
  return glm::perspective(glm::radians(camera.fov_degrees), std::max(aspect, 1e-3f), camera.near_plane,
                          camera.far_plane);
}

}  // namespace engine
