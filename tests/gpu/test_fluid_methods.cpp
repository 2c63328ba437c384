// The particle-direct fluid renderers (engine/fluid_render/screen_space.hpp, raycast.hpp) on
// llvmpipe (headless), against the marching-slices mesh on the same particles, camera and
// backdrop: water masks overlap, the ray-cast lone particle has the field's analytic radius,
// the fragment-list pool overflows gracefully and is counted, and switching methods leaks no
// GL objects.
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "tests/gpu/fluid_scene.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>

using namespace engine;
using namespace gputest;

namespace {

constexpr int kW = 128, kH = 96;
constexpr float kRc = 0.2f, kThreshold = 0.2f;  // extractMesh()'s field (fluid_scene.cpp)
const glm::vec4 kClear(0.1f, 0.1f, 0.12f, 1.0f);

std::filesystem::path shaderDir() { return std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders"; }

std::vector<unsigned char> readRgba8(GLuint fbo, int w, int h) {
  std::vector<unsigned char> px(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return px;
}

std::vector<glm::vec3> positionsOf(const FluidScene& s) { return s.particles; }

// Water mask: pixels that differ from the frame without fluid by more than 2/255 in a channel.
std::vector<std::uint8_t> waterMask(const std::vector<unsigned char>& image, const std::vector<unsigned char>& bg) {
  std::vector<std::uint8_t> mask(image.size() / 4, 0);
  for (std::size_t p = 0; p < mask.size(); ++p)
    for (std::size_t c = 0; c < 3; ++c) mask[p] |= std::abs(int(image[4 * p + c]) - int(bg[4 * p + c])) > 2;
  return mask;
}

std::size_t countOf(const std::vector<std::uint8_t>& m) {
  std::size_t n = 0;
  for (std::uint8_t v : m) n += v;
  return n;
}

double iou(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  std::size_t both = 0, either = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    both += a[i] & b[i];
    either += a[i] | b[i];
  }
  return either == 0 ? 0.0 : static_cast<double>(both) / static_cast<double>(either);
}

// Every GL name of the kinds the renderers create that the context still knows, probed over
// the first `range` names: independent of any renderer's own bookkeeping.
std::size_t liveNamesProbe(GLuint range = 4096) {
  std::size_t n = 0;
  for (GLuint i = 1; i <= range; ++i)
    n += (glIsBuffer(i) == GL_TRUE) + (glIsTexture(i) == GL_TRUE) + (glIsFramebuffer(i) == GL_TRUE) +
         (glIsVertexArray(i) == GL_TRUE) + (glIsProgram(i) == GL_TRUE) + (glIsShader(i) == GL_TRUE);
  return n;
}

class FluidMethodsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
    std::string error;
    ASSERT_TRUE(createFluidScene(scene_, kW, kH, {2.4f, 0.9f, 0.3f}, error)) << error;
    ASSERT_TRUE(extractMesh(scene_, fluid::SurfaceOrder::backToFront, false, error)) << error;
    desc_.width = kW;
    desc_.height = kH;
    desc_.shader_dir = shaderDir();
  }
  void TearDown() override {
    destroyFluidScene(scene_);
    destroyContext(ctx_);
  }
  std::vector<unsigned char> renderMesh(GLuint fbo, bool with_fluid) {
    FluidRenderer r;
    createFluidRenderer(desc_, r);
    EXPECT_TRUE(r.ready) << r.error;
    auto px = renderFrame(scene_, r, fbo, water_, with_fluid);
    destroyFluidRenderer(r);
    return px;
  }
  std::vector<unsigned char> renderScreenSpace(GLuint fbo, std::span<const glm::vec3> particles,
                                               const ScreenSpaceParams& params) {
    ScreenSpaceRenderer r;
    createScreenSpaceRenderer(desc_, r);
    EXPECT_TRUE(r.ready) << r.error;
    beginScreenSpaceOpaquePass(r, kClear);
    drawBackdrop(scene_);
    std::string error;
    EXPECT_TRUE(uploadScreenSpaceParticles(r, particles, error)) << error;
    drawScreenSpaceFluid(r, fbo, scene_.camera, water_, params);
    destroyScreenSpaceRenderer(r);
    return readRgba8(fbo, kW, kH);
  }
  std::vector<unsigned char> renderRaycast(GLuint fbo, std::span<const glm::vec3> particles, RaycastDesc desc,
                                           const RaycastParams& params, RaycastRenderer* keep = nullptr) {
    RaycastRenderer local;
    RaycastRenderer& r = keep != nullptr ? *keep : local;
    createRaycastRenderer(desc, r);
    EXPECT_TRUE(r.ready) << r.error;
    beginRaycastOpaquePass(r, kClear);
    drawBackdrop(scene_);
    std::string error;
    EXPECT_TRUE(uploadRaycastParticles(r, particles, error)) << error;
    drawRaycastFluid(r, fbo, scene_.camera, water_, params);
    auto px = readRgba8(fbo, desc.base.width, desc.base.height);
    if (keep == nullptr) destroyRaycastRenderer(r);
    return px;
  }
  RaycastDesc raycastDesc() const {
    RaycastDesc d;
    d.base = desc_;
    return d;
  }
  static RaycastParams raycastParams() {
    RaycastParams p;
    p.rc = kRc;
    p.threshold = kThreshold;
    return p;
  }
  static ScreenSpaceParams screenSpaceParams() {
    ScreenSpaceParams p;
    p.radius = 0.975f * kRc / 3.0f;  // a lone particle's iso-surface radius, as for the mesh
    p.filter_radius = 0.5f * kRc;
    return p;
  }
  GlContext ctx_;
  FluidScene scene_;
  FluidRenderDesc desc_;
  WaterParams water_;
};

}  // namespace

