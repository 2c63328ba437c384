#pragma once
// Bullet rigid-body world: bodies from primitives (box, sphere, plane) and from triangle meshes
// (static, BVH), stepped in fixed substeps. Bodies are addressed by index (BodyId) in insertion
// order; they are never removed, only reset (thrown crates are recycled), so ids stay valid.

#include "engine/assets/assets.hpp"
#include "fluid/core/blast.hpp"
#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <memory>
#include <vector>

class btBroadphaseInterface;
class btCollisionConfiguration;
class btCollisionDispatcher;
class btCollisionShape;
class btConstraintSolver;
class btDiscreteDynamicsWorld;
class btRigidBody;
class btStridingMeshInterface;
struct btDefaultMotionState;

namespace engine {

using BodyId = int;

struct PhysicsDesc {
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};  // m/s^2
};

struct BodyDesc {
  float mass = 0.0f;         // kg; 0 = static
  glm::vec3 position{0.0f};  // metres, world
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 linear_velocity{0.0f};
  glm::vec3 angular_velocity{0.0f};
  float friction = 0.6f;
  float restitution = 0.1f;
};

struct BodyState {
  glm::vec3 position{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 linear_velocity{0.0f};
  glm::vec3 angular_velocity{0.0f};
};

// One contact manifold's push in one Bullet substep: the sum of its points' applied impulses (N s)
// along the normal, at their mean point. Bodies a < b by id (a static mesh or plane counts as a body).
struct ContactImpulse {
  BodyId a = -1, b = -1;
  glm::vec3 point{0.0f};  // m, world: the mean of the manifold's points
  float impulse = 0.0f;   // N s, > 0
  int substep = 0;        // which substep of the stepPhysics call (0 first)
};

// Owns every Bullet object. Not copyable; destroy with the unique_ptr from createPhysicsWorld.
struct PhysicsWorld {
  PhysicsWorld();
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  std::unique_ptr<btCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btBroadphaseInterface> broadphase;
  std::unique_ptr<btConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btStridingMeshInterface>> meshes;
  std::vector<std::unique_ptr<std::vector<glm::vec3>>> mesh_vertices;  // referenced by `meshes`
  std::vector<std::unique_ptr<std::vector<int>>> mesh_indices;
  std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;  // index = BodyId
  // External force (N, at the centre of mass) and torque (N m) per body for the next
  // stepPhysics call (every substep), then zeroed; sized lazily by setExternalForce.
  std::vector<glm::vec3> external_force, external_torque;
  std::uint64_t steps = 0;  // substeps taken
  // When set, stepPhysics lists every manifold with a non-zero push after each of its substeps in
  // `contacts` (cleared at the start of the call): what sound synthesis hears of the crates. A
  // resting contact appears too, pushing its weight each substep. Off: no cost.
  bool record_contacts = false;
  std::vector<ContactImpulse> contacts;
};

std::unique_ptr<PhysicsWorld> createPhysicsWorld(const PhysicsDesc& desc);

BodyId addBox(PhysicsWorld& world, const BodyDesc& desc, glm::vec3 half_extents);
BodyId addSphere(PhysicsWorld& world, const BodyDesc& desc, float radius);
// Infinite static plane {x : dot(normal, x) = offset}.
BodyId addStaticPlane(PhysicsWorld& world, glm::vec3 normal, float offset, float friction = 0.8f);
// Static concave body from a mesh (copied; `mesh` may be freed afterwards). Returns -1 and
// sets `error` if the mesh is empty or desc.mass != 0 (Bullet's BVH meshes are static only).
BodyId addStaticTriangleMesh(PhysicsWorld& world, const BodyDesc& desc, const MeshData& mesh, std::string& error);

// Holds `force` (N, through the centre of mass) and `torque` (N m) on a dynamic body during the
// next stepPhysics call, in every substep (Bullet clears its own accumulators after each one);
// they are zeroed afterwards. Wakes the body when the force is non-zero. Non-finite values are
// refused (returns false, nothing is applied).
bool setExternalForce(PhysicsWorld& world, BodyId id, glm::vec3 force, glm::vec3 torque);

// Advances exactly `substeps` internal steps of step_seconds / substeps each (no Bullet
// interpolation, so the result depends only on the inputs).
void stepPhysics(PhysicsWorld& world, double step_seconds, int substeps);

// Pushes every dynamic body within the blast's reach (fluid/core/blast.hpp): the impulse per area at
// the body's nearest point times the area its bounding box shows the blast, applied at that point,
// so a crate hit off-centre also spins. Returns the number of bodies pushed, or -1 (nothing applied)
// when validateBlast rejects the blast.
int applyBlast(PhysicsWorld& world, const fluid::Blast& blast);

int bodyCount(const PhysicsWorld& world);
BodyState bodyState(const PhysicsWorld& world, BodyId id);
// A body as the pose of a fluid collider (water, blob) that moves with it: collider space is the
// body's own, its origin the centre of mass (a box shape centred there), with the body's velocities
// so the collider pushes particles as it moves (fluid::colliderVelocityAt).
inline fluid::ColliderPose colliderPoseOf(const BodyState& body) {
  return {body.rotation, body.position, body.linear_velocity, body.angular_velocity};
}
// Takes a body out of the simulation (Bullet neither moves it nor collides with it) or puts it
// back at its current state. Ids stay valid: a game recycles short-lived bodies (explosives)
// instead of removing them.
void setBodyEnabled(PhysicsWorld& world, BodyId id, bool enabled);
bool bodyEnabled(const PhysicsWorld& world, BodyId id);

// Teleports a body and sets its velocities (wakes it up).
void resetBody(PhysicsWorld& world, BodyId id, const BodyState& state);
void setGravity(PhysicsWorld& world, glm::vec3 gravity);

// First body whose transform or velocity is NaN/inf, or -1.
BodyId findNonFiniteBody(const PhysicsWorld& world);

}  // namespace engine
