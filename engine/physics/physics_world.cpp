#include "engine/physics/physics_world.hpp"

#include "fluid/core/finite.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace engine {
namespace {

btVector3 bt(glm::vec3 v) { return {v.x, v.y, v.z}; }
glm::vec3 toGlm(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

BodyId addBody(PhysicsWorld& world, const BodyDesc& desc, std::unique_ptr<btCollisionShape> shape) {
  btTransform transform;
  transform.setIdentity();
  transform.setOrigin(bt(desc.position));
  transform.setRotation(btQuaternion(desc.rotation.x, desc.rotation.y, desc.rotation.z, desc.rotation.w));
  const float mass = desc.mass > 0.0f ? desc.mass : 0.0f;
  btVector3 inertia(0, 0, 0);
  if (mass > 0.0f) shape->calculateLocalInertia(mass, inertia);
  auto motion = std::make_unique<btDefaultMotionState>(transform);
  btRigidBody::btRigidBodyConstructionInfo info(mass, motion.get(), shape.get(), inertia);
  info.m_friction = desc.friction;
  info.m_restitution = desc.restitution;
  auto body = std::make_unique<btRigidBody>(info);
  if (mass > 0.0f) {
    body->setLinearVelocity(bt(desc.linear_velocity));
    body->setAngularVelocity(bt(desc.angular_velocity));
  }
  world.world->addRigidBody(body.get());
  world.shapes.push_back(std::move(shape));
  world.motion_states.push_back(std::move(motion));
  world.bodies.push_back(std::move(body));
  return static_cast<BodyId>(world.bodies.size() - 1);
}

}  // namespace

PhysicsWorld::PhysicsWorld() = default;

PhysicsWorld::~PhysicsWorld() {
  // Bodies must leave the world before the world (and then shapes/meshes) go away.
  if (world) {
    for (auto& body : bodies)
      if (body->isInWorld()) world->removeRigidBody(body.get());
  }
  bodies.clear();
  world.reset();
  solver.reset();
  broadphase.reset();
  dispatcher.reset();
  configuration.reset();
  motion_states.clear();
  shapes.clear();
  meshes.clear();
}

std::unique_ptr<PhysicsWorld> createPhysicsWorld(const PhysicsDesc& desc) {
  auto world = std::make_unique<PhysicsWorld>();
  world->configuration = std::make_unique<btDefaultCollisionConfiguration>();
  world->dispatcher = std::make_unique<btCollisionDispatcher>(world->configuration.get());
  world->broadphase = std::make_unique<btDbvtBroadphase>();
  world->solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  world->world = std::make_unique<btDiscreteDynamicsWorld>(world->dispatcher.get(), world->broadphase.get(),
                                                           world->solver.get(), world->configuration.get());
  world->world->setGravity(bt(desc.gravity));
  return world;
}

BodyId addBox(PhysicsWorld& world, const BodyDesc& desc, glm::vec3 half_extents) {
  return addBody(world, desc, std::make_unique<btBoxShape>(bt(glm::max(half_extents, glm::vec3(1e-3f)))));
}

BodyId addSphere(PhysicsWorld& world, const BodyDesc& desc, float radius) {
  return addBody(world, desc, std::make_unique<btSphereShape>(std::max(radius, 1e-3f)));
}

BodyId addStaticPlane(PhysicsWorld& world, glm::vec3 normal, float offset, float friction) {
  BodyDesc desc;
  desc.friction = friction;
  return addBody(world, desc, std::make_unique<btStaticPlaneShape>(bt(glm::normalize(normal)), offset));
}

BodyId addStaticTriangleMesh(PhysicsWorld& world, const BodyDesc& desc, const MeshData& mesh, std::string& error) {
  if (desc.mass != 0.0f) {
    error = "triangle-mesh bodies must be static (mass 0)";
    return -1;
  }
  if (mesh.indices.size() < 3 || mesh.positions.empty()) {
    error = "triangle-mesh body from an empty mesh";
    return -1;
  }
  auto vertices = std::make_unique<std::vector<glm::vec3>>(mesh.positions);
  auto indices = std::make_unique<std::vector<int>>(mesh.indices.begin(), mesh.indices.end());
  btIndexedMesh part;
  part.m_numTriangles = static_cast<int>(indices->size() / 3);
  part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indices->data());
  part.m_triangleIndexStride = 3 * sizeof(int);
  part.m_numVertices = static_cast<int>(vertices->size());
  part.m_vertexBase = reinterpret_cast<const unsigned char*>(vertices->data());
  part.m_vertexStride = sizeof(glm::vec3);
  part.m_indexType = PHY_INTEGER;
  part.m_vertexType = PHY_FLOAT;
  auto array = std::make_unique<btTriangleIndexVertexArray>();
  array->addIndexedMesh(part, PHY_INTEGER);
  auto shape = std::make_unique<btBvhTriangleMeshShape>(array.get(), true);
  world.mesh_vertices.push_back(std::move(vertices));
  world.mesh_indices.push_back(std::move(indices));
  world.meshes.push_back(std::move(array));
  return addBody(world, desc, std::move(shape));
}

