// State hashes of a World (contract and coverage: state_hash.hpp).
#include "game/replay/state_hash.hpp"

#include "game/world/blob_monster.hpp"
#include "game/world/world.hpp"

#include <algorithm>
#include <numeric>

namespace game {
namespace {

void addVec3(Fnv1a64& h, const glm::vec3& v) {
  h.add(v.x);
  h.add(v.y);
  h.add(v.z);
}

void addQuat(Fnv1a64& h, const glm::quat& q) {
  h.add(q.x);
  h.add(q.y);
  h.add(q.z);
  h.add(q.w);
}

std::uint64_t hashRigidBodies(const RigidBodies& bodies) {
  Fnv1a64 h;
  h.add(static_cast<std::uint64_t>(bodies.crates.size()));
  h.add(static_cast<std::int64_t>(bodies.thrown));
  const engine::PhysicsWorld& physics = *bodies.physics;
  for (engine::BodyId id : bodies.crates) {
    const engine::BodyState s = engine::bodyState(physics, id);
    addVec3(h, s.position);
    addQuat(h, s.rotation);
    addVec3(h, s.linear_velocity);
    addVec3(h, s.angular_velocity);
    const auto k = static_cast<std::size_t>(id);
    addVec3(h, k < physics.external_force.size() ? physics.external_force[k] : glm::vec3(0.0f));
    addVec3(h, k < physics.external_torque.size() ? physics.external_torque[k] : glm::vec3(0.0f));
  }
  return h.value;
}

std::uint64_t hashSph(const SphFluid& fluid, StateHashScratch& scratch) {
  const fluid::SphWorld& w = fluid.world;
  const fluid::ParticleStore& p = w.particles;
  // The store is re-sorted by grid cell each step; hash in id order so the hash says "same
  // particles in the same states", whatever the storage order.
  scratch.order.resize(p.size());
  std::iota(scratch.order.begin(), scratch.order.end(), 0u);
  std::sort(scratch.order.begin(), scratch.order.end(),
            [&p](std::uint32_t a, std::uint32_t b) { return p.id[a] < p.id[b]; });
  Fnv1a64 h;
  h.add(static_cast<std::uint64_t>(p.size()));
  for (std::uint32_t i : scratch.order) {
    h.add(p.id[i]);
    addVec3(h, p.position[i]);
    addVec3(h, p.velocity[i]);
    h.add(i < p.density.size() ? p.density[i] : 0.0f);
    h.add(i < p.pressure.size() ? p.pressure[i] : 0.0f);
  }
  h.add(w.time);
  h.add(w.step_count);
  h.add(w.next_id);
  h.add(w.last_dt);
  for (const fluid::SphEmitter& e : w.emitters) h.add(e.accumulator);
  // The pump's water is part of the state (the ids it will give back, in order, and when).
  if (w.pump.feeds_emitters || w.pump.size() > 0) {
    h.add(static_cast<std::uint64_t>(w.pump.size()));
    for (std::size_t k = w.pump.head; k < w.pump.held.size(); ++k) {
      h.add(w.pump.held[k].id);
      h.add(w.pump.held[k].ready_time);
    }
  }
  for (const fluid::SphCollider& c : w.colliders) {
    addQuat(h, c.pose.rotation);
    addVec3(h, c.pose.translation);
    addVec3(h, c.pose.linear_velocity);
    addVec3(h, c.pose.angular_velocity);
    addVec3(h, c.force);
    addVec3(h, c.torque);
  }
  return h.value;
}

// The blob monster (game/world/blob_monster.hpp): particles in index order (their order never
// changes), the behaviour machine, the round.
std::uint64_t hashBlob(const BlobMonster& blob) {
  Fnv1a64 h;
  const fluid::BlobParticles& p = blob.world.particles;
  h.add(static_cast<std::uint64_t>(p.size()));
  for (std::size_t i = 0; i < p.size(); ++i) {
    addVec3(h, p.position[i]);
    addVec3(h, p.velocity[i]);
  }
  h.add(static_cast<std::int64_t>(blob.machine.state));
  h.add(blob.machine.time_in_state);
  h.add(static_cast<std::int64_t>(blob.catches));
  h.add(blob.caught_timer);
  return h.value;
}

}  // namespace

void hashWorldState(const World& world, StateHashScratch& scratch, StateHash& out) {
  out.parts.clear();
  if (const RigidBodies* bodies = findState<RigidBodies>(world))
    out.parts.push_back({"rigid_bodies", hashRigidBodies(*bodies)});
  if (const SphFluid* fluid = findState<SphFluid>(world)) out.parts.push_back({"sph_fluid", hashSph(*fluid, scratch)});
  if (const BlobMonster* blob = findState<BlobMonster>(world)) out.parts.push_back({"blob", hashBlob(*blob)});
  Fnv1a64 h;
  h.add(world.steps);
  for (const SubsystemHash& part : out.parts) {
    h.bytes(part.name.data(), part.name.size());
    h.add(part.value);
  }
  out.combined = h.value;
}

}  // namespace game
