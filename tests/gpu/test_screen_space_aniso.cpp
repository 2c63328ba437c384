// Screen-space fluid with anisotropic kernels and the narrow-range filter (issue 36) on llvmpipe:
//   - one ellipsoid splat's silhouette and linear depth against the analytic ray-ellipsoid
//     intersection, computed here in double for every pixel;
//   - an identity g draws the sphere the isotropic path draws;
//   - the ray caster's lone ellipsoidal metaball hits the ellipsoid of the field's iso radius, and an
//     identity g casts what the spherical metaballs cast;
//   - a jittered flat pool's top surface: the RMS angle of its screen-space normals from vertical,
//     isotropic against anisotropic kernels (issue 36: at least halved);
//   - the narrow-range filter (Truong & Yuksel 2018) flattens a noisy depth plane and keeps a step
//     edge (numbers asserted; the bilateral filter's printed beside them).
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "fluid/sph/anisotropy.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace engine;

namespace {

constexpr int kW = 96, kH = 96;
constexpr float kEmpty = 1e20f;

std::filesystem::path shaderDir() { return std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders"; }

FluidCamera camera(int w, int h) {
  FluidCamera c;
  c.eye = glm::vec3(0.3f, 0.4f, 3.0f);
  c.near_plane = 0.1f;
  c.far_plane = 20.0f;
  c.view = glm::lookAt(c.eye, glm::vec3(0.0f), glm::vec3(0, 1, 0));
  c.projection =
      glm::perspective(glm::radians(45.0f), static_cast<float>(w) / static_cast<float>(h), c.near_plane, c.far_plane);
  return c;
}

std::vector<float> readDepth(const ScreenSpaceRenderer& r, int index) {
  std::vector<float> z(static_cast<std::size_t>(r.desc.width) * static_cast<std::size_t>(r.desc.height));
  glBindFramebuffer(GL_FRAMEBUFFER, r.smooth_fbo[index]);
  glReadPixels(0, 0, r.desc.width, r.desc.height, GL_RED, GL_FLOAT, z.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return z;
}

// Analytic linear depth of the ellipsoid {x : |g (x - c)| <= rho} through pixel (x, y) (its
// centre), in double; < 0 when the ray misses. `margin` receives 1 - |q|^2 of the closest approach
// (near 0 at the silhouette).
double analyticDepth(const FluidCamera& cam, int w, int h, int x, int y, glm::dvec3 c, const glm::dmat3& g, double rho,
                     double& margin) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.projection) * glm::dmat4(cam.view));
  const glm::dvec2 ndc((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0);
  glm::dvec4 a = inv * glm::dvec4(ndc, -1.0, 1.0), b = inv * glm::dvec4(ndc, 1.0, 1.0);
  const glm::dvec3 p0 = glm::dvec3(a) / a.w, p1 = glm::dvec3(b) / b.w;
  const glm::dvec3 eye(cam.eye), dir = glm::normalize(p1 - p0);
  const glm::dvec3 o = g * (eye - c) / rho, d = g * dir / rho;
  const double aa = glm::dot(d, d), m = -glm::dot(o, d) / aa;
  const glm::dvec3 q = o + m * d;
  margin = 1.0 - glm::dot(q, q);
  if (margin <= 0.0) return -1.0;
  const double t0 = m - std::sqrt(margin / aa);
  const glm::dvec3 p = eye + t0 * dir;
  return -(glm::dmat4(cam.view) * glm::dvec4(p, 1.0)).z;
}

class ScreenSpaceAnisoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gputest::createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
  }
  void TearDown() override { gputest::destroyContext(ctx_); }
  // Draws `centres` (spheres, or ellipsoids when g is given) with no smoothing; returns pass 1's depth.
  std::vector<float> splatDepth(std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                                std::span<const float> max_axis, float rho) {
    FluidRenderDesc desc;
    desc.width = kW;
    desc.height = kH;
    desc.shader_dir = shaderDir();
    ScreenSpaceRenderer r;
    createScreenSpaceRenderer(desc, r);
    EXPECT_TRUE(r.ready) << r.error;
    SceneTargets target;
    EXPECT_TRUE(createSceneTargets(kW, kH, target));
    beginScreenSpaceOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
    std::string error;
    if (g.empty())
      EXPECT_TRUE(uploadScreenSpaceParticles(r, centres, error)) << error;
    else
      EXPECT_TRUE(uploadScreenSpaceEllipsoids(r, centres, g, max_axis, error)) << error;
    ScreenSpaceParams p;
    p.radius = rho;
    p.smoothing_iterations = 0;
    drawScreenSpaceFluid(r, target.fbo, camera(kW, kH), WaterParams{}, p);
    std::vector<float> z = readDepth(r, 0);
    EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
    const std::size_t live = countLiveGlObjects(glNames(r));
    destroyScreenSpaceRenderer(r);
    destroySceneTargets(target);
    EXPECT_GT(live, 0u);
    return z;
  }
  gputest::GlContext ctx_;
};

