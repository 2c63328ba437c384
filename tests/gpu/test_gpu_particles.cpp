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

void uploadColliders(GpuParticles& s, const std::vector<TestCollider*>& colliders) {
  std::vector<GpuColliderDesc> descs;
  for (TestCollider* c : colliders) descs.push_back(c->gpu());
  std::string error;
  ASSERT_TRUE(setColliders(s, descs, error)) << error;
}

const char* formatLabel(fluid::DepthMapFormat f) { return fluid::formatName(f); }

std::string formatTestName(const ::testing::TestParamInfo<fluid::DepthMapFormat>& param) {
  std::string name = fluid::formatName(param.param);
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
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
  std::printf("[ metric ] euler forces, 4096 particles, 60 steps: max GPU−CPU position difference %.3g m\n", d.max);
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
  std::printf("[ metric ] verlet forces, 4096 particles, 60 steps: max GPU−CPU position difference %.3g m\n", d.max);
}

// Decoding: particles at rest on a lattice through the ground and a sphere baked by the
// collide module in each format, one step with no forces. A particle inside is projected to
// surface + skin along the decoded normal by the decoded distance, so GPU and CPU
// (fluid::DepthMapCollider) positions agree only if both pick the same map and texel by rule (2)
// and decode depth and normal alike.
class GpuDecodeTest : public GpuParticlesTest, public ::testing::WithParamInterface<fluid::DepthMapFormat> {};

TEST_P(GpuDecodeTest, DepthMapDecodeMatchesCpuQuery) {
  ASSERT_NO_FATAL_FAILURE(create(64, 64, Integrator::euler));
  TestCollider ground = makeGroundCollider(64);
  TestCollider sphere = makeSphereCollider({0.0f, 0.6f, 0.0f}, 0.35f, 64, GetParam());
  CpuStepDesc cpu_desc;
  cpu_desc.params.gravity = glm::vec3(0.0f);
  cpu_desc.params.push_out_iterations = 0;
  cpu_desc.colliders = {&ground, &sphere};
  ASSERT_NO_FATAL_FAILURE(uploadColliders(system_, cpu_desc.colliders));
  BirthBatch b;
  for (int k = 0; k < 4096; ++k) {  // 16×16×16 lattice over the sphere and the ground
    const glm::vec3 p(-0.45f + 0.06f * static_cast<float>(k % 16), -0.1f + 0.06f * static_cast<float>((k / 16) % 16),
                      -0.45f + 0.06f * static_cast<float>(k / 256));
    b.push(p, glm::vec3(0.0f), 10.0f, 0, 0.0f);
  }
  ASSERT_EQ(spawn(system_, b), b.size());
  CpuParticles cpu;
  cpuSpawn(cpu, b, 0.0f, cpu_desc);
  step(system_, cpu_desc.params);
  cpuStep(cpu, system_.time, cpu_desc);
  std::vector<glm::vec4> gpu;
  readPositions(system_, gpu);
  std::size_t moved = 0;
  for (std::size_t k = 0; k < b.size(); ++k) moved += glm::length(cpu.position[k] - b.positions[k]) > 0.0f;
  EXPECT_GT(moved, 200u) << "too few lattice points inside a collider to test the decoding";
  const Diff d = compare(gpu, cpu, 1e-5f);
  EXPECT_EQ(d.over, 0u) << "max error " << d.max << " m";
  std::printf("[ metric ] decode %s: %zu of 4096 lattice points projected, max GPU−CPU difference %.3g m\n",
              formatLabel(GetParam()), moved, d.max);
}

INSTANTIATE_TEST_SUITE_P(Formats, GpuDecodeTest,
                         ::testing::Values(fluid::DepthMapFormat::float32, fluid::DepthMapFormat::fixed8,
                                           fluid::DepthMapFormat::front_back16, fluid::DepthMapFormat::cube8),
                         formatTestName);

