#include "fluid/core/collider.hpp"

#include <algorithm>

namespace fluid {

glm::vec3 toColliderSpace(const ColliderPose& pose, glm::vec3 world_point) {
  return glm::inverse(pose.rotation) * (world_point - pose.translation);
}

glm::vec3 toWorldDirection(const ColliderPose& pose, glm::vec3 local_direction) {
  return pose.rotation * local_direction;
}

glm::vec3 colliderVelocityAt(const ColliderPose& pose, glm::vec3 world_point) {
  return pose.linear_velocity + glm::cross(pose.angular_velocity, world_point - pose.translation);
}

glm::vec3 collisionResponse(glm::vec3 velocity, glm::vec3 outward_normal, const CollisionMaterial& material) {
  const float normal_speed = glm::dot(velocity, outward_normal);
  if (normal_speed >= 0.0f) return velocity;  // already leaving the surface
  const glm::vec3 normal_part = normal_speed * outward_normal;
  const glm::vec3 tangential_part = velocity - normal_part;
  const float friction = std::clamp(material.friction, 0.0f, 1.0f);
  const float resilience = std::clamp(material.resilience, 0.0f, 1.0f);
  // §3.3.2: friction is skipped for slow particles so they do not creep to a halt.
  const bool apply_friction = glm::length(velocity) >= material.friction_speed_threshold;
  const float tangential_keep = apply_friction ? 1.0f - friction : 1.0f;
  return tangential_keep * tangential_part - resilience * normal_part;
}

CollisionResult resolveCollision(glm::vec3 previous_position, const ColliderSample& previous,
                                 glm::vec3 predicted_position, glm::vec3 predicted_velocity,
                                 const ColliderSample& predicted, glm::vec3 collider_velocity, float dt, float skin,
                                 const CollisionMaterial& material, float depth_slack) {
  CollisionResult result{predicted_position, predicted_velocity, CollisionOutcome::none};
  if (!predicted.valid || predicted.distance >= 0.0f) return result;

  const glm::vec3 relative = predicted_velocity - collider_velocity;
  const bool caught = previous.valid && previous.distance < 0.0f;
  if (!caught && previous.valid) {
    // A depth map measures distance along its axis or its cube's ray (§4.1, §4.3), so a point just
    // inside a concave corner or under an overhang (a floor beside a wall whose rim covers its
    // texel, a dish floor round a spire) can read many times deeper than it is. A particle the
    // previous sample saw outside went in at most as far as it moved relative to the collider: an
    // answer deeper than that by more than the field's own error (depth_slack) is not its
    // penetration, and projecting by it would throw the particle across the part. It stays at its
    // previous position, which the collider called outside (no skin added: next to such a corner the
    // field can flip to "deep inside" within a fraction of a millimetre), and reacts as if it had met
    // a surface square to its way: the way it was stopped.
    const glm::vec3 moved = predicted_position - previous_position - collider_velocity * dt;
    const float travelled = glm::length(moved);
    if (-predicted.distance > travelled + skin + depth_slack) {
      result.position = previous_position + collider_velocity * dt;
      const glm::vec3 blocking = travelled > 0.0f ? -moved / travelled : previous.normal;
      result.velocity = collisionResponse(relative, blocking, material) + collider_velocity;
      result.outcome = CollisionOutcome::reacted;
      result.held_back = true;
      return result;
    }
  }
  const glm::vec3 n = predicted.normal;
  // Projecting the predicted position onto the surface (plus a skin) guarantees the step
  // never ends inside the collider, to the accuracy of the distance field.
  result.position = predicted_position + n * (skin - predicted.distance);
  if (!caught) {
    // About to collide (Figure 2a): friction/resilience reaction.
    result.velocity = collisionResponse(relative, n, material) + collider_velocity;
    result.outcome = CollisionOutcome::reacted;
    return result;
  }
  // Already penetrated (Figure 2b): push out along the shortest way, and make the normal
  // velocity head outside. The printed case "v⊥ − v*" reduces to −v∥, which cannot move a
  // particle out; we read it as flipping the inward normal component, v∥ − v⊥.
  const float normal_speed = glm::dot(relative, n);
  glm::vec3 pushed = relative;
  if (normal_speed < 0.0f) pushed = relative - 2.0f * normal_speed * n;
  result.velocity = pushed + collider_velocity;
  result.outcome = CollisionOutcome::pushed_out;
  return result;
}

}  // namespace fluid