TEST_F(ScreenSpaceAnisoTest, EllipsoidSplatMatchesTheAnalyticEllipsoid) {
  // Semi-axes rho * (2, 1, 0.5) along a rotated frame (the long one tilted towards the camera).
  const glm::dvec3 e0 = glm::normalize(glm::dvec3(1.0, 0.6, 0.5));
  const glm::dvec3 e1 = glm::normalize(glm::cross(e0, glm::dvec3(0, 0, 1)));
  const glm::dvec3 e2 = glm::cross(e0, e1);
  const double axes[3] = {2.0, 1.0, 0.5};
  glm::dmat3 g(0.0);
  const glm::dvec3 frame[3] = {e0, e1, e2};
  for (int k = 0; k < 3; ++k) g += (1.0 / axes[k]) * glm::outerProduct(frame[k], frame[k]);
  const double rho = 0.3;
  const glm::dvec3 c(0.1, -0.05, 0.2);
  const std::vector<glm::vec3> centres{glm::vec3(c)};
  const std::vector<glm::mat3> gs{glm::mat3(g)};
  const std::vector<float> max_axis{2.0f};
  const std::vector<float> z = splatDepth(centres, gs, max_axis, static_cast<float>(rho));
  const FluidCamera cam = camera(kW, kH);
  std::size_t inside = 0, gpu_inside = 0, mismatched = 0, near_edge_mismatch = 0;
  double worst = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      double margin = 0.0;
      const double expected = analyticDepth(cam, kW, kH, x, y, c, g, rho, margin);
      const float got = z[static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x)];
      const bool hit = expected > 0.0, gpu_hit = got < kEmpty;
      inside += hit;
      gpu_inside += gpu_hit;
      if (hit != gpu_hit) {
        ++mismatched;
        near_edge_mismatch += std::abs(margin) < 0.02;  // within 1 % of the radius of the silhouette
        continue;
      }
      if (hit && margin > 0.02) worst = std::max(worst, std::abs(static_cast<double>(got) - expected));
    }
  std::printf(
      "ellipsoid splat: %zu pixels analytic, %zu drawn, %zu differ (%zu at the silhouette), largest depth "
      "error %.2e m inside\n",
      inside, gpu_inside, mismatched, near_edge_mismatch, worst);
  EXPECT_GT(inside, 600u);                    // a real footprint at 96 x 96
  EXPECT_EQ(mismatched, near_edge_mismatch);  // only silhouette pixels may differ
  EXPECT_LE(mismatched, inside / 100 + 2);
  EXPECT_LT(worst, 1e-4);  // depth of the ray-ellipsoid hit

  // Not the bounding sphere: the sphere of the longest axis covers far more pixels.
  std::size_t sphere = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      double margin = 0.0;
      sphere += analyticDepth(cam, kW, kH, x, y, c, glm::dmat3(1.0), 2.0 * rho, margin) > 0.0;
    }
  EXPECT_GT(sphere, gpu_inside * 3 / 2);
}

// g = I draws the isotropic renderer's sphere (the same pixels, depths within float rounding).
TEST_F(ScreenSpaceAnisoTest, IdentityMatrixDrawsTheSphere) {
  const std::vector<glm::vec3> centres{{0.0f, 0.0f, 0.0f}, {0.35f, 0.1f, -0.2f}, {-0.3f, -0.2f, 0.4f}};
  const std::vector<glm::mat3> gs(3, glm::mat3(1.0f));
  const std::vector<float> axes(3, 1.0f);
  const std::vector<float> spheres = splatDepth(centres, {}, {}, 0.25f);
  const std::vector<float> ellipsoids = splatDepth(centres, gs, axes, 0.25f);
  std::size_t drawn = 0, differ = 0;
  float worst = 0.0f;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const bool a = spheres[i] < kEmpty, b = ellipsoids[i] < kEmpty;
    drawn += a;
    differ += a != b;
    if (a && b) worst = std::max(worst, std::abs(spheres[i] - ellipsoids[i]));
  }
  EXPECT_GT(drawn, 500u);
  EXPECT_LE(differ, 2u);
  EXPECT_LT(worst, 1e-4f);
}