namespace {

// Deepest penetration over live particles, by the CPU query of the same depth maps.
float deepest(const std::vector<glm::vec4>& gpu, std::size_t n, const std::vector<TestCollider*>& colliders) {
  float worst = 0.0f;
  for (std::size_t k = 0; k < n; ++k) {
    if (gpu[k].w == 0.0f) continue;
    for (const TestCollider* c : colliders) {
      const fluid::ColliderSample s = c->sampleWorld(glm::vec3(gpu[k]));
      if (s.valid) worst = std::min(worst, s.distance);
    }
  }
  return worst;
}

struct RainResult {
  float worst = 0.0f;  // deepest signed distance seen after any step (<= 0)
  Diff diff;
  std::size_t hits = 0;
};

void rainOnColliders(GpuParticles& system, Integrator integrator, fluid::DepthMapFormat format, int push_out_iterations,
                     RainResult& out) {
  TestCollider ground = makeGroundCollider(64);
  TestCollider sphere = makeSphereCollider({0.0f, 0.6f, 0.0f}, 0.35f, 64, format);
  // A moving collider: the sphere slides along x (its velocity enters the reaction).
  sphere.pose.linear_velocity = {0.3f, 0.0f, 0.0f};
  CpuStepDesc cpu_desc;
  cpu_desc.integrator = integrator;
  cpu_desc.params.gravity = {0.0f, -9.81f, 0.0f};
  cpu_desc.params.material = {0.2f, 0.4f, 0.05f};
  cpu_desc.params.push_out_iterations = push_out_iterations;
  cpu_desc.colliders = {&ground, &sphere};
  ASSERT_NO_FATAL_FAILURE(uploadColliders(system, cpu_desc.colliders));
  const BirthBatch births = randomBirths(4096, {-0.5f, 0.3f, -0.5f}, {0.5f, 1.6f, 0.5f}, 0.5f, 10.0f, 3);
  ASSERT_EQ(spawn(system, births), births.size());
  CpuParticles cpu;
  cpuSpawn(cpu, births, 0.0f, cpu_desc);
  std::vector<glm::vec4> gpu;
  for (int s = 0; s < 45; ++s) {
    step(system, cpu_desc.params);
    cpuStep(cpu, system.time, cpu_desc);
    readPositions(system, gpu);
    out.worst = std::min(out.worst, deepest(gpu, births.size(), cpu_desc.colliders));
  }
  for (std::size_t k = 0; k < births.size(); ++k) {
    const glm::vec3 p(gpu[k]);
    out.hits += p.y < 0.01f || glm::length(p - glm::vec3(0.0f, 0.6f, 0.0f)) < 0.37f;
  }
  out.diff = compare(gpu, cpu, 1e-4f);
}

}  // namespace

// Rain on a ground plane (float32 map) and a sliding sphere baked in each format: the GPU
// matches the CPU reference (fluid::collideParticles on the same maps) and, with the default
// extra push-out, no particle ends a step inside a collider. Without it (exactly the single
// §3.3.2 projection) particles can stay inside by less than a texel, because a push along one
// texel's normal can land over a neighbouring texel whose surface is higher.
class GpuCollisionTest : public GpuParticlesTest,
                         public ::testing::WithParamInterface<std::tuple<Integrator, fluid::DepthMapFormat, int>> {};

TEST_P(GpuCollisionTest, MatchesCpuAndNoParticleEndsInside) {
  const auto [integrator, format, iterations] = GetParam();
  ASSERT_NO_FATAL_FAILURE(create(64, 64, integrator));
  RainResult r;
  ASSERT_NO_FATAL_FAILURE(rainOnColliders(system_, integrator, format, iterations, r));
  const float texel = 2.0f * 1.2f * 0.35f / 64.0f * 1.1f;  // a sphere map texel (padded bounds), m
  if (iterations >= GpuStepParams{}.push_out_iterations) {
    EXPECT_GE(r.worst, 0.0f) << "a particle ended " << -r.worst << " m inside a collider";
  } else {
    EXPECT_GT(r.worst, -texel) << "a particle ended " << -r.worst << " m inside a collider";
  }
  EXPECT_GT(r.hits, 1000u) << "too few particles reached a collider";
  EXPECT_EQ(r.diff.over, 0u) << "max error " << r.diff.max << " m";
  std::printf(
      "[ metric ] %s, sphere %s, push-out iterations %d: deepest %.3g m inside after any step, %zu of 4096 "
      "differ from the CPU by more than 1e-4 m (max %.3g m), %zu on colliders\n",
      integrator == Integrator::euler ? "euler" : "verlet", formatLabel(format), iterations,
      r.worst < 0.0f ? -r.worst : 0.0f, r.diff.over, r.diff.max, r.hits);
}