// Both particle renderers draw the blob where the mesh draws it. Bounds: ray casting evaluates
// the mesh's own field exactly along each pixel's ray, so its mask differs from the mesh's only
// by the marching-cubes facets (cube 0.04 = ~1.5 px here) along the silhouettes: IoU >= 0.9.
// Screen space draws spheres of the lone-particle radius, smoothed: a different surface, close
// at the bulk and off at the rim and between the two blobs: IoU >= 0.7.
TEST_F(FluidMethodsTest, EachMethodDrawsTheWaterWhereTheMeshDoes) {
  ColourTarget target(kW, kH, GL_RGBA8);
  const auto background = renderMesh(target.fbo, false);
  const auto mesh_mask = waterMask(renderMesh(target.fbo, true), background);
  const std::vector<glm::vec3> particles = positionsOf(scene_);
  const auto ss_mask = waterMask(renderScreenSpace(target.fbo, particles, screenSpaceParams()), background);
  const auto rc_mask = waterMask(renderRaycast(target.fbo, particles, raycastDesc(), raycastParams()), background);
  EXPECT_GT(countOf(mesh_mask), 500u);
  EXPECT_GT(countOf(ss_mask), 500u);
  EXPECT_GT(countOf(rc_mask), 500u);
  const double ss = iou(ss_mask, mesh_mask), rc = iou(rc_mask, mesh_mask);
  std::printf(
      "[ metric ] water px: mesh %zu, screen_space %zu, raycast %zu; IoU vs mesh: screen_space %.3f raycast %.3f\n",
      countOf(mesh_mask), countOf(ss_mask), countOf(rc_mask), ss, rc);
  EXPECT_GE(rc, 0.9);
  EXPECT_GE(ss, 0.7);
}

// One particle: the field f = (u − 1/2)^2, u = r^2 / (2 Rc^2) (field.hpp) equals T = 0.2 at
// u = 1/2 − sqrt(0.2), r = Rc sqrt(1 − 2 sqrt(0.2)) = 0.3249 Rc = 0.975 Rc / 3 (the root with
// u > 1/2 lies past the support Rc). Its silhouette seen from distance D has half-angle
// asin(R / D); the cast disc's width along the centre row and column is 2 R_px ± 1 px.
TEST_F(FluidMethodsTest, LoneParticleRaycastHasTheAnalyticRadius) {
  const double radius = kRc * std::sqrt(1.0 - 2.0 * std::sqrt(0.2));
  EXPECT_NEAR(radius, 0.975 * kRc / 3.0, 1e-3 * kRc);
  constexpr int kSize = 160;
  const float distance = 1.0f, fov = glm::radians(45.0f);
  const glm::vec3 centre(0.3f, 0.6f, 0.2f);  // in front of the wall (x = -1.2)
  scene_.camera.eye = centre + glm::vec3(distance, 0.0f, 0.0f);
  scene_.camera.view = glm::lookAt(scene_.camera.eye, centre, glm::vec3(0, 1, 0));
  scene_.camera.projection = glm::perspective(fov, 1.0f, scene_.camera.near_plane, scene_.camera.far_plane);
  desc_.width = desc_.height = kSize;
  // Opaque, strongly absorbing, unrefracted water: every covered pixel differs from the wall
  // (thin water at the rim is bright by Fresnel, the rest dark).
  water_.absorption = glm::vec3(40.0f);
  water_.refraction = 0.0f;
  water_.opacity = 1.0f;
  ColourTarget target(kSize, kSize, GL_RGBA8);
  const std::vector<glm::vec3> one{centre}, none;
  const auto background = renderRaycast(target.fbo, none, raycastDesc(), raycastParams());
  const auto image = renderRaycast(target.fbo, one, raycastDesc(), raycastParams());
  const auto mask = waterMask(image, background);
  const double r_px = std::tan(std::asin(radius / distance)) / std::tan(fov / 2.0) * kSize / 2.0;
  int row = 0, column = 0;
  for (int i = 0; i < kSize; ++i) {
    row += mask[static_cast<std::size_t>(kSize / 2) * kSize + static_cast<std::size_t>(i)];
    column += mask[static_cast<std::size_t>(i) * kSize + kSize / 2];
  }
  std::printf("[ metric ] lone particle: analytic radius %.2f px, cast widths row %d column %d px\n", r_px, row,
              column);
  EXPECT_NEAR(row / 2.0, r_px, 1.0);
  EXPECT_NEAR(column / 2.0, r_px, 1.0);
  // A disc: about pi R^2 pixels.
  EXPECT_NEAR(static_cast<double>(countOf(mask)), M_PI * r_px * r_px, 2.0 * M_PI * r_px);
}