// Garbage matrices are refused before they reach the GPU.
TEST_F(ScreenSpaceAnisoTest, NonFiniteMatricesAreRefused) {
  FluidRenderDesc desc;
  desc.width = 32;
  desc.height = 32;
  desc.shader_dir = shaderDir();
  ScreenSpaceRenderer r;
  createScreenSpaceRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  const std::vector<glm::vec3> centres{glm::vec3(0.0f)};
  std::vector<glm::mat3> gs{glm::mat3(1.0f)};
  gs[0][1][2] = std::nanf("");
  const std::vector<float> axes{1.0f};
  std::string error;
  EXPECT_FALSE(uploadScreenSpaceEllipsoids(r, centres, gs, axes, error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;
  EXPECT_FALSE(uploadScreenSpaceEllipsoids(r, centres, {}, axes, error));
  destroyScreenSpaceRenderer(r);
}

constexpr float kNoise = 0.04f;

struct FilterResult {
  double rms_left = 0, rms_right = 0;    // deviation from the plane, interior columns
  double edge_left = 0, edge_right = 0;  // mean depth of the two columns at the step
};

// A noisy plane at depth 3 m (left half) stepping to 3.6 m (right half), filtered in place: noise
// of +-4 cm, the size of the bumps a lattice of particles of radius 2 cm leaves, comparable to the
// bilateral filter's range sigma (5 cm).
FilterResult filterStep(DepthFilter filter, std::vector<float>* out_before = nullptr) {
  constexpr int w = 64, h = 64;
  FluidRenderDesc desc;
  desc.width = w;
  desc.height = h;
  desc.shader_dir = shaderDir();
  ScreenSpaceRenderer r;
  createScreenSpaceRenderer(desc, r);
  EXPECT_TRUE(r.ready) << r.error;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(-kNoise, kNoise);
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) z[static_cast<std::size_t>(y) * w + x] = (x < w / 2 ? 3.0f : 3.6f) + noise(rng);
  if (out_before != nullptr) *out_before = z;
  glBindTexture(GL_TEXTURE_2D, r.smooth_depth[0]);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RED, GL_FLOAT, z.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  ScreenSpaceParams p;
  p.filter = filter;
  p.radius = 0.02f;  // narrow range: threshold 0.21 m, clamp 0.02 m (the step is 0.6 m)
  p.filter_radius = 0.25f;
  p.smoothing_iterations = 3;
  filterScreenSpaceDepth(r, camera(w, h), p);
  const std::vector<float> f = readDepth(r, 0);
  destroyScreenSpaceRenderer(r);
  FilterResult res;
  std::size_t n = 0;
  for (int y = 12; y < h - 12; ++y) {
    for (int x = 8; x < 24; ++x) {
      const double dl = f[static_cast<std::size_t>(y) * w + x] - 3.0,
                   dr = f[static_cast<std::size_t>(y) * w + x + 32] - 3.6;
      res.rms_left += dl * dl;
      res.rms_right += dr * dr;
      ++n;
    }
    res.edge_left += f[static_cast<std::size_t>(y) * w + w / 2 - 1];
    res.edge_right += f[static_cast<std::size_t>(y) * w + w / 2];
  }
  res.rms_left = std::sqrt(res.rms_left / static_cast<double>(n));
  res.rms_right = std::sqrt(res.rms_right / static_cast<double>(n));
  res.edge_left /= h - 24;
  res.edge_right /= h - 24;
  return res;
}

TEST_F(ScreenSpaceAnisoTest, NarrowRangeFlattensNoiseAndKeepsTheStep) {
  const double input_rms = kNoise / std::sqrt(3.0);  // uniform noise
  const FilterResult narrow = filterStep(DepthFilter::narrow_range);
  const FilterResult bilateral = filterStep(DepthFilter::bilateral);
  std::printf("noisy plane (rms %.4f m in), step 3.0 -> 3.6 m, smoothing_iterations 3:\n", input_rms);
  std::printf("  narrow_range: rms %.5f / %.5f m, edge columns %.4f / %.4f m\n", narrow.rms_left, narrow.rms_right,
              narrow.edge_left, narrow.edge_right);
  std::printf("  bilateral:    rms %.5f / %.5f m, edge columns %.4f / %.4f m\n", bilateral.rms_left,
              bilateral.rms_right, bilateral.edge_left, bilateral.edge_right);
  // Flattened: the noise down to under a tenth on both sides of the step (on this plane the
  // bilateral filter does about as well: the numbers above).
  EXPECT_LT(narrow.rms_left, 0.1 * input_rms);
  EXPECT_LT(narrow.rms_right, 0.1 * input_rms);
  // Kept: the far side takes nothing from the near side (its samples are left out); the near side
  // moves back by less than the clamp (2 cm; the filter runs one round as wide as the bilateral's
  // three), the step stays over 0.57 m.
  EXPECT_NEAR(narrow.edge_right, 3.6, 0.01);
  EXPECT_NEAR(narrow.edge_left, 3.0, 0.02);
  EXPECT_GT(narrow.edge_right - narrow.edge_left, 0.57);
}

// Distance along the pixel's ray to the ellipsoid {x : |g (x - c)| <= rho}; < 0 when missed.
double analyticHit(const FluidCamera& cam, int w, int h, int x, int y, glm::dvec3 c, const glm::dmat3& g, double rho,
                   double& margin) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.projection) * glm::dmat4(cam.view));
  const glm::dvec2 ndc((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0);
  glm::dvec4 a = inv * glm::dvec4(ndc, -1.0, 1.0), b = inv * glm::dvec4(ndc, 1.0, 1.0);
  const glm::dvec3 dir = glm::normalize(glm::dvec3(b) / b.w - glm::dvec3(a) / a.w);
  const glm::dvec3 o = g * (glm::dvec3(cam.eye) - c) / rho, d = g * dir / rho;
  const double aa = glm::dot(d, d), m = -glm::dot(o, d) / aa;
  const glm::dvec3 q = o + m * d;
  margin = 1.0 - glm::dot(q, q);
  return margin <= 0.0 ? -1.0 : m - std::sqrt(margin / aa);
}