INSTANTIATE_TEST_SUITE_P(
    Integrators, GpuCollisionTest,
    ::testing::Combine(::testing::Values(Integrator::euler, Integrator::verlet),
                       ::testing::Values(fluid::DepthMapFormat::float32, fluid::DepthMapFormat::fixed8,
                                         fluid::DepthMapFormat::front_back16, fluid::DepthMapFormat::cube8),
                       ::testing::Values(0, GpuStepParams{}.push_out_iterations)));

// §3.3.1: the GPU flags dead particles by age, the CPU frees their indices on its own; the two
// agree, and new births take the smallest free indices (never a live one).
TEST_F(GpuParticlesTest, BirthAndDeathAgreeBetweenCpuAndGpu) {
  ASSERT_NO_FATAL_FAILURE(create(32, 32, Integrator::euler));
  GpuStepParams params;
  params.gravity = glm::vec3(0.0f);
  BirthBatch b;
  for (int k = 0; k < 600; ++k) b.push({0.01f * k, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, k % 3 == 0 ? 0.1f : 5.0f, 0, 0.0f);
  ASSERT_EQ(spawn(system_, b), 600u);
  EXPECT_EQ(system_.allocator.active_range, 600u);
  for (int s = 0; s < 12; ++s) step(system_, params);  // 0.2 s: every third particle died
  std::vector<glm::vec4> gpu;
  readPositions(system_, gpu);
  for (std::uint32_t k = 0; k < 600; ++k) {
    EXPECT_EQ(gpu[k].w != 0.0f, system_.allocator.live[k] != 0) << "index " << k;
    EXPECT_EQ(system_.allocator.live[k] != 0, k % 3 != 0) << "index " << k;
  }
  EXPECT_EQ(system_.allocator.live_count, 400u);
  // 300 new ones: the first 200 fill the freed slots 0, 3, 6, …; the rest extend the range.
  BirthBatch more;
  for (int k = 0; k < 300; ++k) more.push({0.0f, 5.0f, 0.0f}, glm::vec3(0.0f), 5.0f, 0, 0.0f);
  ASSERT_EQ(spawn(system_, more), 300u);
  EXPECT_EQ(system_.allocator.active_range, 700u);
  step(system_, params);
  readPositions(system_, gpu);
  for (std::uint32_t k = 0; k < 700; ++k) {
    ASSERT_NE(gpu[k].w, 0.0f) << "index " << k;
    const bool reborn = k % 3 == 0 || k >= 600;
    EXPECT_EQ(gpu[k].y == 5.0f, reborn) << "index " << k;  // a live particle was not overwritten
  }
  // Bad births (NaN, non-positive lifetime) are dropped, never uploaded.
  BirthBatch bad;
  bad.push({NAN, 0.0f, 0.0f}, glm::vec3(0.0f), 1.0f, 0, 0.0f);
  bad.push(glm::vec3(0.0f), glm::vec3(0.0f), -1.0f, 0, 0.0f);
  EXPECT_EQ(spawn(system_, bad), 0u);
  // More births than free slots: the rest are dropped, nothing live is handed out again.
  BirthBatch flood;
  for (int k = 0; k < 2000; ++k) flood.push(glm::vec3(1.0f), glm::vec3(0.0f), 5.0f, 0, 0.0f);
  EXPECT_EQ(spawn(system_, flood), 1024u - 700u);
  EXPECT_EQ(system_.allocator.live_count, 1024u);
}

namespace {

std::uint64_t inversions(std::vector<float> keys) {
  // Merge sort count, O(n log n).
  std::vector<float> tmp(keys.size());
  std::uint64_t count = 0;
  for (std::size_t width = 1; width < keys.size(); width *= 2) {
    for (std::size_t lo = 0; lo < keys.size(); lo += 2 * width) {
      const std::size_t mid = std::min(lo + width, keys.size()), hi = std::min(lo + 2 * width, keys.size());
      std::size_t i = lo, j = mid, o = lo;
      while (i < mid && j < hi) {
        if (keys[j] < keys[i]) {
          count += mid - i;
          tmp[o++] = keys[j++];
        } else {
          tmp[o++] = keys[i++];
        }
      }
      while (i < mid) tmp[o++] = keys[i++];
      while (j < hi) tmp[o++] = keys[j++];
    }
    keys.swap(tmp);
  }
  return count;
}

}  // namespace

// §3.3.3: the odd-even merge sort spread over frames converges in ceil(passes / per-frame)
// frames, the inversion count never grows from one pass to the next, and the result is a
// permutation of the particle indices sorted back-to-front.
TEST_F(GpuParticlesTest, OddEvenMergeSortConvergesAndSortednessNeverDecreases) {
  ASSERT_NO_FATAL_FAILURE(create(64, 64, Integrator::euler));
  const std::uint32_t n = 64 * 64;
  const std::uint32_t total = sortPassCount(n);
  ASSERT_EQ(total, 78u);
  const BirthBatch births = randomBirths(3500, {-1, -1, -1}, {1, 1, 1}, 0.0f, 100.0f, 9);  // 596 slots stay dead
  ASSERT_EQ(spawn(system_, births), births.size());
  const glm::vec3 eye(0.2f, 0.5f, 4.0f);
  const std::uint32_t per_frame = 5;
  const std::uint32_t frames = (total + per_frame - 1) / per_frame;
  std::vector<glm::vec2> pairs;
  std::vector<float> keys(n);
  std::uint64_t previous = UINT64_MAX;
  std::uint32_t passes_run = 0;
  for (std::uint32_t f = 0; f < frames; ++f) {
    for (std::uint32_t p = 0; p < per_frame && passes_run < total; ++p, ++passes_run) {
      sortStep(system_, eye, 1);  // key refresh (no-op for static particles) + one pass
      readSortPairs(system_, pairs);
      for (std::uint32_t k = 0; k < n; ++k) keys[k] = pairs[k].x;
      const std::uint64_t inv = inversions(keys);
      ASSERT_LE(inv, previous) << "sortedness decreased at pass " << passes_run;
      previous = inv;
    }
  }
  EXPECT_EQ(previous, 0u) << "not sorted after " << frames << " frames of " << per_frame << " passes";
  std::vector<int> seen(n, 0);
  for (std::uint32_t k = 0; k < n; ++k) ++seen[static_cast<std::size_t>(pairs[k].y)];
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; })) << "not a permutation";
  // Back-to-front: the first slot holds the farthest live particle; dead ones are last.
  float far = 0.0f;
  for (const glm::vec3& p : births.positions) far = std::max(far, glm::length(p - eye));
  EXPECT_FLOAT_EQ(-pairs[0].x, far);
  for (std::uint32_t k = 3500; k < n; ++k) EXPECT_GE(pairs[k].y, 3500.0f);
  // The network restarts: a full second round on sorted keys keeps them sorted.
  sortStep(system_, eye, total);
  readSortPairs(system_, pairs);
  for (std::uint32_t k = 0; k < n; ++k) keys[k] = pairs[k].x;
  EXPECT_EQ(inversions(keys), 0u);
}

