#pragma once
// CPU reference for the GPU particle tests: the same integrator as update.frag, step for step,
// and test-local depth-map colliders (an analytic plane and sphere encoded in the collide
// module's float32 and fixed8 texel formats) with a CPU rule-(2) query that follows
// fluid/collide's decoding. Collision reaction: fluid::resolveCollision (fluid/core).

#include "engine/gpu_particles/gpu_particles.hpp"
#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace gputest {

// One depth map with owned texels (GpuDepthMapView fields).
struct TestDepthMap {
  std::uint32_t format = 1, compare = 0, resolution = 0;
  glm::mat4 collider_to_map{1.0f};
  float z_scale = 1.0f;
  glm::vec3 cube_scale{1.0f};
  bool encloses_collider = false;
  std::vector<std::uint8_t> texels;
  engine::GpuDepthMapView view() const;
};

// L1 (octahedral) normal index, Kolb et al. §4.2 eq. (3), with the collide module's texel rule.
glm::ivec2 l1Texel(glm::vec3 direction, int resolution);
std::vector<float> l1NormalTable(int resolution);  // 3·R·R floats, texel (i,j) at j·R + i

struct TestCollider final : fluid::SignedDistanceShape {
  std::vector<TestDepthMap> maps;
  int normal_resolution = 64;
  std::vector<float> normal_table;
  fluid::ColliderPose pose{};
  void query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const override;
  fluid::ColliderSample sample(glm::vec3 local) const;
  fluid::ColliderSample sampleWorld(glm::vec3 world) const;
  std::vector<engine::GpuDepthMapView> views() const;
};

// Ground: the half-space y < 0 under [-2,2]×[-2,2] in x,z; one float32 LESS map looking down.
TestCollider makeGroundCollider(int resolution);
// Sphere: a fixed8 LESS + GREATER pair along z (front and back maps), normals indexed.
TestCollider makeSphereCollider(glm::vec3 centre, float radius, int resolution, int normal_resolution);

struct CpuFlowField {
  glm::ivec3 size{0};
  glm::vec3 origin{0.0f}, extent{1.0f};
  std::vector<glm::vec3> velocities;
  glm::vec3 sample(glm::vec3 p) const;  // same trilinear rule as update.frag
};

// SoA particle state mirroring the GPU textures.
struct CpuParticles {
  std::vector<glm::vec3> position, state1;  // state1: velocity (Euler) or P_{i-2} (Verlet)
  std::vector<float> death;
  std::vector<std::uint8_t> alive;
};

struct CpuStepDesc {
  engine::Integrator integrator = engine::Integrator::euler;
  float dt = 1.0f / 60.0f;
  engine::GpuStepParams params{};
  const CpuFlowField* flow = nullptr;
  std::vector<const TestCollider*> colliders;
};

void cpuSpawn(CpuParticles& p, const engine::BirthBatch& batch, float time, const CpuStepDesc& desc);
// time: the time at the end of this step (as GpuParticles::time after step()).
void cpuStep(CpuParticles& p, float time, const CpuStepDesc& desc);

}  // namespace gputest
