// Diffuse sprites on a headless GL context (llvmpipe in CI): the update pass classes each sprite by
// the fluid grid's neighbour estimate (Ihmsen et al. 2012 §4.2) and moves it as its class does:
// foam with the water (eq. 7), bubbles up by buoyancy and drag (eq. 8), spray ballistic. The grid
// upload is recorded and runs in order with the steps.
#include "engine/gpu_particles/gpu_particles.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace engine;
using namespace gputest;

namespace {

const std::filesystem::path kShaders = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
constexpr float kDt = 1.0f / 60.0f;

class GpuDiffuseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
    GpuParticlesDesc d;
    d.width = 4;
    d.height = 4;
    d.shader_dir = kShaders;
    d.dt = kDt;
    d.types.resize(3);
    for (ParticleTypeDesc& t : d.types) t.diffuse = true;
    d.class_types = {0, 1, 2};
    createGpuParticles(d, system_);
    ASSERT_TRUE(system_.ready) << system_.error;
  }
  void TearDown() override {
    destroyGpuParticles(system_);
    destroyContext(ctx_);
  }
  // A 4 x 4 x 4 grid of 0.5 m cells from the origin, `count` particles per cell moving at `v`,
  // the neighbour estimate `count * scale`.
  void uploadUniformWater(float count, glm::vec3 v, float scale = 1.0f) {
    cells_.assign(64, glm::vec4(v * count, count));
    FluidGridDesc grid;
    grid.size = {4, 4, 4};
    grid.origin = glm::vec3(0.0f);
    grid.cell = 0.5f;
    grid.neighbour_scale = scale;
    grid.cells = cells_;
    std::string error;
    ASSERT_TRUE(setFluidGrid(system_, grid, error)) << error;
  }
  // Positions (xyz) and the class (state1.w) of the live sprites after `steps` steps.
  void run(int steps, std::vector<glm::vec4>& positions, std::vector<glm::vec4>& state1) {
    GpuStepParams params;
    for (int k = 0; k < steps; ++k) step(system_, params);
    readPositions(system_, positions);
    readState1(system_, state1);
  }
  GlContext ctx_;
  GpuParticles system_;
  std::vector<glm::vec4> cells_;
};

// Foam (6..20 neighbours): moves with the water, whatever its own velocity was.
TEST_F(GpuDiffuseTest, FoamMovesWithTheFlow) {
  const glm::vec3 flow(0.3f, 0.0f, -0.2f);
  uploadUniformWater(12.0f, flow);
  BirthBatch b;
  b.push(glm::vec3(1.0f), glm::vec3(0.0f, 5.0f, 0.0f), 10.0f, 1, 0.0f);
  ASSERT_EQ(spawn(system_, b), 1u);
  std::vector<glm::vec4> p, s1;
  run(30, p, s1);
  EXPECT_EQ(s1[0].w, 1.0f) << "class foam";
  const glm::vec3 expected = glm::vec3(1.0f) + 30.0f * kDt * flow;
  EXPECT_NEAR(p[0].x, expected.x, 1e-4f);
  EXPECT_NEAR(p[0].y, expected.y, 1e-4f);
  EXPECT_NEAR(p[0].z, expected.z, 1e-4f);
  EXPECT_NEAR(s1[0].x, flow.x, 1e-5f);
}

// A bubble (> 20 neighbours) in still water rises: v_{n+1} = v_n + k_b |g| dt - k_d v_n, which
// settles at k_b |g| dt (1 - k_d) / k_d upward.
TEST_F(GpuDiffuseTest, BubbleInStillWaterRises) {
  uploadUniformWater(30.0f, glm::vec3(0.0f));
  BirthBatch b;
  b.push(glm::vec3(1.0f, 0.5f, 1.0f), glm::vec3(0.0f), 10.0f, 2, 0.0f);
  ASSERT_EQ(spawn(system_, b), 1u);
  std::vector<glm::vec4> p, s1;
  run(20, p, s1);
  EXPECT_EQ(s1[0].w, 2.0f) << "class bubble";
  // The recurrence on the CPU, in float like the shader.
  const GpuStepParams params;
  float v = 0.0f, y = 0.5f;
  for (int k = 0; k < 20; ++k) {
    v = v + params.diffuse.buoyancy * 9.81f * kDt - params.diffuse.drag * v;
    y += v * kDt;
  }
  EXPECT_GT(p[0].y, 0.5f + 0.05f);
  EXPECT_NEAR(p[0].y, y, 1e-4f);
  EXPECT_NEAR(s1[0].y, v, 1e-4f);
  EXPECT_NEAR(p[0].x, 1.0f, 1e-6f);
}