// §3.3.4: point sprites fetched in the vertex shader cover the pixels of the particles and
// nothing else; dead particles are not drawn.
TEST_F(GpuParticlesTest, SpritesCoverTheirPixelsOnly) {
  GpuParticlesDesc d;
  d.width = d.height = 16;
  d.shader_dir = kShaders;
  ParticleTypeDesc type;
  for (ParticleKeyframe& k : type.keys) k = {{1.0f, 0.5f, 0.25f, 1.0f}, 0.2f};
  d.types = {type};
  createGpuParticles(d, system_);
  ASSERT_TRUE(system_.ready) << system_.error;
  BirthBatch b;
  b.push({-0.5f, 0.0f, 0.0f}, glm::vec3(0.0f), 10.0f, 0, 0.0f);  // left half
  b.push({0.5f, 0.0f, 0.0f}, glm::vec3(0.0f), 0.01f, 0, 0.0f);   // right half, dies at once
  ASSERT_EQ(spawn(system_, b), 2u);
  GpuStepParams params;
  params.gravity = glm::vec3(0.0f);
  step(system_, params);
  const glm::mat4 proj = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 10.0f);
  const glm::mat4 view = glm::lookAt(glm::vec3(0.0f, 0.0f, 2.0f), glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  sortStep(system_, glm::vec3(0.0f, 0.0f, 2.0f), sortPassCount(system_.capacity));
  GLuint tex = 0, fbo = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, 64, 64, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
  glViewport(0, 0, 64, 64);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  drawSprites(system_, proj * view, proj[1][1], 64);
  std::vector<std::uint8_t> px(64 * 64 * 4);
  glReadPixels(0, 0, 64, 64, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &tex);
  // The live particle projects to x = 32 − 0.5/(2·tan30°)·32 ≈ 18 px; sprite ≈ 5.5 px wide.
  int left = 0, right = 0, red_max = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const std::uint8_t a = px[(static_cast<std::size_t>(y) * 64 + static_cast<std::size_t>(x)) * 4 + 3];
      if (a == 0) continue;
      (x < 32 ? left : right)++;
      red_max = std::max<int>(red_max, px[(static_cast<std::size_t>(y) * 64 + static_cast<std::size_t>(x)) * 4]);
      EXPECT_NEAR(x, 18, 4);
      EXPECT_NEAR(y, 32, 4);
    }
  }
  EXPECT_GT(left, 4);
  EXPECT_EQ(right, 0) << "a dead particle was drawn";
  EXPECT_GT(red_max, 128);
}

