// The voxel renderer with anisotropic kernels (issue 36: Zirr & Dachsbacher 2015's splat of Yu &
// Turk 2013's ellipsoids, engine/fluid_render/voxel.hpp) on llvmpipe, headless:
//   - the tile bits and spans of particles with their kernels (fluid/sph/anisotropy.hpp) plus
//     hand-made needles across tile borders, word borders and the near plane equal the CPU reference
//     (fluid/surface/voxel_reference.hpp) bit for bit;
//   - identity kernels set exactly the sphere's bits and draw exactly the sphere's picture;
//   - one rotated ellipsoid's voxels are the layers of its analytic ray interval (in double, in
//     world space) at every pixel off the silhouette and the layer boundaries;
//   - the water backend draws the kernels a WaterInput carries (a flat ellipsoid's silhouette);
//   - bad kernels are refused.
#include "engine/fluid_render/voxel.hpp"
#include "engine/fluid_render/water_backend.hpp"
#include "fluid/sph/anisotropy.hpp"
#include "fluid/surface/voxel_reference.hpp"
#include "tests/gpu/gl_test_context.hpp"
#include "tests/voxel/voxel_reference_checks.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace engine;

namespace {

const glm::vec4 kClear(0.1f, 0.1f, 0.12f, 1.0f);

std::filesystem::path shaderDir() { return std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders"; }

FluidCamera cameraAt(glm::vec3 eye, glm::vec3 target, int w, int h, float near_plane) {
  FluidCamera c;
  c.eye = eye;
  c.near_plane = near_plane;
  c.far_plane = 50.0f;
  c.view = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(50.0f), float(w) / float(h), c.near_plane, c.far_plane);
  return c;
}

// g = sum_k (1 / axes_k) e_k e_k^T: the ellipsoid |g (x − c)| <= ρ has semi-axes ρ axes_k along a
// right-handed frame whose first axis is `along`.
glm::dmat3 kernelOf(glm::dvec3 along, glm::dvec3 axes) {
  const glm::dvec3 e0 = glm::normalize(along);
  const glm::dvec3 e1 =
      glm::normalize(glm::cross(e0, std::abs(e0.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
  const glm::dvec3 e2 = glm::cross(e0, e1);
  return (1.0 / axes.x) * glm::outerProduct(e0, e0) + (1.0 / axes.y) * glm::outerProduct(e1, e1) +
         (1.0 / axes.z) * glm::outerProduct(e2, e2);
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

bool isWater(const unsigned char* px) {
  return std::abs(px[0] - int(std::lround(kClear.r * 255))) > 2 ||
         std::abs(px[1] - int(std::lround(kClear.g * 255))) > 2 ||
         std::abs(px[2] - int(std::lround(kClear.b * 255))) > 2;
}

// The ellipsoid { x : |g (x − c)| <= rho } against the view ray through window point (fx, fy)
// (pixel centres at + 0.5), in double and world space: false when missed, else the view depths of
// entry and exit. `margin` = 1 − |q|^2 at the closest approach (0 at the silhouette).
bool analyticInterval(const FluidCamera& cam, int w, int h, double fx, double fy, glm::dvec3 c, const glm::dmat3& g,
                      double rho, double& d0, double& d1, double& margin) {
  const glm::dmat4 proj(cam.projection);
  const glm::dvec3 ray(((fx / w) * 2.0 - 1.0 + proj[2][0]) / proj[0][0],
                       ((fy / h) * 2.0 - 1.0 + proj[2][1]) / proj[1][1],
                       -1.0);  // view space, z = −1: the point at view depth d is d ray
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.view));
  const glm::dvec3 origin(inv * glm::dvec4(0, 0, 0, 1)), dir(inv * glm::dvec4(ray, 0.0));
  const glm::dvec3 a = g * dir / rho, b = g * (origin - c) / rho;
  const double aa = glm::dot(a, a), m = -glm::dot(a, b) / aa;
  const glm::dvec3 q = b + m * a;
  margin = 1.0 - glm::dot(q, q);
  if (margin <= 0.0) return false;
  const double half = std::sqrt(margin / aa);
  d0 = m - half;
  d1 = m + half;
  return true;
}

int layerOf(const std::vector<float>& depth, double d) {
  const int count = static_cast<int>(depth.size()) - 1;
  if (!(d >= depth[0])) return -1;
  if (d >= depth[static_cast<std::size_t>(count)]) return count;
  int lo = 0;
  while (lo + 1 < count && depth[static_cast<std::size_t>(lo) + 1] <= d) ++lo;
  return lo;
}

class VoxelAnisoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gputest::createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
  }
  void TearDown() override { gputest::destroyContext(ctx_); }
  gputest::GlContext ctx_;
};

// A random cluster and a tilted two-layer sheet with their kernels (k_n lowered so the sparse
// cluster's random neighbourhoods stretch too), needles across the near plane and on tile borders.
TEST_F(VoxelAnisoTest, EllipsoidBitsAndSpansEqualTheCpuReference) {
  constexpr int kW = 48, kH = 40;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  desc.tile_width = 20;  // 3 x 3 tiles, the last ones partial
  desc.tile_height = 16;
  desc.max_spans = 3;
  desc.max_layers = 256;
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const FluidCamera camera = cameraAt({0.0f, 0.3f, 2.0f}, {0.0f, 0.0f, 0.0f}, kW, kH, 0.5f);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.45f, 0.45f), jitter(-0.01f, 0.01f);
  std::vector<glm::vec3> p;
  for (int i = 0; i < 200; ++i) p.push_back({u(rng), u(rng) * 0.8f, u(rng) * 2.0f});
  const float tilt = glm::radians(40.0f);
  const glm::vec3 ey(0.0f, std::cos(tilt), std::sin(tilt)), ez(0.0f, -std::sin(tilt), std::cos(tilt));
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < 10; ++b)
      for (int layer = 0; layer < 2; ++layer)
        p.push_back(glm::vec3((a - 4.5f) * 0.08f + jitter(rng), 0.1f, 0.3f) + ((b - 4.5f) * 0.08f + jitter(rng)) * ey +
                    (layer * 0.08f + jitter(rng)) * ez);
  fluid::AnisotropyParams ap;
  ap.radius = 0.24f;
  ap.k_n = 6;
  fluid::AnisotropyScratch scratch;
  fluid::Anisotropy kernels;
  ASSERT_TRUE(fluid::computeAnisotropy(p, ap, scratch, kernels));
  EXPECT_GT(kernels.stretched, 150u);
  std::vector<glm::vec3> centres = kernels.centre;
  std::vector<glm::mat3> g = kernels.g;
  std::vector<float> axes = kernels.max_axis;
  auto needle = [&](glm::vec3 at, glm::dvec3 along) {
    centres.push_back(at);
    g.push_back(glm::mat3(kernelOf(along, {2.5, 0.7, 0.5})));
    axes.push_back(2.5f);
  };
  // Through the near plane (0.5 m from the eye): cut ellipsoids start at layer 0.
  for (int i = 0; i < 6; ++i) needle({-0.15f + 0.06f * i, 0.25f, 1.55f}, {1.0, 0.3 * i, 0.5});
  VoxelParams params;
  params.radius = 0.06f;
  params.min_gap = 0.03f;
  params.angle_degrees = 2.0f;  // many layers: ellipsoids cross word borders
  ASSERT_TRUE(uploadVoxelEllipsoids(r, centres, g, axes, r.error)) << r.error;
  std::vector<fluid::VoxelTile> tiles;
  ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
  ASSERT_EQ(tiles.size(), 9u);
  // Needles centred on pixels at the tile borders (x = 19|20, y = 15|16), lying along the border.
  const glm::mat4 inv_view = glm::inverse(camera.view);
  for (glm::ivec2 px : {glm::ivec2(19, 15), glm::ivec2(20, 16), glm::ivec2(40, 16), glm::ivec2(19, 33)}) {
    const glm::vec3 ray = fluid::voxelPixelRay(r.view, px.x, px.y);
    needle(glm::vec3(inv_view * glm::vec4(ray * 2.1f, 1.0f)), px.x % 2 ? glm::dvec3(0, 1, 0.2) : glm::dvec3(1, 0, 0.2));
  }
  ASSERT_TRUE(uploadVoxelEllipsoids(r, centres, g, axes, r.error)) << r.error;
  EXPECT_TRUE(r.stats.ellipsoids);
  ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
  EXPECT_GT(r.layers.words, 1);
  const std::uint64_t set_bits = voxel_test::splatTilesLikeTheReference(
      r, params, tiles, [&](const fluid::VoxelTile& tile, std::vector<std::uint32_t>& bits) {
        fluid::voxelizeReference(centres, g, params.radius, r.view, r.layers, tile, bits);
      });
  EXPECT_GT(set_bits, 1000u);
  std::vector<std::uint32_t> all;
  fluid::voxelizeReference(centres, g, params.radius, r.view, r.layers, {0, 0, kW, kH}, all);
  voxel_test::SpanCounts counts;
  voxel_test::expectSpansLikeTheReference(r, desc, params, kW, kH, all, counts);
  if (HasFatalFailure()) return;
  EXPECT_GT(counts.overflowing, 0u) << "no column overflowed its spans: the hidden gap went untested";
  EXPECT_GT(counts.near_cut, 0u) << "no ellipsoid was cut by the near plane";
  EXPECT_GT(counts.covered, 200u);
  destroyVoxelRenderer(r);
}