// A fixed pool far too small for the blob: records are dropped and counted, and the picture (in
// a float target) holds no NaN or infinity; a pool large enough drops nothing.
TEST_F(FluidMethodsTest, FragmentPoolOverflowIsCountedAndHarmless) {
  const std::vector<glm::vec3> particles = positionsOf(scene_);
  ColourTarget target(kW, kH, GL_RGBA32F);
  RaycastDesc tiny = raycastDesc();
  tiny.pool_per_pixel = 0.05f;
  RaycastParams fixed = raycastParams();
  fixed.grow_pool = false;
  RaycastRenderer r;
  renderRaycast(target.fbo, particles, tiny, fixed, &r);
  EXPECT_EQ(r.pool_growths, 0u);
  EXPECT_GT(r.used, r.pool_records);
  EXPECT_EQ(r.dropped, r.used - r.pool_records);
  std::vector<float> px(static_cast<std::size_t>(kW) * kH * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, target.fbo);
  glReadPixels(0, 0, kW, kH, GL_RGBA, GL_FLOAT, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  std::size_t nonfinite = 0;
  for (float v : px) nonfinite += !std::isfinite(v);
  EXPECT_EQ(nonfinite, 0u);
  std::printf("[ metric ] pool %u records: %llu asked, %llu dropped\n", r.pool_records,
              static_cast<unsigned long long>(r.used), static_cast<unsigned long long>(r.dropped));
  destroyRaycastRenderer(r);
  RaycastDesc ample = raycastDesc();
  ample.pool_per_pixel = 32.0f;  // this blob needs ~11 records per pixel on average (the pool's size)
  RaycastRenderer full;
  renderRaycast(target.fbo, particles, ample, fixed, &full);
  EXPECT_GT(full.used, 0u);
  EXPECT_EQ(full.dropped, 0u);
  destroyRaycastRenderer(full);
}

// The default pool sizes itself: started far too small, the first frame's gather overflows, the
// pool grows to 1.25x the demand and the gather runs again, so nothing is dropped and the picture
// is the one an ample fixed pool gives; the next frame needs no growth.
TEST_F(FluidMethodsTest, PoolGrowsToTheDemandAndDropsNothing) {
  const std::vector<glm::vec3> particles = positionsOf(scene_);
  ColourTarget target(kW, kH, GL_RGBA8);
  RaycastDesc ample = raycastDesc();
  ample.pool_per_pixel = 32.0f;
  RaycastParams fixed = raycastParams();
  fixed.grow_pool = false;
  const std::vector<unsigned char> reference = renderRaycast(target.fbo, particles, ample, fixed);
  RaycastDesc small = raycastDesc();
  small.pool_per_pixel = 0.05f;  // ~1/200 of this blob's demand
  RaycastRenderer r;
  const std::vector<unsigned char> grown = renderRaycast(target.fbo, particles, small, raycastParams(), &r);
  std::printf("[ metric ] pool grown from %.0f to %u records for %llu asked (%llu growths)\n",
              std::round(0.05 * kW * kH), r.pool_records, static_cast<unsigned long long>(r.used),
              static_cast<unsigned long long>(r.pool_growths));
  EXPECT_EQ(r.pool_growths, 1u);
  EXPECT_EQ(r.dropped, 0u);
  EXPECT_GT(r.used, static_cast<std::uint64_t>(0.05 * kW * kH));
  EXPECT_EQ(r.pool_records, static_cast<std::uint32_t>(std::ceil(1.25 * static_cast<double>(r.used))));
  std::size_t differing = 0;
  for (std::size_t i = 0; i < grown.size(); ++i) differing += std::abs(int(grown[i]) - int(reference[i])) > 1;
  EXPECT_EQ(differing, 0u);
  drawRaycastFluid(r, target.fbo, scene_.camera, water_, raycastParams());
  EXPECT_EQ(r.pool_growths, 1u);
  EXPECT_EQ(r.dropped, 0u);
  destroyRaycastRenderer(r);
}

// Growth stops at max_pool_per_pixel: the demand above it is dropped and counted as before.
TEST_F(FluidMethodsTest, PoolStopsAtItsBoundAndCountsTheRest) {
  const std::vector<glm::vec3> particles = positionsOf(scene_);
  ColourTarget target(kW, kH, GL_RGBA8);
  RaycastDesc bounded = raycastDesc();
  bounded.pool_per_pixel = 0.05f;
  bounded.max_pool_per_pixel = 0.5f;  // this blob asks for ~11 records per pixel on average
  RaycastRenderer r;
  renderRaycast(target.fbo, particles, bounded, raycastParams(), &r);
  EXPECT_EQ(r.pool_growths, 1u);
  EXPECT_EQ(r.pool_records, r.max_pool_records);
  EXPECT_EQ(r.max_pool_records, static_cast<std::uint32_t>(std::round(0.5 * kW * kH)));
  EXPECT_GT(r.used, r.pool_records);
  EXPECT_EQ(r.dropped, r.used - r.pool_records);
  destroyRaycastRenderer(r);
}

// Creating and destroying each method in turn (as the game's live switch does) leaves no GL
// object behind: each renderer's own name list is all dead right after destroy, and a probe of
// the context's first 4096 names of every kind counts as many live objects after two rounds as
// before them.
TEST_F(FluidMethodsTest, SwitchingMethodsLeaksNoGlObjects) {
  const std::vector<glm::vec3> particles = positionsOf(scene_);
  ColourTarget target(kW, kH, GL_RGBA8);
  renderMesh(target.fbo, true);
  const std::size_t before = liveNamesProbe();
  // An unused method holds nothing.
  EXPECT_EQ(glNames(ScreenSpaceRenderer{}).size(), 0u);
  EXPECT_EQ(glNames(RaycastRenderer{}).size(), 0u);
  for (int round = 0; round < 2; ++round) {
    ScreenSpaceRenderer ss;
    createScreenSpaceRenderer(desc_, ss);
    ASSERT_TRUE(ss.ready) << ss.error;
    std::string error;
    ASSERT_TRUE(uploadScreenSpaceParticles(ss, particles, error));
    drawScreenSpaceFluid(ss, target.fbo, scene_.camera, water_, screenSpaceParams());
    const GlObjectNames ss_names = glNames(ss);
    EXPECT_EQ(countLiveGlObjects(ss_names), ss_names.size());
    EXPECT_GE(ss_names.size(), 15u);
    destroyScreenSpaceRenderer(ss);
    EXPECT_EQ(countLiveGlObjects(ss_names), 0u) << "round " << round;
    RaycastRenderer rc;
    renderRaycast(target.fbo, particles, raycastDesc(), raycastParams(), &rc);
    const GlObjectNames rc_names = glNames(rc);
    EXPECT_EQ(countLiveGlObjects(rc_names), rc_names.size());
    EXPECT_GE(rc_names.size(), 14u);
    destroyRaycastRenderer(rc);
    EXPECT_EQ(countLiveGlObjects(rc_names), 0u) << "round " << round;
    renderMesh(target.fbo, true);
    EXPECT_EQ(liveNamesProbe(), before) << "round " << round;
  }
}

// Bad particles are refused with the index named, and the renderer stays usable.
TEST_F(FluidMethodsTest, NonFiniteParticlesAreRefused) {
  std::vector<glm::vec3> particles = positionsOf(scene_);
  particles[7].y = std::nanf("");
  ScreenSpaceRenderer ss;
  createScreenSpaceRenderer(desc_, ss);
  std::string error;
  EXPECT_FALSE(uploadScreenSpaceParticles(ss, particles, error));
  EXPECT_NE(error.find("position 7"), std::string::npos) << error;
  EXPECT_EQ(ss.particles.count, 0u);
  destroyScreenSpaceRenderer(ss);
  RaycastRenderer rc;
  createRaycastRenderer(raycastDesc(), rc);
  EXPECT_FALSE(uploadRaycastParticles(rc, particles, error));
  EXPECT_NE(error.find("position 7"), std::string::npos) << error;
  destroyRaycastRenderer(rc);
  RaycastDesc bad = raycastDesc();
  bad.pool_per_pixel = 0.0f;
  createRaycastRenderer(bad, rc);
  EXPECT_FALSE(rc.ready);
  EXPECT_NE(rc.error.find("pool_per_pixel"), std::string::npos) << rc.error;
  bad = raycastDesc();
  bad.max_pool_per_pixel = std::nanf("");
  createRaycastRenderer(bad, rc);
  EXPECT_FALSE(rc.ready);
  EXPECT_NE(rc.error.find("max_pool_per_pixel"), std::string::npos) << rc.error;
}