// Hard case: a shader that fails to compile. The error names the file and line, the system is
// not ready, and every call on it is a harmless no-op (the game runs on without the effect).
TEST_F(GpuParticlesTest, ShaderCompileFailureIsReportedAndTheSystemIsInert) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "gpu_broken_shaders";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "gpu_particles");
  for (const auto& entry : std::filesystem::directory_iterator(kShaders / "gpu_particles")) {
    std::filesystem::copy_file(entry.path(), dir / "gpu_particles" / entry.path().filename());
  }
  {
    std::ofstream out(dir / "gpu_particles" / "sort_pass.frag", std::ios::app);
    out << "\nthis is not glsl;\n";
  }
  GpuParticlesDesc d;
  d.width = d.height = 16;
  d.shader_dir = dir;
  createGpuParticles(d, system_);
  EXPECT_FALSE(system_.ready);
  EXPECT_NE(system_.error.find("sort_pass.frag:"), std::string::npos) << system_.error;
  BirthBatch b;
  b.push(glm::vec3(0.0f), glm::vec3(0.0f), 1.0f, 0, 0.0f);
  EXPECT_EQ(spawn(system_, b), 0u);
  step(system_, GpuStepParams{});
  sortStep(system_, glm::vec3(0.0f), 3);
  drawSprites(system_, glm::mat4(1.0f), 1.0f, 16);
  std::vector<glm::vec4> out;
  readPositions(system_, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  // Missing folder: a clear error too.
  d.shader_dir = dir / "nowhere";
  createGpuParticles(d, system_);
  EXPECT_FALSE(system_.ready);
  EXPECT_NE(system_.error.find("cannot open shader file"), std::string::npos) << system_.error;
  std::filesystem::remove_all(dir);
}

// Bad collider content: a clear error naming the map, and the previous colliders are kept.
TEST_F(GpuParticlesTest, BadColliderInputIsRejectedWithAClearError) {
  ASSERT_NO_FATAL_FAILURE(create(16, 16, Integrator::euler));
  TestCollider ground = makeGroundCollider(16);
  GpuColliderDesc desc = ground.gpu();
  std::vector<GpuDepthMapView> views = ground.views;
  views[0].texels = views[0].texels.first(100);
  desc.maps = views;
  std::string error;
  EXPECT_FALSE(setColliders(system_, std::span<const GpuColliderDesc>(&desc, 1), error));
  EXPECT_NE(error.find("collider 0 map 0: texels has 100 bytes"), std::string::npos) << error;
  TestCollider sphere = makeSphereCollider(glm::vec3(0.0f), 1.0f, 16, fluid::DepthMapFormat::fixed8);
  GpuColliderDesc no_table = sphere.gpu();
  no_table.normal_table = {};
  EXPECT_FALSE(setColliders(system_, std::span<const GpuColliderDesc>(&no_table, 1), error));
  EXPECT_NE(error.find("normal_table has 0 floats"), std::string::npos) << error;
  EXPECT_EQ(system_.collider_count, 0);
  std::vector<GpuColliderDesc> too_many(engine::kMaxGpuColliders + 1, ground.gpu());
  EXPECT_FALSE(setColliders(system_, too_many, error));
  EXPECT_NE(error.find("at most " + std::to_string(engine::kMaxGpuColliders) + " colliders"), std::string::npos)
      << error;
  FlowFieldDesc flow;
  flow.size = {2, 2, 2};
  std::vector<glm::vec3> v(7, glm::vec3(0.0f));
  flow.velocities = v;
  EXPECT_FALSE(setFlowField(system_, flow, error));
  EXPECT_NE(error.find("does not match 7 velocities"), std::string::npos) << error;
}

