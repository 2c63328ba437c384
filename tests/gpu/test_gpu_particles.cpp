// GPU particles on a headless GL context (Mesa llvmpipe in CI): read back and compare with the
// CPU reference (tests/gpu/cpu_reference.*), collisions, birth/death, sorting, sprites, and a
// shader that fails to compile.
#include "engine/gpu_particles/gpu_particles.hpp"
#include "tests/gpu/cpu_reference.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

using namespace engine;
using namespace gputest;

namespace {

const std::filesystem::path kShaders = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";

class GpuParticlesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
  }
  void TearDown() override {
    destroyGpuParticles(system_);
    destroyContext(ctx_);
  }
  void create(std::uint32_t w, std::uint32_t h, Integrator integrator) {
    GpuParticlesDesc d;
    d.width = w;
    d.height = h;
    d.integrator = integrator;
    d.shader_dir = kShaders;
    createGpuParticles(d, system_);
    ASSERT_TRUE(system_.ready) << system_.error;
  }
  GlContext ctx_;
  GpuParticles system_;
};

BirthBatch randomBirths(std::size_t n, glm::vec3 lo, glm::vec3 hi, float speed, float lifetime, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  BirthBatch b;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::vec3 p = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
    const glm::vec3 v = speed * (2.0f * glm::vec3(u(rng), u(rng), u(rng)) - 1.0f);
    b.push(p, v, lifetime, 0, 1.0f);
  }
  return b;
}

struct Diff {
  float max = 0.0f;
  std::size_t over = 0;  // particles beyond the tolerance
};

Diff compare(const std::vector<glm::vec4>& gpu, const CpuParticles& cpu, float tolerance) {
  Diff d;
  for (std::size_t k = 0; k < cpu.position.size(); ++k) {
    EXPECT_EQ(gpu[k].w != 0.0f, cpu.alive[k] != 0) << "particle " << k;
    if (!cpu.alive[k]) continue;
    const float e = glm::length(glm::vec3(gpu[k]) - cpu.position[k]);
    d.max = std::max(d.max, e);
    d.over += e > tolerance;
  }
  return d;
}

CpuFlowField swirl() {
  CpuFlowField f;
  f.size = {8, 8, 8};
  f.origin = {-2.0f, -1.0f, -2.0f};
  f.extent = {4.0f, 4.0f, 4.0f};
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) f.velocities.push_back({0.3f * (z - 3.5f), 0.1f * y, -0.3f * (x - 3.5f)});
  return f;
}

void uploadFlow(GpuParticles& s, const CpuFlowField& f) {
  FlowFieldDesc d;
  d.size = f.size;
  d.origin = f.origin;
  d.extent = f.extent;
  d.velocities = f.velocities;
  std::string error;
  ASSERT_TRUE(setFlowField(s, d, error)) << error;
}

void uploadColliders(GpuParticles& s, const std::vector<const TestCollider*>& colliders) {
  std::vector<std::vector<GpuDepthMapView>> views;
  std::vector<GpuColliderDesc> descs;
  for (const TestCollider* c : colliders) views.push_back(c->views());
  for (std::size_t k = 0; k < colliders.size(); ++k) {
    GpuColliderDesc d;
    d.maps = views[k];
    d.normal_resolution = colliders[k]->normal_resolution;
    d.normal_table = colliders[k]->normal_table;
    d.pose = colliders[k]->pose;
    descs.push_back(d);
  }
  std::string error;
  ASSERT_TRUE(setColliders(s, descs, error)) << error;
}

GpuStepParams forces() {
  GpuStepParams p;
  p.gravity = {0.0f, -9.81f, 0.0f};
  p.wind = {0.5f, 0.0f, 0.2f};
  p.attractor_count = 1;
  p.attractors[0] = {{0.3f, 1.0f, 0.0f}, 0.5f, 0.2f};
  p.viscosity = 1.8e-5f * 50.0f;  // thick air, so the drag is visible in one second
  p.particle_radius = 0.01f;
  p.particle_mass = 1e-3f;
  return p;
}

}  // namespace

// §3.3.2 integration with gravity, wind, an attractor and Stokes drag in a flow-field texture:
// after 60 steps the GPU positions match the CPU reference integrator.
TEST_F(GpuParticlesTest, EulerMatchesCpuReference) {
  ASSERT_NO_FATAL_FAILURE(create(64, 64, Integrator::euler));
  const CpuFlowField flow = swirl();
  uploadFlow(system_, flow);
  CpuStepDesc cpu_desc;
  cpu_desc.params = forces();
  cpu_desc.flow = &flow;
  const BirthBatch births = randomBirths(4096, {-1, 0, -1}, {1, 2, 1}, 2.0f, 10.0f, 1);
  ASSERT_EQ(spawn(system_, births), 4096u);
  CpuParticles cpu;
  cpuSpawn(cpu, births, 0.0f, cpu_desc);
  for (int s = 0; s < 60; ++s) {
    step(system_, cpu_desc.params);
    cpuStep(cpu, system_.time, cpu_desc);
  }
  std::vector<glm::vec4> gpu;
  readPositions(system_, gpu);
  const Diff d = compare(gpu, cpu, 1e-4f);
  EXPECT_EQ(d.over, 0u) << "max error " << d.max << " m";
  EXPECT_LT(d.max, 1e-4f);
  // Something moved: the test cannot pass with a pass that does nothing.
  EXPECT_GT(glm::length(glm::vec3(gpu[0]) - births.positions[0]), 0.5f);
}

TEST_F(GpuParticlesTest, VerletMatchesCpuReference) {
  ASSERT_NO_FATAL_FAILURE(create(64, 64, Integrator::verlet));
  const CpuFlowField flow = swirl();
  uploadFlow(system_, flow);
  CpuStepDesc cpu_desc;
  cpu_desc.integrator = Integrator::verlet;
  cpu_desc.params = forces();
  cpu_desc.flow = &flow;
  const BirthBatch births = randomBirths(4096, {-1, 0, -1}, {1, 2, 1}, 2.0f, 10.0f, 2);
  ASSERT_EQ(spawn(system_, births), 4096u);
  CpuParticles cpu;
  cpuSpawn(cpu, births, 0.0f, cpu_desc);
  for (int s = 0; s < 60; ++s) {
    step(system_, cpu_desc.params);
    cpuStep(cpu, system_.time, cpu_desc);
  }
  std::vector<glm::vec4> gpu;
  readPositions(system_, gpu);
  const Diff d = compare(gpu, cpu, 1e-3f);
  EXPECT_EQ(d.over, 0u) << "max error " << d.max << " m";
  EXPECT_GT(glm::length(glm::vec3(gpu[0]) - births.positions[0]), 0.5f);
}
