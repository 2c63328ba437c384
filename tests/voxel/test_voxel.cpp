// The voxel renderer (engine/fluid_render/voxel.hpp, Zirr & Dachsbacher 2015) on llvmpipe,
// headless: its tile bit grids and compressed spans equal the CPU reference
// (fluid/surface/voxel_reference.hpp) bit for bit, with particles across tile borders, word
// (32-layer slice) borders and the near plane; a ball of particles draws within 2 px of its
// analytic silhouette; a million particles draw; destroy frees every GL name.
#include "engine/fluid_render/voxel.hpp"
#include "fluid/surface/voxel_reference.hpp"
#include "tests/gpu/gl_test_context.hpp"
#include "tests/voxel/voxel_reference_checks.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cmath>
#include <random>

using namespace engine;

namespace {

const glm::vec4 kClear(0.1f, 0.1f, 0.12f, 1.0f);

std::filesystem::path shaderDir() { return std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders"; }

FluidCamera cameraAt(glm::vec3 eye, glm::vec3 target, int w, int h, float near_plane = 0.05f) {
  FluidCamera c;
  c.eye = eye;
  c.near_plane = near_plane;
  c.far_plane = 50.0f;
  c.view = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(50.0f), float(w) / float(h), c.near_plane, c.far_plane);
  return c;
}

struct Target {
  GLuint fbo = 0, texture = 0;
  Target(int w, int h) {
    texture = createTexture2D(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  ~Target() {
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &texture);
  }
};

std::vector<unsigned char> readRgba8(GLuint fbo, int w, int h) {
  std::vector<unsigned char> px(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return px;
}

class VoxelTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gputest::createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
  }
  void TearDown() override { gputest::destroyContext(ctx_); }
  gputest::GlContext ctx_;
};

// A cluster in front of the camera plus particles placed on the tile borders and across the near
// plane, and the spans of the whole screen after every tile.
TEST_F(VoxelTest, BitsAndSpansEqualTheCpuReference) {
  constexpr int kW = 48, kH = 40;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  desc.tile_width = 20;  // 3 x 3 tiles, the last ones partial
  desc.tile_height = 16;
  desc.max_spans = 3;  // small, so deep columns overflow into the hidden gap
  desc.max_layers = 256;
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const FluidCamera camera = cameraAt({0.0f, 0.3f, 2.0f}, {0.0f, 0.0f, 0.0f}, kW, kH, 0.5f);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.45f, 0.45f);
  std::vector<glm::vec3> p;
  for (int i = 0; i < 300; ++i) p.push_back({u(rng), u(rng) * 0.8f, u(rng) * 2.0f});
  // Through the near plane (0.5 m from the eye): spheres cut by it start at layer 0.
  for (int i = 0; i < 6; ++i) p.push_back({-0.15f + 0.06f * i, 0.25f, 1.55f});
  VoxelParams params;
  params.radius = 0.06f;
  params.min_gap = 0.03f;
  params.angle_degrees = 2.0f;  // many layers: spheres cross word borders
  ASSERT_TRUE(uploadVoxelParticles(r, p, r.error));
  // Particles at the centres of pixels on the tile borders (x = 19|20, y = 15|16) at mid depth.
  std::vector<fluid::VoxelTile> tiles;
  ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
  ASSERT_EQ(tiles.size(), 9u);
  const glm::mat4 inv_view = glm::inverse(camera.view);
  for (glm::ivec2 px : {glm::ivec2(19, 15), glm::ivec2(20, 16), glm::ivec2(40, 16), glm::ivec2(19, 33)}) {
    const glm::vec3 ray = fluid::voxelPixelRay(r.view, px.x, px.y);
    p.push_back(glm::vec3(inv_view * glm::vec4(ray * 2.1f, 1.0f)));
  }
  ASSERT_TRUE(uploadVoxelParticles(r, p, r.error));
  ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
  EXPECT_GT(r.layers.words, 1);
  const std::uint64_t set_bits = voxel_test::splatTilesLikeTheReference(
      r, params, tiles, [&](const fluid::VoxelTile& tile, std::vector<std::uint32_t>& bits) {
        fluid::voxelizeReference(p, params.radius, r.view, r.layers, tile, bits);
      });
  EXPECT_GT(set_bits, 1000u);
  // The CPU compression of the CPU bits of the whole screen as one tile.
  std::vector<std::uint32_t> all;
  fluid::voxelizeReference(p, params.radius, r.view, r.layers, {0, 0, kW, kH}, all);
  voxel_test::SpanCounts counts;
  voxel_test::expectSpansLikeTheReference(r, desc, params, kW, kH, all, counts);
  if (HasFatalFailure()) return;
  EXPECT_GT(counts.overflowing, 0u) << "no column overflowed its spans: the hidden gap went untested";
  EXPECT_GT(counts.near_cut, 0u) << "no sphere was cut by the near plane";
  EXPECT_GT(counts.covered, 200u);
  destroyVoxelRenderer(r);
}