// The ray caster's hit distances (RGBA32F .w, < 0 = none) for `centres` as spherical or ellipsoidal
// metaballs of cutoff rc, iso level 0.2.
std::vector<glm::vec4> raycastHits(std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                                   std::span<const float> max_axis, float rc) {
  RaycastDesc desc;
  desc.base.width = kW;
  desc.base.height = kH;
  desc.base.shader_dir = shaderDir();
  RaycastRenderer r;
  createRaycastRenderer(desc, r);
  EXPECT_TRUE(r.ready) << r.error;
  SceneTargets target;
  EXPECT_TRUE(createSceneTargets(kW, kH, target));
  beginRaycastOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
  std::string error;
  if (g.empty())
    EXPECT_TRUE(uploadRaycastParticles(r, centres, error)) << error;
  else
    EXPECT_TRUE(uploadRaycastEllipsoids(r, centres, g, max_axis, error)) << error;
  RaycastParams p;
  p.rc = rc;
  p.threshold = 0.2f;
  drawRaycastFluid(r, target.fbo, camera(kW, kH), WaterParams{}, p);
  std::vector<glm::vec4> hits(static_cast<std::size_t>(kW) * kH);
  glBindTexture(GL_TEXTURE_2D, r.hits);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, hits.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  EXPECT_EQ(r.dropped, 0u);
  destroyRaycastRenderer(r);
  destroySceneTargets(target);
  return hits;
}