// g = I: M = I exactly (voxelKernelMatrix), so the ellipsoid splat sets the sphere splat's bits and
// every later stage sees the same grid: the same picture, byte for byte.
TEST_F(VoxelAnisoTest, IdentityKernelsDrawExactlyTheSpheres) {
  constexpr int kW = 64, kH = 48;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  desc.tile_width = 40;
  desc.tile_height = 30;
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const FluidCamera camera = cameraAt({0.2f, 0.6f, 1.8f}, {0.0f, 0.0f, 0.0f}, kW, kH, 0.3f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.4f, 0.4f);
  std::vector<glm::vec3> p;
  for (int i = 0; i < 400; ++i) p.push_back({u(rng), u(rng) * 0.5f, u(rng)});
  const std::vector<glm::mat3> identity(p.size(), glm::mat3(1.0f));
  const std::vector<float> ones(p.size(), 1.0f);
  VoxelParams params;
  params.radius = 0.05f;
  params.min_gap = 0.04f;
  auto bitsAndPicture = [&](bool ellipsoids, std::vector<std::uint32_t>& bits, std::vector<unsigned char>& image) {
    ASSERT_TRUE(ellipsoids ? uploadVoxelEllipsoids(r, p, identity, ones, r.error)
                           : uploadVoxelParticles(r, p, r.error));
    EXPECT_EQ(r.stats.ellipsoids, ellipsoids);
    std::vector<fluid::VoxelTile> tiles;
    ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
    bits.clear();
    for (const fluid::VoxelTile& tile : tiles) {
      voxelSplatTile(r, params, tile);
      std::vector<std::uint32_t> words;
      readVoxelTileBits(r, tile, words);
      bits.insert(bits.end(), words.begin(), words.end());
    }
    beginVoxelOpaquePass(r, kClear);
    Target target(kW, kH);
    drawVoxelFluid(r, target.fbo, camera, WaterParams{}, params);
    image = readRgba8(target.fbo, kW, kH);
  };
  std::vector<std::uint32_t> sphere_bits, ellipsoid_bits;
  std::vector<unsigned char> sphere_image, ellipsoid_image;
  bitsAndPicture(false, sphere_bits, sphere_image);
  bitsAndPicture(true, ellipsoid_bits, ellipsoid_image);
  std::uint64_t set = 0;
  for (std::uint32_t w : sphere_bits) set += static_cast<std::uint64_t>(__builtin_popcount(w));
  EXPECT_GT(set, 5000u);
  EXPECT_TRUE(sphere_bits == ellipsoid_bits);
  std::size_t water = 0, differ = 0;
  for (std::size_t i = 0; i < sphere_image.size(); i += 4) {
    water += isWater(&sphere_image[i]);
    for (int c = 0; c < 4; ++c) differ += sphere_image[i + c] != ellipsoid_image[i + c];
  }
  EXPECT_GT(water, 300u);
  EXPECT_EQ(differ, 0u);
  // The references agree too.
  std::vector<std::uint32_t> cpu_sphere, cpu_ellipsoid;
  fluid::voxelizeReference(p, params.radius, r.view, r.layers, {0, 0, kW, kH}, cpu_sphere);
  fluid::voxelizeReference(p, identity, params.radius, r.view, r.layers, {0, 0, kW, kH}, cpu_ellipsoid);
  EXPECT_TRUE(cpu_sphere == cpu_ellipsoid);
  const glm::mat3 m = fluid::voxelKernelMatrix(camera.view, glm::mat3(1.0f));
  EXPECT_TRUE(m == glm::mat3(1.0f));
  destroyVoxelRenderer(r);
}