namespace {

BodyId bodyIdOf(const PhysicsWorld& world, const btCollisionObject* object) {
  for (std::size_t i = 0; i < world.bodies.size(); ++i)
    if (world.bodies[i].get() == object) return static_cast<BodyId>(i);
  return -1;
}

// The manifolds of the substep just taken, in the dispatcher's order (Bullet is serial here, so
// the same inputs give the same manifolds in the same order).
void recordContacts(PhysicsWorld& world, int substep) {
  btDispatcher& dispatcher = *world.world->getDispatcher();
  const int count = dispatcher.getNumManifolds();
  for (int m = 0; m < count; ++m) {
    const btPersistentManifold& manifold = *dispatcher.getManifoldByIndexInternal(m);
    ContactImpulse contact;
    contact.substep = substep;
    glm::vec3 sum(0.0f);
    for (int p = 0; p < manifold.getNumContacts(); ++p) {
      const btManifoldPoint& point = manifold.getContactPoint(p);
      contact.impulse += point.getAppliedImpulse();
      const btVector3 at = point.getPositionWorldOnB();
      sum += glm::vec3(at.x(), at.y(), at.z());
    }
    if (!(contact.impulse > 0.0f) || manifold.getNumContacts() == 0) continue;
    contact.point = sum / static_cast<float>(manifold.getNumContacts());
    BodyId a = bodyIdOf(world, manifold.getBody0()), b = bodyIdOf(world, manifold.getBody1());
    if (a > b) std::swap(a, b);
    contact.a = a;
    contact.b = b;
    world.contacts.push_back(contact);
  }
}

}  // namespace

void stepPhysics(PhysicsWorld& world, double step_seconds, int substeps) {
  substeps = std::max(substeps, 1);
  world.contacts.clear();
  const btScalar h = static_cast<btScalar>(step_seconds / substeps);
  // maxSubSteps = 0 makes Bullet take exactly one step of h: no internal accumulator.
  for (int i = 0; i < substeps; ++i) {
    for (std::size_t b = 0; b < world.external_force.size(); ++b) {
      if (world.external_force[b] == glm::vec3(0.0f) && world.external_torque[b] == glm::vec3(0.0f)) continue;
      world.bodies[b]->applyCentralForce(bt(world.external_force[b]));
      world.bodies[b]->applyTorque(bt(world.external_torque[b]));
    }
    world.world->stepSimulation(h, 0);
    if (world.record_contacts) recordContacts(world, i);
    ++world.steps;
  }
  std::fill(world.external_force.begin(), world.external_force.end(), glm::vec3(0.0f));
  std::fill(world.external_torque.begin(), world.external_torque.end(), glm::vec3(0.0f));
}

bool setExternalForce(PhysicsWorld& world, BodyId id, glm::vec3 force, glm::vec3 torque) {
  assert(id >= 0 && id < bodyCount(world));
  if (!fluid::isFinite(force) || !fluid::isFinite(torque)) return false;
  const auto index = static_cast<std::size_t>(id);
  if (world.external_force.size() < world.bodies.size()) {
    world.external_force.resize(world.bodies.size(), glm::vec3(0.0f));
    world.external_torque.resize(world.bodies.size(), glm::vec3(0.0f));
  }
  btRigidBody& body = *world.bodies[index];
  if (body.getInvMass() == 0.0f) return true;  // static: nothing moves it
  world.external_force[index] = force;
  world.external_torque[index] = torque;
  if (force != glm::vec3(0.0f) || torque != glm::vec3(0.0f)) body.activate();
  return true;
}