// Hard cases: zero particles (every pass is a no-op that leaves GL error-free), then a particle
// count that changes every frame (random births, random lifetimes): each frame the GPU's live
// flags equal the CPU allocator's, and the active range never exceeds what is live + packed.
TEST_F(GpuParticlesTest, ZeroParticlesAndACountThatChangesEveryFrame) {
  ASSERT_NO_FATAL_FAILURE(create(32, 32, Integrator::euler));
  GpuStepParams params;
  step(system_, params);
  sortStep(system_, glm::vec3(0.0f), 4);
  drawSprites(system_, glm::mat4(1.0f), 1.0f, 64);
  EXPECT_EQ(spawn(system_, BirthBatch{}), 0u);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  std::vector<glm::vec4> gpu;
  readPositions(system_, gpu);
  for (const glm::vec4& p : gpu) ASSERT_EQ(p.w, 0.0f);
  std::mt19937 rng(5);
  std::size_t max_live = 0;
  for (int frame = 0; frame < 60; ++frame) {
    BirthBatch b;
    const int births = static_cast<int>(rng() % 60);
    for (int k = 0; k < births; ++k) {
      b.push({0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, 0.02f + 0.3f * static_cast<float>(rng() % 100) / 100.0f, 0, 0.0f);
    }
    spawn(system_, b);
    step(system_, params);
    sortStep(system_, glm::vec3(0.0f, 0.0f, 3.0f), 2);
    readPositions(system_, gpu);
    std::uint32_t live = 0;
    for (std::uint32_t k = 0; k < system_.capacity; ++k) {
      const bool cpu_live = system_.allocator.live[k] != 0;
      ASSERT_EQ(gpu[k].w != 0.0f && k < system_.allocator.active_range, cpu_live)
          << "frame " << frame << " index " << k;
      live += cpu_live;
    }
    ASSERT_EQ(live, system_.allocator.live_count);
    max_live = std::max<std::size_t>(max_live, live);
  }
  EXPECT_GT(max_live, 100u);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

namespace {

// Sprites at rest on a line through the blast, no gravity: the velocity after one step is the
// blast's dv from the shared CPU model (fluid/core/blast.hpp).
GpuStepParams blastStep(glm::vec3 centre) {
  GpuStepParams p;
  p.gravity = glm::vec3(0.0f);
  p.particle_radius = 0.01f;
  p.particle_mass = 1e-3f;
  p.blast_count = 1;
  p.blasts[0].centre = centre;
  p.blasts[0].impulse_at_1m = 2.0f;
  p.blasts[0].core_radius = 0.1f;
  p.blasts[0].reach = 3.0f;
  p.blast_max_speed_change = 40.0f;
  return p;
}

BirthBatch restingLine(int n) {
  BirthBatch b;
  for (int k = 0; k < n; ++k) b.push({-3.2f + 0.1f * static_cast<float>(k), 0.5f, 0.2f}, glm::vec3(0.0f), 10.0f, 0, 1.0f);
  return b;
}

}  // namespace

// A sprite takes each blast's push once; one born in the blast's own step takes none.
TEST_F(GpuParticlesTest, BlastGivesEachSpriteTheSharedModelsVelocityChangeOnce) {
  for (const Integrator integrator : {Integrator::euler, Integrator::verlet}) {
    destroyGpuParticles(system_);
    ASSERT_NO_FATAL_FAILURE(create(16, 16, integrator));
    const BirthBatch births = restingLine(64);
    ASSERT_EQ(spawn(system_, births), 64u);
    const GpuStepParams with_blast = blastStep({0.0f, 0.5f, 0.2f});
    GpuStepParams calm = with_blast;
    calm.blast_count = 0;
    step(system_, calm);  // born before the blast's step: it takes the push
    // A second line born in the blast's own step (as a blast's fire and smoke are) does not.
    BirthBatch late = restingLine(64);
    for (glm::vec3& x : late.positions) x.z += 0.05f;
    ASSERT_EQ(spawn(system_, late), 64u);
    step(system_, with_blast);
    step(system_, calm);  // the push is given once, then the sprite coasts
    std::vector<glm::vec4> positions, state1;
    readPositions(system_, positions);
    readState1(system_, state1);
    const float area_over_mass = 3.14159265f * 0.01f * 0.01f / 1e-3f;
    float max_error = 0.0f, fastest = 0.0f;
    for (std::size_t k = 0; k < 64; ++k) {
      const glm::vec3 expected =
          fluid::blastVelocityChange(with_blast.blasts[0], births.positions[k], area_over_mass, 40.0f);
      const glm::vec3 velocity = integrator == Integrator::euler
                                     ? glm::vec3(state1[k])
                                     : (glm::vec3(positions[k]) - glm::vec3(state1[k])) / system_.desc.dt;
      max_error = std::max(max_error, glm::length(velocity - expected));
      fastest = std::max(fastest, glm::length(expected));
    }
    EXPECT_GT(fastest, 10.0f);  // the line crosses the core: the test sees a real push
    EXPECT_LT(max_error, 1e-3f * fastest) << (integrator == Integrator::euler ? "euler" : "verlet");
    float late_fastest = 0.0f;
    for (std::size_t k = 64; k < 128; ++k) {
      const glm::vec3 velocity = integrator == Integrator::euler
                                     ? glm::vec3(state1[k])
                                     : (glm::vec3(positions[k]) - glm::vec3(state1[k])) / system_.desc.dt;
      late_fastest = std::max(late_fastest, glm::length(velocity));
    }
    EXPECT_LT(late_fastest, 1e-4f) << "a sprite born in the blast's step took its push";
  }
}

TEST_F(GpuParticlesTest, AnInvalidBlastIsSkippedAndMovesNothing) {
  ASSERT_NO_FATAL_FAILURE(create(16, 16, Integrator::euler));
  ASSERT_EQ(spawn(system_, restingLine(64)), 64u);
  GpuStepParams params = blastStep({0.0f, 0.5f, 0.2f});
  params.blasts[0].reach = std::numeric_limits<float>::quiet_NaN();
  step(system_, params);
  std::vector<glm::vec4> state1;
  readState1(system_, state1);
  for (std::size_t k = 0; k < 64; ++k) EXPECT_EQ(glm::vec3(state1[k]), glm::vec3(0.0f)) << k;
}

// Per-type motion (ParticleTypeDesc::gravity_scale, damping): a type that rises against gravity
// and is held back by the air, like smoke, beside one that falls freely. Euler steps of dt:
// v_{n+1} = v_n + dt (s g - c v_n), so v_n = v_inf (1 - (1 - c dt)^n) with v_inf = s g / c.
TEST_F(GpuParticlesTest, EachTypeFallsOrRisesWithItsOwnGravityScaleAndDamping) {
  GpuParticlesDesc d;
  d.width = 16;
  d.height = 16;
  d.integrator = Integrator::euler;
  d.shader_dir = kShaders;
  d.types.resize(2);
  d.types[1].gravity_scale = -0.2f;
  d.types[1].damping = 1.5f;
  createGpuParticles(d, system_);
  ASSERT_TRUE(system_.ready) << system_.error;
  BirthBatch births;
  births.push({0.0f, 1.0f, 0.0f}, glm::vec3(0.0f), 10.0f, 0, 0.0f);
  births.push({1.0f, 1.0f, 0.0f}, glm::vec3(0.0f), 10.0f, 1, 0.0f);
  ASSERT_EQ(spawn(system_, births), 2u);
  GpuStepParams params;
  params.gravity = {0.0f, -9.81f, 0.0f};
  const int steps = 120;
  for (int n = 0; n < steps; ++n) step(system_, params);
  std::vector<glm::vec4> velocity;
  readState1(system_, velocity);
  const float dt = system_.desc.dt;
  const double falling = -9.81 * dt * steps;
  const double v_inf = 0.2 * 9.81 / 1.5;
  const double rising = v_inf * (1.0 - std::pow(1.0 - 1.5 * dt, steps));
  EXPECT_NEAR(velocity[0].y, falling, 1e-3 * std::abs(falling));
  EXPECT_NEAR(velocity[1].y, rising, 1e-3 * rising);
  EXPECT_GT(velocity[1].y, 0.0f) << "the smoke-like type rises";
  destroyGpuParticles(system_);
  d.types[1].damping = -1.0f;
  createGpuParticles(d, system_);
  EXPECT_FALSE(system_.ready);
  EXPECT_NE(system_.error.find("type 1"), std::string::npos) << system_.error;
}