// One ellipsoid (semi-axes ρ (2.2, 1, 0.45), tilted): each column's set layers are exactly
// [layer(d0), layer(d1)] of the analytic entry and exit depths, computed in double from g in world
// space (so a wrong view rotation of g, or a transposed one, fails), wherever the pixel is off the
// silhouette and d0, d1 are off the layer boundaries.
TEST_F(VoxelAnisoTest, OneEllipsoidSetsTheLayersOfItsAnalyticInterval) {
  constexpr int kW = 96, kH = 80;
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  desc.max_layers = 2048;
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const FluidCamera camera = cameraAt({0.3f, 0.4f, 1.6f}, {0.0f, 0.0f, 0.0f}, kW, kH, 0.1f);
  const glm::dvec3 c(0.1, -0.05, 0.2);
  const glm::dmat3 gd = kernelOf({1.0, 0.6, 0.5}, {2.2, 1.0, 0.45});
  const double rho = 0.16;
  const std::vector<glm::vec3> centres{glm::vec3(c)};
  const std::vector<glm::mat3> g{glm::mat3(gd)};
  const std::vector<float> axes{2.2f};
  ASSERT_TRUE(uploadVoxelEllipsoids(r, centres, g, axes, r.error)) << r.error;
  VoxelParams params;
  params.radius = static_cast<float>(rho);
  params.angle_degrees = 1.0f;
  std::vector<fluid::VoxelTile> tiles;
  ASSERT_TRUE(voxelBeginFrame(r, camera, params, tiles));
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_GE(r.layers.count, 256);
  voxelSplatTile(r, params, tiles[0]);
  std::vector<std::uint32_t> gpu, cpu;
  readVoxelTileBits(r, tiles[0], gpu);
  fluid::voxelizeReference(centres, g, params.radius, r.view, r.layers, tiles[0], cpu);
  EXPECT_TRUE(gpu == cpu);
  const std::vector<float>& depth = r.layers.depth;
  const int words = r.layers.words;
  std::size_t analytic = 0, drawn = 0, checked = 0, checked_inside = 0, wrong = 0, silhouette = 0, sphere = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const std::uint32_t* column = &gpu[(static_cast<std::size_t>(y) * kW + x) * words];
      int first = -1, last = -1, set = 0;
      for (int l = 0; l < r.layers.count; ++l) {
        if (!((column[l >> 5] >> (l & 31)) & 1u)) continue;
        if (first < 0) first = l;
        last = l;
        ++set;
      }
      drawn += set > 0;
      double d0 = 0, d1 = 0, margin = 0;
      const bool hit = analyticInterval(camera, kW, kH, x + 0.5, y + 0.5, c, gd, rho, d0, d1, margin);
      analytic += hit;
      double s0 = 0, s1 = 0, sm = 0;  // the bounding sphere of radius 2.2 ρ
      sphere += analyticInterval(camera, kW, kH, x + 0.5, y + 0.5, c, glm::dmat3(1.0), 2.2 * rho, s0, s1, sm);
      if (std::abs(margin) < 1e-3) {  // the float and double answers may differ at the silhouette
        ++silhouette;
        continue;
      }
      ++checked;
      checked_inside += hit;
      if (!hit) {
        wrong += set > 0;
        continue;
      }
      const double eps = 1e-5;  // relative: float rounding of the depths near a layer boundary
      const int first_lo = std::max(layerOf(depth, d0 * (1 - eps)), 0), first_hi = layerOf(depth, d0 * (1 + eps));
      const int last_lo = layerOf(depth, d1 * (1 - eps)),
                last_hi = std::min(layerOf(depth, d1 * (1 + eps)), r.layers.count - 1);
      const bool ok = set == last - first + 1 && first >= first_lo && first <= std::max(first_hi, 0) &&
                      last >= last_lo && last <= last_hi;
      if (!ok && wrong < 5)
        ADD_FAILURE() << "pixel " << x << "," << y << ": layers " << first << ".." << last << " (" << set
                      << " set), analytic " << layerOf(depth, d0) << ".." << layerOf(depth, d1);
      wrong += !ok;
    }
  }
  std::printf(
      "one ellipsoid: %zu pixels analytic, %zu drawn, %zu checked (%zu inside), %zu at the silhouette; its "
      "bounding sphere covers %zu\n",
      analytic, drawn, checked, checked_inside, silhouette, sphere);
  EXPECT_GT(checked_inside, 300u);
  EXPECT_EQ(wrong, 0u);
  EXPECT_LE(silhouette, analytic / 10);
  EXPECT_GT(sphere, analytic * 3 / 2);  // the footprint is the ellipsoid's, not the bound's
  destroyVoxelRenderer(r);
}