// A lone metaball's surface is where (u - 1/2)^2 = T, u = |g (x - c)|^2 / (2 Rc^2): the ellipsoid
// of "radius" Rc sqrt(1 - 2 sqrt(T)) (0.325 Rc at T = 0.2, the mesh's lone-particle radius).
TEST_F(ScreenSpaceAnisoTest, RaycastEllipsoidalMetaballHitsTheIsoEllipsoid) {
  const glm::dvec3 e0 = glm::normalize(glm::dvec3(1.0, 0.6, 0.5));
  const glm::dvec3 e1 = glm::normalize(glm::cross(e0, glm::dvec3(0, 0, 1)));
  const glm::dvec3 e2 = glm::cross(e0, e1);
  const double axes[3] = {2.0, 1.0, 0.5};
  const glm::dvec3 frame[3] = {e0, e1, e2};
  glm::dmat3 g(0.0);
  for (int k = 0; k < 3; ++k) g += (1.0 / axes[k]) * glm::outerProduct(frame[k], frame[k]);
  const double rc = 0.9, iso = rc * std::sqrt(1.0 - 2.0 * std::sqrt(0.2));
  const glm::dvec3 c(0.1, -0.05, 0.2);
  const std::vector<glm::vec3> centres{glm::vec3(c)};
  const std::vector<glm::mat3> gs{glm::mat3(g)};
  const std::vector<float> max_axis{2.0f};
  const std::vector<glm::vec4> hits = raycastHits(centres, gs, max_axis, static_cast<float>(rc));
  const FluidCamera cam = camera(kW, kH);
  std::size_t inside = 0, drawn = 0, mismatched = 0, at_silhouette = 0;
  double worst = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      double margin = 0.0;
      const double expected = analyticHit(cam, kW, kH, x, y, c, g, iso, margin);
      const glm::vec4 got = hits[static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x)];
      const bool hit = expected > 0.0, gpu_hit = got.w >= 0.0f;
      inside += hit;
      drawn += gpu_hit;
      if (hit != gpu_hit) {
        ++mismatched;
        at_silhouette += std::abs(margin) < 0.05;
        continue;
      }
      if (hit && margin > 0.05) worst = std::max(worst, std::abs(static_cast<double>(got.w) - expected));
    }
  std::printf(
      "ellipsoidal metaball: %zu pixels analytic, %zu cast, %zu differ (%zu at the silhouette), largest hit "
      "error %.2e m inside\n",
      inside, drawn, mismatched, at_silhouette, worst);
  EXPECT_GT(inside, 300u);
  EXPECT_EQ(mismatched, at_silhouette);
  EXPECT_LE(mismatched, inside / 50 + 2);
  EXPECT_LT(worst, 2e-4);  // 3.4e-5 m on llvmpipe: the cast bisects each crossing 12 times
}

TEST_F(ScreenSpaceAnisoTest, RaycastIdentityMatrixCastsTheSphericalMetaballs) {
  const std::vector<glm::vec3> centres{{0.0f, 0.0f, 0.0f}, {0.25f, 0.1f, -0.1f}, {-0.2f, -0.15f, 0.2f}};
  const std::vector<glm::mat3> gs(3, glm::mat3(1.0f));
  const std::vector<float> axes(3, 1.0f);
  const std::vector<glm::vec4> spheres = raycastHits(centres, {}, {}, 0.6f);
  const std::vector<glm::vec4> ellipsoids = raycastHits(centres, gs, axes, 0.6f);
  std::size_t drawn = 0, differ = 0;
  float worst = 0.0f;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const bool a = spheres[i].w >= 0.0f, b = ellipsoids[i].w >= 0.0f;
    drawn += a;
    differ += a != b;
    if (a && b) worst = std::max(worst, std::abs(spheres[i].w - ellipsoids[i].w));
  }
  EXPECT_GT(drawn, 500u);
  EXPECT_LE(differ, 2u);
  EXPECT_LT(worst, 1e-3f);
}

// RMS angle (degrees) from vertical of the normals of the filtered depth over the pool's top
// (pixels whose world point lies in the middle of the pool, near its top), as the composite pass
// builds them: view positions from linear depth, central differences.
double topNormalRms(const std::vector<float>& z, const FluidCamera& cam, int w, int h, glm::vec2 lo, glm::vec2 hi,
                    float top, float band, std::size_t& pixels) {
  auto view = [&](int x, int y) {
    const float d = z[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)];
    const glm::vec2 ndc((static_cast<float>(x) + 0.5f) / static_cast<float>(w) * 2.0f - 1.0f,
                        (static_cast<float>(y) + 0.5f) / static_cast<float>(h) * 2.0f - 1.0f);
    return glm::vec3(ndc.x * d / cam.projection[0][0], ndc.y * d / cam.projection[1][1], -d);
  };
  const glm::mat3 view_to_world = glm::transpose(glm::mat3(cam.view));
  double sum = 0.0;
  pixels = 0;
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      bool full = true;
      for (int k = -1; k <= 1; ++k)
        full = full && z[static_cast<std::size_t>(y + k) * w + static_cast<std::size_t>(x)] < kEmpty &&
               z[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x + k)] < kEmpty;
      if (!full) continue;
      const glm::vec3 world = cam.eye + view_to_world * view(x, y);
      if (world.x < lo.x || world.x > hi.x || world.z < lo.y || world.z > hi.y || std::abs(world.y - top) > band)
        continue;
      glm::vec3 n = glm::normalize(glm::cross(view(x + 1, y) - view(x - 1, y), view(x, y + 1) - view(x, y - 1)));
      n = view_to_world * n;
      const double c = std::clamp(static_cast<double>(std::abs(n.y)), 0.0, 1.0);
      const double angle = std::acos(c) * 180.0 / 3.14159265358979;
      sum += angle * angle;
      ++pixels;
    }
  return pixels > 0 ? std::sqrt(sum / static_cast<double>(pixels)) : 0.0;
}