// Spray: outside the water (no neighbours) it falls under gravity like any sprite.
TEST_F(GpuDiffuseTest, SprayOutsideTheWaterFalls) {
  uploadUniformWater(30.0f, glm::vec3(0.0f));
  BirthBatch b;
  b.push(glm::vec3(1.0f, 5.0f, 1.0f), glm::vec3(0.0f), 10.0f, 0, 0.0f);  // above the grid
  ASSERT_EQ(spawn(system_, b), 1u);
  std::vector<glm::vec4> p, s1;
  run(30, p, s1);
  EXPECT_EQ(s1[0].w, 0.0f) << "class spray";
  EXPECT_NEAR(s1[0].y, -9.81f * 30.0f * kDt, 1e-3f);
  EXPECT_LT(p[0].y, 5.0f - 0.4f);
}

// A bubble rising out of the water turns into foam where the count drops (the grid's top cells
// hold fewer particles), and stays there, carried by the surface.
TEST_F(GpuDiffuseTest, BubbleTurnsIntoFoamAtTheSurface) {
  cells_.assign(64, glm::vec4(0.0f));
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) cells_[(z * 4 + y) * 4 + x] = glm::vec4(0.0f, 0.0f, 0.0f, y < 2 ? 30.0f : 0.0f);
  FluidGridDesc grid;
  grid.size = {4, 4, 4};
  grid.cell = 0.5f;
  grid.cells = cells_;
  std::string error;
  ASSERT_TRUE(setFluidGrid(system_, grid, error)) << error;
  BirthBatch b;
  b.push(glm::vec3(1.0f, 0.3f, 1.0f), glm::vec3(0.0f), 10.0f, 2, 0.0f);
  ASSERT_EQ(spawn(system_, b), 1u);
  std::vector<glm::vec4> p, s1;
  run(240, p, s1);
  EXPECT_EQ(s1[0].w, 1.0f) << "a surfaced bubble is foam";
  // Foam lives where the count is 6..20: between the full row of cell centres (y = 0.75, 30) and
  // the empty one (y = 1.25, 0).
  EXPECT_GT(p[0].y, 0.75f);
  EXPECT_LT(p[0].y, 1.25f);
}

// Without a grid (or after an empty one), diffuse sprites are spray; a bad grid is refused.
TEST_F(GpuDiffuseTest, NoGridMeansSprayAndBadGridsAreRefused) {
  BirthBatch b;
  b.push(glm::vec3(1.0f), glm::vec3(0.0f), 10.0f, 1, 0.0f);
  ASSERT_EQ(spawn(system_, b), 1u);
  std::vector<glm::vec4> p, s1;
  run(10, p, s1);
  EXPECT_EQ(s1[0].w, 0.0f);
  EXPECT_LT(p[0].y, 1.0f);
  std::vector<glm::vec4> cells(8, glm::vec4(0.0f));
  FluidGridDesc grid;
  grid.size = {2, 2, 3};
  grid.cell = 0.5f;
  grid.cells = cells;
  std::string error;
  EXPECT_FALSE(setFluidGrid(system_, grid, error));
  EXPECT_NE(error.find("does not match"), std::string::npos) << error;
  grid.size = {2, 2, 2};
  cells[3].y = NAN;
  EXPECT_FALSE(setFluidGrid(system_, grid, error));
  cells[3].y = 0.0f;
  grid.cell = 0.0f;
  EXPECT_FALSE(setFluidGrid(system_, grid, error));
}

}  // namespace