// A ball of particles (a dense shell of radius Rb and a filled inside) is, as a union of spheres of
// radius r, a ball of radius about Rb + r: every pixel whose water mask disagrees with that ball's
// analytic silhouette is within 2 px of the silhouette's edge.
TEST_F(VoxelTest, BallOfParticlesDrawsWithinTwoPixelsOfItsSilhouette) {
  constexpr int kW = 96, kH = 80;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const glm::vec3 centre(0.1f, 0.05f, -0.2f);
  const float ball = 0.3f, radius = 0.05f;
  std::vector<glm::vec3> p;
  const int shell = 3000;  // Fibonacci sphere: spacing about 0.02 m, well under the radius
  for (int i = 0; i < shell; ++i) {
    const float z = 1.0f - 2.0f * (i + 0.5f) / shell, rho = std::sqrt(1.0f - z * z);
    const float phi = 2.39996323f * static_cast<float>(i);
    p.push_back(centre + ball * glm::vec3(rho * std::cos(phi), rho * std::sin(phi), z));
  }
  for (float x = -ball; x <= ball; x += 0.06f)
    for (float y = -ball; y <= ball; y += 0.06f)
      for (float z = -ball; z <= ball; z += 0.06f)
        if (x * x + y * y + z * z < (ball - 0.05f) * (ball - 0.05f)) p.push_back(centre + glm::vec3(x, y, z));
  const FluidCamera camera = cameraAt({0.6f, 0.5f, 1.6f}, centre, kW, kH);
  ASSERT_TRUE(uploadVoxelParticles(r, p, r.error));
  beginVoxelOpaquePass(r, kClear);
  Target target(kW, kH);
  VoxelParams params;
  params.radius = radius;
  WaterParams water;
  drawVoxelFluid(r, target.fbo, camera, water, params);
  const std::vector<unsigned char> image = readRgba8(target.fbo, kW, kH);
  // Analytic: the pixel ray's distance to the centre against Rb + r.
  const glm::vec3 c = glm::vec3(camera.view * glm::vec4(centre, 1.0f));
  const float R = ball + radius;
  auto inside = [&](float x, float y) {
    const glm::vec3 d = glm::normalize(glm::vec3((x / kW * 2.0f - 1.0f) / camera.projection[0][0],
                                                 (y / kH * 2.0f - 1.0f) / camera.projection[1][1], -1.0f));
    const float along = glm::dot(c, d);
    return glm::dot(c, c) - along * along < R * R;
  };
  int wrong = 0, far_wrong = 0, water_pixels = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const unsigned char* px = &image[(static_cast<std::size_t>(y) * kW + x) * 4];
      const bool is_water = std::abs(px[0] - int(std::lround(kClear.r * 255))) > 2 ||
                            std::abs(px[1] - int(std::lround(kClear.g * 255))) > 2 ||
                            std::abs(px[2] - int(std::lround(kClear.b * 255))) > 2;
      water_pixels += is_water;
      const bool expected = inside(x + 0.5f, y + 0.5f);
      if (is_water == expected) continue;
      ++wrong;
      // Within 2 px of the edge: some point within 2 px has the other answer.
      bool near_edge = false;
      for (int dy = -2; dy <= 2 && !near_edge; ++dy)
        for (int dx = -2; dx <= 2 && !near_edge; ++dx) near_edge = inside(x + 0.5f + dx, y + 0.5f + dy) != expected;
      far_wrong += !near_edge;
    }
  }
  EXPECT_GT(water_pixels, 500);
  EXPECT_EQ(far_wrong, 0) << wrong << " pixels differ from the analytic silhouette";
  EXPECT_LT(wrong, water_pixels / 10);
  destroyVoxelRenderer(r);
}