// The water backend (as the game's fluid_surface drives it) draws the kernels its input carries:
// a flat ellipsoid's silhouette within 2 px, far from the sphere of the same radius.
TEST_F(VoxelAnisoTest, WaterBackendDrawsTheKernelsOfItsInput) {
  constexpr int kW = 96, kH = 80;
  const WaterBackendDesc* voxel = findWaterBackend("voxel");
  ASSERT_NE(voxel, nullptr);
  FluidRenderDesc base;
  base.width = kW;
  base.height = kH;
  base.shader_dir = shaderDir();
  std::unique_ptr<WaterBackend> backend = voxel->create(base);
  ASSERT_TRUE(backend->ready()) << backend->error();
  const FluidCamera camera = cameraAt({0.5f, 0.9f, 1.4f}, {0.0f, 0.0f, 0.0f}, kW, kH, 0.1f);
  const glm::dvec3 c(0.05, 0.0, -0.05);
  const double rho = 0.14;
  const glm::dmat3 gd = kernelOf({1.0, 0.1, -0.4}, {3.0, 0.35, 2.0});
  // The particle 5 px off its kernel centre x̄: the backend draws at the centres.
  const std::vector<glm::vec3> centres{glm::vec3(c)}, particles{glm::vec3(c) + glm::vec3(0.1f, 0.0f, 0.0f)};
  const std::vector<glm::mat3> g{glm::mat3(gd)};
  const std::vector<float> axes{3.0f};
  WaterInput in;
  in.particles = particles;
  in.rc = static_cast<float>(3.0 * rho / 0.975);  // the backend's sphere radius 0.975 Rc / 3 = ρ
  in.kernel_g = g;
  in.kernel_max_axis = axes;
  in.kernel_centres = centres;
  WaterParams water;  // opaque, so the mask is the silhouette however thin the water is
  water.absorption = glm::vec3(1000.0f);
  water.refraction = 0.0f;
  water.opacity = 1.0f;
  std::string error;
  const GLuint scene = backend->upload(in, error);
  ASSERT_NE(scene, 0u) << error;
  glBindFramebuffer(GL_FRAMEBUFFER, scene);
  glViewport(0, 0, kW, kH);
  glClearColor(kClear.r, kClear.g, kClear.b, kClear.a);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  Target target(kW, kH);
  backend->draw(target.fbo, camera, water, in);
  const std::vector<unsigned char> image = readRgba8(target.fbo, kW, kH);
  auto inside = [&](double fx, double fy, const glm::dmat3& shape, double radius) {
    double d0, d1, margin;
    return analyticInterval(camera, kW, kH, fx, fy, c, shape, radius, d0, d1, margin);
  };
  int water_pixels = 0, expected_pixels = 0, sphere_pixels = 0, wrong = 0, far_wrong = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const bool is_water = isWater(&image[(static_cast<std::size_t>(y) * kW + x) * 4]);
      const bool expected = inside(x + 0.5, y + 0.5, gd, rho);
      water_pixels += is_water;
      expected_pixels += expected;
      sphere_pixels += inside(x + 0.5, y + 0.5, glm::dmat3(1.0), rho);
      if (is_water == expected) continue;
      ++wrong;
      bool near_edge = false;
      for (int dy = -2; dy <= 2 && !near_edge; ++dy)
        for (int dx = -2; dx <= 2 && !near_edge; ++dx)
          near_edge = inside(x + 0.5 + dx, y + 0.5 + dy, gd, rho) != expected;
      far_wrong += !near_edge;
    }
  }
  std::printf(
      "backend ellipsoid: %d water pixels, %d analytic, %d differ (%d away from the edge); the sphere of "
      "the same radius: %d\n",
      water_pixels, expected_pixels, wrong, far_wrong, sphere_pixels);
  EXPECT_GT(expected_pixels, 300);
  EXPECT_EQ(far_wrong, 0);
  EXPECT_LT(wrong, expected_pixels / 5);
  // Not the sphere of the same radius (which the backend drew before anisotropic kernels).
  EXPECT_GT(std::abs(expected_pixels - sphere_pixels), expected_pixels / 3);
}