int applyBlast(PhysicsWorld& world, const fluid::Blast& blast) {
  if (!fluid::validateBlast(blast).empty()) return -1;
  int pushed = 0;
  for (auto& body : world.bodies) {
    if (body->getInvMass() == 0.0f || !body->isInWorld()) continue;
    btVector3 aabb_min, aabb_max;
    body->getAabb(aabb_min, aabb_max);
    const glm::vec3 lo = toGlm(aabb_min), hi = toGlm(aabb_max);
    // Distance to the box's nearest point, not its centre: an explosive lying against a crate
    // gives it the full near-field push.
    const glm::vec3 nearest = glm::clamp(blast.centre, lo, hi);
    const float impulse_per_area = fluid::blastImpulsePerArea(blast, glm::length(nearest - blast.centre));
    if (!(impulse_per_area > 0.0f)) continue;
    const glm::vec3 centre = toGlm(body->getCenterOfMassPosition());
    const glm::vec3 direction = fluid::blastDirection(blast, centre);
    // Projected area of the axis-aligned box along `direction` (exact for the box; a rotated
    // crate's bounding box overstates its area by at most sqrt(3)).
    const glm::vec3 extent = hi - lo;
    const float area = std::abs(direction.x) * extent.y * extent.z + std::abs(direction.y) * extent.x * extent.z +
                       std::abs(direction.z) * extent.x * extent.y;
    body->applyImpulse(bt(impulse_per_area * area * direction), bt(nearest - centre));
    body->activate(true);
    ++pushed;
  }
  return pushed;
}

int bodyCount(const PhysicsWorld& world) { return static_cast<int>(world.bodies.size()); }

BodyState bodyState(const PhysicsWorld& world, BodyId id) {
  assert(id >= 0 && id < bodyCount(world));
  const btRigidBody& body = *world.bodies[static_cast<std::size_t>(id)];
  const btTransform& transform = body.getWorldTransform();
  const btQuaternion q = transform.getRotation();
  BodyState state;
  state.position = toGlm(transform.getOrigin());
  state.rotation = glm::quat(q.w(), q.x(), q.y(), q.z());
  state.linear_velocity = toGlm(body.getLinearVelocity());
  state.angular_velocity = toGlm(body.getAngularVelocity());
  return state;
}

void resetBody(PhysicsWorld& world, BodyId id, const BodyState& state) {
  assert(id >= 0 && id < bodyCount(world));
  btRigidBody& body = *world.bodies[static_cast<std::size_t>(id)];
  btTransform transform;
  transform.setIdentity();
  transform.setOrigin(bt(state.position));
  transform.setRotation(btQuaternion(state.rotation.x, state.rotation.y, state.rotation.z, state.rotation.w));
  body.setWorldTransform(transform);
  if (body.getMotionState() != nullptr) body.getMotionState()->setWorldTransform(transform);
  body.setInterpolationWorldTransform(transform);
  body.setLinearVelocity(bt(state.linear_velocity));
  body.setAngularVelocity(bt(state.angular_velocity));
  body.clearForces();
  body.activate(true);
}

void setBodyEnabled(PhysicsWorld& world, BodyId id, bool enabled) {
  assert(id >= 0 && id < bodyCount(world));
  btRigidBody* body = world.bodies[static_cast<std::size_t>(id)].get();
  if (enabled == body->isInWorld()) return;
  if (enabled) {
    world.world->addRigidBody(body);  // takes the world's gravity again
    body->activate(true);
  } else {
    world.world->removeRigidBody(body);
  }
}

bool bodyEnabled(const PhysicsWorld& world, BodyId id) {
  assert(id >= 0 && id < bodyCount(world));
  return world.bodies[static_cast<std::size_t>(id)]->isInWorld();
}

void setGravity(PhysicsWorld& world, glm::vec3 gravity) {
  world.world->setGravity(bt(gravity));
  for (auto& body : world.bodies) {
    if (!body->isStaticObject()) {
      body->setGravity(bt(gravity));
      body->activate(true);
    }
  }
}

BodyId findNonFiniteBody(const PhysicsWorld& world) {
  for (std::size_t i = 0; i < world.bodies.size(); ++i) {
    const btRigidBody& body = *world.bodies[i];
    const btTransform& t = body.getWorldTransform();
    const btQuaternion q = t.getRotation();
    const btVector3 v = body.getLinearVelocity();
    const btVector3 w = body.getAngularVelocity();
    const btScalar values[] = {t.getOrigin().x(),
                               t.getOrigin().y(),
                               t.getOrigin().z(),
                               q.x(),
                               q.y(),
                               q.z(),
                               q.w(),
                               v.x(),
                               v.y(),
                               v.z(),
                               w.x(),
                               w.y(),
                               w.z()};
    for (btScalar value : values) {
      if (!std::isfinite(value)) return static_cast<BodyId>(i);
    }
  }
  return -1;
}

}  // namespace engine