// A pool of a million particles (100 x 100 x 100 lattice) draws headless, in tiles, in bounded time.
TEST_F(VoxelTest, MillionParticlesDrawHeadless) {
  constexpr int kW = 160, kH = 120;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  desc.tile_budget_bytes = std::size_t{1} << 18;  // several tiles
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  std::vector<glm::vec3> p;
  p.reserve(1000000);
  const float spacing = 0.04f;
  for (int z = 0; z < 100; ++z)
    for (int y = 0; y < 100; ++y)
      for (int x = 0; x < 100; ++x) p.push_back({(x - 50) * spacing, (y - 100) * spacing * 0.2f, (z - 50) * spacing});
  const FluidCamera camera = cameraAt({0.0f, 2.5f, 4.5f}, {0.0f, -0.4f, 0.0f}, kW, kH);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(uploadVoxelParticles(r, p, r.error));
  beginVoxelOpaquePass(r, kClear);
  Target target(kW, kH);
  VoxelParams params;
  params.radius = 0.03f;
  params.min_gap = 0.04f;
  params.time_stages = true;
  drawVoxelFluid(r, target.fbo, camera, WaterParams{}, params);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<unsigned char> image = readRgba8(target.fbo, kW, kH);
  int water = 0;
  for (std::size_t i = 0; i < image.size(); i += 4)
    water += std::abs(image[i + 2] - int(std::lround(kClear.b * 255))) > 2;
  EXPECT_GT(r.stats.tiles, 1);
  EXPECT_GT(water, kW * kH / 8);
  EXPECT_GT(r.stats.stored_spans, 0u);
  std::printf("1M particles at %dx%d: %.2f s, %d tiles of %dx%d, %d layers; splat %.1f ms, compress %.1f ms\n", kW, kH,
              seconds, r.stats.tiles, r.stats.tile_width, r.stats.tile_height, r.stats.layers, r.stats.splat_ms,
              r.stats.compress_ms);
  EXPECT_LT(seconds, 60.0);
  destroyVoxelRenderer(r);
}

TEST_F(VoxelTest, DestroyFreesEveryGlName) {
  VoxelDesc desc;
  desc.base = {32, 24, shaderDir()};
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const std::vector<glm::vec3> p = {{0.0f, 0.0f, 0.0f}};
  ASSERT_TRUE(uploadVoxelParticles(r, p, r.error));
  Target target(32, 24);
  drawVoxelFluid(r, target.fbo, cameraAt({0, 0, 1}, {0, 0, 0}, 32, 24), WaterParams{}, VoxelParams{});
  const GlObjectNames names = glNames(r);
  EXPECT_GT(names.size(), 10u);
  destroyVoxelRenderer(r);
  EXPECT_EQ(countLiveGlObjects(names), 0u);
  EXPECT_FALSE(r.ready);
}

TEST_F(VoxelTest, BadInputIsRefusedWithAMessage) {
  VoxelDesc desc;
  desc.base = {32, 24, shaderDir()};
  desc.max_spans = 9;
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  EXPECT_FALSE(r.ready);
  EXPECT_NE(r.error.find("max_spans 9"), std::string::npos) << r.error;
  desc.max_spans = 4;
  desc.base.shader_dir = "/nonexistent";
  createVoxelRenderer(desc, r);
  EXPECT_FALSE(r.ready);
  EXPECT_NE(r.error.find("voxel_"), std::string::npos) << r.error;
  desc.base.shader_dir = shaderDir();
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const std::vector<glm::vec3> bad = {{0.0f, 0.0f, 0.0f}, {NAN, 0.0f, 0.0f}};
  std::string error;
  EXPECT_FALSE(uploadVoxelParticles(r, bad, error));
  EXPECT_NE(error.find("position 1"), std::string::npos) << error;
  destroyVoxelRenderer(r);
}

// NVIDIA's compiler reads a vertex or fragment shader that enables GL_ARB_compute_shader as a
// compute shader and refuses its outputs (the shade program failed to build on an H200 while
// llvmpipe took it), so only programs with a compute stage may get that line.
TEST(VoxelShaderPrelude, OnlyComputeProgramsEnableTheComputeExtension) {
  const std::string compute_line = "#extension GL_ARB_compute_shader";
  const std::vector<ShaderStageFiles> compute = {{GL_COMPUTE_SHADER, {"voxel_splat.comp"}}};
  const std::vector<ShaderStageFiles> shade = {{GL_VERTEX_SHADER, {"blit.vert"}},
                                               {GL_FRAGMENT_SHADER, {"voxel_shade.frag"}}};
  EXPECT_NE(voxelShaderPrelude(compute).find(compute_line), std::string::npos);
  const std::string shade_prelude = voxelShaderPrelude(shade);
  EXPECT_EQ(shade_prelude.find(compute_line), std::string::npos) << shade_prelude;
  EXPECT_NE(shade_prelude.find("GL_ARB_shader_storage_buffer_object"), std::string::npos) << shade_prelude;
}

}  // namespace
