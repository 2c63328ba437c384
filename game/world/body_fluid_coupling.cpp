#include "game/world/body_fluid_coupling.hpp"

#include "fluid/sph/analytic_colliders.hpp"

#include <limits>

namespace game {

void initBodyFluidCoupling(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, glm::vec3 half_extents,
                           glm::vec3 region_min, glm::vec3 region_max) {
  coupling = BodyFluidCoupling{};
  coupling.box_shape = std::make_shared<fluid::BoxShape>(half_extents);
  // Water slides along wood and does not bounce off it (Kolb 2004 §3.3.2: ε = 0, small friction).
  coupling.material.resilience = 0.0f;
  coupling.material.friction = 0.05f;
  coupling.region_min = region_min;
  coupling.region_max = region_max;
  coupling.first_collider = sph.colliders.size();
  const float volume = 8.0f * half_extents.x * half_extents.y * half_extents.z;
  coupling.max_force = coupling.force_limit * sph.params.rest_density * glm::length(sph.params.gravity) * volume;
  coupling.reach = glm::length(half_extents);
  coupling.max_torque = coupling.max_force * coupling.reach;
}

void collidersFromBodies(BodyFluidCoupling& coupling, const engine::PhysicsWorld& physics,
                         std::span<const engine::BodyId> bodies, fluid::SphWorld& sph) {
  sph.colliders.resize(coupling.first_collider);
  coupling.coupled.clear();
  // Bounds of the water, grown by what can reach it this step: a box's half diagonal and the
  // kernel support (boundary terms act within it). A box outside costs the SPH step nothing.
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec3& x : sph.particles.position) {
    lo = glm::min(lo, x);
    hi = glm::max(hi, x);
  }
  const glm::vec3 grow(coupling.reach + 4.0f * sph.params.particle_radius);
  lo = glm::max(lo - grow, coupling.region_min);
  hi = glm::min(hi + grow, coupling.region_max);
  for (const engine::BodyId id : bodies) {
    const engine::BodyState state = engine::bodyState(physics, id);
    if (glm::any(glm::lessThan(state.position, lo)) || glm::any(glm::greaterThan(state.position, hi))) continue;
    fluid::SphCollider collider;
    collider.shape = coupling.box_shape;
    collider.pose = engine::colliderPoseOf(state);  // box centre = centre of mass
    collider.material = coupling.material;
    collider.integrate_pose = true;  // moves with its velocities through the SPH sub-steps
    sph.colliders.push_back(collider);
    coupling.coupled.push_back(id);
  }
}

std::string forcesToBodies(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, engine::PhysicsWorld& physics) {
  std::string bad;
  for (std::size_t k = 0; k < coupling.coupled.size(); ++k) {
    const fluid::SphCollider& collider = sph.colliders[coupling.first_collider + k];
    // fluid/sph reports the torque about pose.translation, the box centre: Bullet's centre of mass.
    glm::vec3 force = collider.force, torque = collider.torque;
    const float f = glm::length(force), t = glm::length(torque);
    const bool cap_force = f > coupling.max_force, cap_torque = t > coupling.max_torque;
    if (cap_force) force *= coupling.max_force / f;
    if (cap_torque) torque *= coupling.max_torque / t;
    if (!engine::setExternalForce(physics, coupling.coupled[k], force, torque)) {
      if (bad.empty()) bad = "fluid force on body " + std::to_string(coupling.coupled[k]) + " is not finite";
      continue;
    }
    ++coupling.forces_applied;
    coupling.clamped += (cap_force || cap_torque) ? 1u : 0u;
  }
  return bad;
}

}  // namespace game
