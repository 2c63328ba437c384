#pragma once
// Shared collider contract between the fluid solvers (fluid/sph), the depth-map colliders
// (fluid/collide) and the GPU sprites (engine/render): a collider answers "how far is this
// point from my surface, and which way is out", and one collision reaction serves them all.
//
// Reaction: Kolb, Latta & Rezk-Salama 2004, "Hardware-based Simulation and Collision
// Detection for Large Particle Systems", §3.3.2 (friction/resilience split and the double
// check of previous and predicted positions that pushes caught particles out).

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstddef>
#include <limits>
#include <span>

namespace fluid {

// One signed-distance sample. distance < 0 means inside the collider. normal is a unit
// vector pointing out of the collider (world space when returned by a world query).
// valid == false means the collider has no opinion at this point (e.g. outside every
// depth map's view volume); callers treat such a point as outside and far away.
struct ColliderSample {
  float distance = 0.0f;
  glm::vec3 normal{0.0f, 0.0f, 1.0f};
  bool valid = false;
};

// Rigid placement and motion of a collider, e.g. copied from a Bullet body every step.
// Points map from collider space to world space as world = rotation * local + translation.
struct ColliderPose {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 translation{0.0f};
  glm::vec3 linear_velocity{0.0f};   // m/s of the collider-space origin, world space
  glm::vec3 angular_velocity{0.0f};  // rad/s, world space, about the collider-space origin
};

glm::vec3 toColliderSpace(const ColliderPose& pose, glm::vec3 world_point);
glm::vec3 toWorldDirection(const ColliderPose& pose, glm::vec3 local_direction);
// Velocity of the collider's material at a world point (rigid motion: v + ω × r).
glm::vec3 colliderVelocityAt(const ColliderPose& pose, glm::vec3 world_point);

// A shape that can be asked for signed distance in its own (collider) space. Batch queries
// keep the virtual call out of the per-particle loop. Implementations must be thread-safe
// for concurrent const queries on disjoint output ranges.
class SignedDistanceShape {
 public:
  virtual ~SignedDistanceShape() = default;
  // Fills out[i] for local_points[i]; out.size() == local_points.size().
  virtual void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const = 0;
};

// Collision material, Kolb et al. §3.3.2. Values are clamped to [0, 1] where used.
struct CollisionMaterial {
  float friction = 0.1f;                   // ν: fraction of tangential velocity removed
  float resilience = 0.3f;                 // ε: fraction of normal velocity kept (bounce)
  float friction_speed_threshold = 0.05f;  // below this speed friction is not applied (m/s)
};

// Velocity after a collision, in the collider's rest frame: v' = (1 − ν) v∥ − ε v⊥ (§3.3.2).
// Only velocities heading into the surface (v · n < 0) are reflected; others are returned as is.
glm::vec3 collisionResponse(glm::vec3 velocity, glm::vec3 outward_normal, const CollisionMaterial& material);

// What the double check decided for one particle.
enum class CollisionOutcome { none, reacted, pushed_out };

struct CollisionResult {
  glm::vec3 position{0.0f};
  glm::vec3 velocity{0.0f};
  CollisionOutcome outcome = CollisionOutcome::none;
  // Reacted at its previous position: the predicted sample claimed a penetration deeper than the
  // particle moved since a sample that saw it outside (see resolveCollision).
  bool held_back = false;
};

// The double check of §3.3.2 for one particle: `previous` is the sample at the previous
// position, `predicted` the sample at predicted_position = previous_position + v*·dt.
//  - predicted outside (or invalid): nothing happens.
//  - previous outside, predicted inside: the particle is about to collide; its velocity gets
//    the friction/resilience reaction and the predicted position is moved onto the surface
//    along the normal, plus `skin`. When the predicted sample is deeper than the particle moved
//    relative to the collider plus `skin` plus `depth_slack` (the distance field's own error),
//    which a true penetration cannot be, the particle is held back at its previous position
//    instead and reacts against its own direction of travel (held_back). The default slack
//    (infinite) keeps the paper's rule.
//  - previous inside too: the particle is caught; it is pushed out along the normal to the
//    surface plus `skin`, and its normal velocity is made to head outside (v⊥ − v*, eq. of
//    §3.3.2 for a particle heading inside).
// Velocities are taken relative to `collider_velocity` so moving colliders push particles.
CollisionResult resolveCollision(glm::vec3 previous_position, const ColliderSample& previous,
                                 glm::vec3 predicted_position, glm::vec3 predicted_velocity,
                                 const ColliderSample& predicted, glm::vec3 collider_velocity, float dt, float skin,
                                 const CollisionMaterial& material,
                                 float depth_slack = std::numeric_limits<float>::infinity());

}  // namespace fluid
