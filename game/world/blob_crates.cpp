#include "game/world/blob_crates.hpp"

#include "engine/physics/physics_world.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "game/world/body_fluid_coupling.hpp"

#include <cmath>

namespace game {

// The start of world.colliders is the level, fixed at build and marked `level`, so stepBlob resolves
// the crates first and a particle a crate presses into a wall ends outside it.
void blobCollidersFromCrates(BlobMonster& s, const RigidBodies& bodies) {
  s.world.colliders.resize(s.level_colliders);
  s.crate_of_collider.clear();
  const float half = 0.5f * bodies.params.crate_size;
  const float reach = std::sqrt(3.0f) * half + s.params.spacing;
  glm::vec3 lo, hi;
  grownBounds(s.world.particles.position, glm::vec3(reach), lo, hi);
  if (!s.crate_shape) s.crate_shape = std::make_shared<fluid::BoxShape>(glm::vec3(half));
  for (std::size_t k = 0; k < bodies.crates.size(); ++k) {
    const engine::BodyState& b = bodies.current[k];
    if (glm::any(glm::lessThan(b.position, lo)) || glm::any(glm::greaterThan(b.position, hi))) continue;
    fluid::BlobCollider c;
    c.shape = s.crate_shape;
    c.pose = engine::colliderPoseOf(b);  // box centre = centre of mass
    s.world.colliders.push_back(c);
    s.crate_of_collider.push_back(static_cast<int>(k));
  }
}

void blobImpulsesToCrates(BlobMonster& s, RigidBodies& bodies, double step_seconds) {
  const float inv_dt = static_cast<float>(1.0 / step_seconds);
  const float edge = bodies.params.crate_size;
  WrenchCap cap;
  cap.max_force =
      kBlobCrateForceLimit * s.world.params.density * glm::length(s.world.params.gravity) * edge * edge * edge;
  cap.max_torque = cap.max_force * 0.5f * std::sqrt(3.0f) * edge;
  for (std::size_t k = 0; k < s.crate_of_collider.size(); ++k) {
    const fluid::BlobCollider& c = s.world.colliders[s.level_colliders + k];
    const engine::BodyId id = bodies.crates[static_cast<std::size_t>(s.crate_of_collider[k])];
    glm::vec3 force = c.impulse * inv_dt, torque = c.angular_impulse * inv_dt;
    s.crate_forces_capped += capWrench(cap, force, torque) ? 1u : 0u;
    engine::setExternalForce(*bodies.physics, id, force, torque);
  }
}

}  // namespace game