TEST_F(ScreenSpaceAnisoTest, FlatPoolNormalsAtLeastHalvedByAnisotropicKernels) {
  // A pool of 24 x 4 x 24 particles at spacing d, jittered by up to 0.15 d: the lattice bumps a
  // calm surface shows. The game's screen-space settings for Rc = 2 d: splat radius 0.65 d,
  // filter half-width d, 3 bilateral rounds; anisotropy with r = 3 d and the keys' defaults.
  constexpr int w = 160, h = 120, n = 24, layers = 4;
  const float d = 0.05f;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.15f * d, 0.15f * d);
  std::vector<glm::vec3> pool;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < layers; ++j)
      for (int i = 0; i < n; ++i)
        pool.push_back(glm::vec3(i * d + jitter(rng), j * d + jitter(rng), k * d + jitter(rng)));
  fluid::AnisotropyParams a;
  a.radius = 3.0f * d;
  fluid::Anisotropy kernels;
  fluid::AnisotropyScratch scratch;
  ASSERT_TRUE(fluid::computeAnisotropy(pool, a, scratch, kernels));
  FluidCamera cam;
  const glm::vec3 centre(0.5f * (n - 1) * d, (layers - 1) * d, 0.5f * (n - 1) * d);
  cam.eye = centre + glm::vec3(0.0f, 0.9f, 0.9f);
  cam.near_plane = 0.05f;
  cam.far_plane = 20.0f;
  cam.view = glm::lookAt(cam.eye, centre, glm::vec3(0, 1, 0));
  cam.projection = glm::perspective(glm::radians(45.0f), static_cast<float>(w) / h, cam.near_plane, cam.far_plane);
  auto render = [&](bool anisotropic, int rounds) {
    FluidRenderDesc desc;
    desc.width = w;
    desc.height = h;
    desc.shader_dir = shaderDir();
    ScreenSpaceRenderer r;
    createScreenSpaceRenderer(desc, r);
    EXPECT_TRUE(r.ready) << r.error;
    SceneTargets target;
    EXPECT_TRUE(createSceneTargets(w, h, target));
    beginScreenSpaceOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
    std::string error;
    if (anisotropic)
      EXPECT_TRUE(uploadScreenSpaceEllipsoids(r, kernels.centre, kernels.g, kernels.max_axis, error)) << error;
    else
      EXPECT_TRUE(uploadScreenSpaceParticles(r, pool, error)) << error;
    ScreenSpaceParams p;
    p.radius = 0.65f * d;
    p.filter_radius = d;
    p.smoothing_iterations = rounds;
    drawScreenSpaceFluid(r, target.fbo, cam, WaterParams{}, p);
    std::vector<float> z = readDepth(r, 0);
    destroyScreenSpaceRenderer(r);
    destroySceneTargets(target);
    return z;
  };
  const glm::vec2 lo(0.25f * n * d, 0.25f * n * d), hi(0.75f * n * d, 0.75f * n * d);
  std::printf(
      "flat pool (24 x 4 x 24, jitter 0.15 d), %zu of %zu particles stretched; top normals rms from vertical:\n",
      kernels.stretched, pool.size());
  double rms[2][2];
  for (int rounds : {0, 3}) {
    std::size_t iso_pixels = 0, aniso_pixels = 0;
    // The top within a particle spacing (the centre smoothing moves the anisotropic top down a little).
    rms[rounds > 0][0] = topNormalRms(render(false, rounds), cam, w, h, lo, hi, centre.y, d, iso_pixels);
    rms[rounds > 0][1] = topNormalRms(render(true, rounds), cam, w, h, lo, hi, centre.y, d, aniso_pixels);
    std::printf("  %d bilateral rounds: isotropic %.2f deg (%zu px), anisotropic %.2f deg (%zu px)\n", rounds,
                rms[rounds > 0][0], iso_pixels, rms[rounds > 0][1], aniso_pixels);
    EXPECT_GT(iso_pixels, 1000u);
    EXPECT_GT(aniso_pixels, 1000u);
  }
  EXPECT_LE(rms[0][1], 0.5 * rms[0][0]);   // the splats themselves
  EXPECT_LE(rms[1][1], 0.55 * rms[1][0]);  // after the game's smoothing (measured: 0.502)
}

}  // namespace
