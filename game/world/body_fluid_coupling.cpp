#include "game/world/body_fluid_coupling.hpp"

#include "fluid/sph/analytic_colliders.hpp"

#include <limits>

namespace game {

bool capWrench(const WrenchCap& cap, glm::vec3& force, glm::vec3& torque) {
  const float f = glm::length(force), t = glm::length(torque);
  const bool cap_force = f > cap.max_force, cap_torque = t > cap.max_torque;
  if (cap_force) force *= cap.max_force / f;
  if (cap_torque) torque *= cap.max_torque / t;
  return cap_force || cap_torque;
}

void grownBounds(std::span<const glm::vec3> points, glm::vec3 grow, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(std::numeric_limits<float>::max());
  hi = glm::vec3(-std::numeric_limits<float>::max());
  for (const glm::vec3& x : points) {
    lo = glm::min(lo, x);
    hi = glm::max(hi, x);
  }
  lo -= grow;
  hi += grow;
}

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
  coupling.cap.max_force = coupling.force_limit * sph.params.rest_density * glm::length(sph.params.gravity) * volume;
  coupling.reach = glm::length(half_extents);
  coupling.cap.max_torque = coupling.cap.max_force * coupling.reach;
}

void collidersFromBodies(BodyFluidCoupling& coupling, const engine::PhysicsWorld& physics,
                         std::span<const engine::BodyId> bodies, fluid::SphWorld& sph) {
  sph.colliders.resize(coupling.first_collider);
  coupling.coupled.clear();
  // Bounds of the water, grown by what can reach it this step: a box's half diagonal and the
  // kernel support (boundary terms act within it). A box outside costs the SPH step nothing.
  glm::vec3 lo, hi;
  grownBounds(sph.particles.position, glm::vec3(coupling.reach + 4.0f * sph.params.particle_radius), lo, hi);
  lo = glm::max(lo, coupling.region_min);
  hi = glm::min(hi, coupling.region_max);
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
    const bool capped = capWrench(coupling.cap, force, torque);
    if (!engine::setExternalForce(physics, coupling.coupled[k], force, torque)) {
      if (bad.empty()) bad = "fluid force on body " + std::to_string(coupling.coupled[k]) + " is not finite";
      continue;
    }
    ++coupling.forces_applied;
    coupling.clamped += capped ? 1u : 0u;
  }
  return bad;
}

}  // namespace game
