#pragma once
// CPU reference for the GPU particle tests: the same integrator as update.frag, step for step;
// collisions by the collide module's CPU implementation (fluid::collideParticles on a
// fluid::DepthMapCollider), followed by the same extra push-out projections as the shader.

#include "engine/gpu_particles/gpu_particles.hpp"
#include "fluid/collide/collide.hpp"
#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace gputest {

// A fluid/collide depth-map collider with its pose and the storage of its GPU description.
struct TestCollider {
  fluid::DepthMapCollider shape;
  fluid::ColliderPose pose{};
  std::vector<engine::GpuDepthMapView> views;
  std::vector<float> normal_table;
  engine::GpuColliderDesc gpu();  // for engine::setColliders
  fluid::ColliderSample sampleWorld(glm::vec3 world) const;
};

// Ground: the half-space y < 0 under [-2,2]×[-2,2] in x,z; one float32 LESS map looking down,
// encoded by hand (fluid/collide texel layout).
TestCollider makeGroundCollider(int resolution);
// Sphere baked by fluid::bakeDepthMaps from a UV-sphere mesh. float32/fixed8: LESS+GREATER
// pairs along x, y, z; front_back16: three pairs; cube8: one GREATER depth cube only.
TestCollider makeSphereCollider(glm::vec3 centre, float radius, int resolution, fluid::DepthMapFormat format);

struct CpuFlowField {
  glm::ivec3 size{0};
  glm::vec3 origin{0.0f}, extent{1.0f};
  std::vector<glm::vec3> velocities;
  glm::vec3 sample(glm::vec3 p) const;  // same trilinear rule as update.frag
};

// SoA particle state mirroring the GPU textures.
struct CpuParticles {
  std::vector<glm::vec3> previous, predicted, velocity;  // scratch
  fluid::CollideScratch scratch;
  std::vector<glm::vec3> position, state1;  // state1: velocity (Euler) or P_{i-2} (Verlet)
  std::vector<float> death;
  std::vector<std::uint8_t> alive;
};

struct CpuStepDesc {
  engine::Integrator integrator = engine::Integrator::euler;
  float dt = 1.0f / 60.0f;
  engine::GpuStepParams params{};
  const CpuFlowField* flow = nullptr;
  std::vector<TestCollider*> colliders;
};

void cpuSpawn(CpuParticles& p, const engine::BirthBatch& batch, float time, const CpuStepDesc& desc);
// time: the time at the end of this step (as GpuParticles::time after step()).
void cpuStep(CpuParticles& p, float time, const CpuStepDesc& desc);

}  // namespace gputest