TEST_F(VoxelAnisoTest, BadKernelsAreRefusedWithAMessage) {
  VoxelDesc desc;
  desc.base = {32, 24, shaderDir()};
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const std::vector<glm::vec3> centres{glm::vec3(0.0f), glm::vec3(0.1f)};
  std::vector<glm::mat3> g(2, glm::mat3(1.0f));
  std::vector<float> axes(2, 1.0f);
  std::string error;
  ASSERT_TRUE(uploadVoxelEllipsoids(r, centres, g, axes, error)) << error;
  EXPECT_TRUE(r.stats.ellipsoids);
  g[1][2][0] = std::nanf("");
  EXPECT_FALSE(uploadVoxelEllipsoids(r, centres, g, axes, error));
  EXPECT_NE(error.find("matrix 1 is not finite"), std::string::npos) << error;
  EXPECT_EQ(r.particles.count, 0u);  // nothing drawn from a refused upload
  g[1] = glm::mat3(1.0f);
  axes[0] = 0.0f;
  EXPECT_FALSE(uploadVoxelEllipsoids(r, centres, g, axes, error));
  axes[0] = 1.0f;
  EXPECT_FALSE(uploadVoxelEllipsoids(r, centres, std::span(g).first(1), axes, error));
  EXPECT_NE(error.find("2 centres, 1 matrices"), std::string::npos) << error;
  // Spheres again after ellipsoids: the kernels are dropped.
  ASSERT_TRUE(uploadVoxelParticles(r, centres, error)) << error;
  EXPECT_FALSE(r.stats.ellipsoids);
  EXPECT_EQ(r.shapes.count, 0u);
  destroyVoxelRenderer(r);
}

}  // namespace
