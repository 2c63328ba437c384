// The first-surface read-back (engine/fluid_render/first_surface.hpp) of the three particle-direct
// renderers on llvmpipe, against a lone sphere whose surface is known in closed form: every water
// pixel's world point must lie on the sphere and its world normal must point away from the centre.
// This is what `fluiddemo render --surface-out` writes and docs/appearance.md's flat-pool normals
// are computed from, so a wrong convention (view against world, bottom-up rows, the pixel centre)
// would show here as points off the sphere.
#include "engine/fluid_render/first_surface.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace engine;

namespace {

constexpr int kW = 96, kH = 80;

std::filesystem::path shaderDir() { return std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders"; }

FluidCamera camera() {
  FluidCamera c;
  c.eye = glm::vec3(0.25f, 0.45f, 1.5f);
  c.near_plane = 0.1f;
  c.far_plane = 20.0f;
  c.view = glm::lookAt(c.eye, glm::vec3(0.05f, -0.02f, 0.0f), glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(45.0f), static_cast<float>(kW) / static_cast<float>(kH),
                                  c.near_plane, c.far_plane);
  return c;
}

const glm::vec3 kCentre(0.05f, -0.02f, 0.0f);

struct SphereFit {
  std::size_t pixels = 0, inner = 0;  // water pixels; those whose normal faces the eye by > 30°
  double worst_radius_error = 0.0;    // max | |p - c| - radius | over the inner pixels, metres
  double mean_angle = 0.0, worst_angle = 0.0;  // normal against (p - c)/|p - c| over the inner pixels, degrees
};

// Away from the silhouette (where every renderer's normal is least defined) the normal should be
// the sphere's; the inner pixels are those whose true normal is within 60° of the eye direction.
SphereFit fitSphere(const FirstSurface& s, const FluidCamera& cam, float radius) {
  SphereFit fit;
  double angle_sum = 0.0;
  for (std::size_t i = 0; i < s.hit.size(); ++i) {
    if (!s.hit[i]) continue;
    ++fit.pixels;
    const glm::dvec3 p(s.point[i]), c(kCentre);
    const glm::dvec3 outward = glm::normalize(p - c), to_eye = glm::normalize(glm::dvec3(cam.eye) - p);
    if (glm::dot(outward, to_eye) < 0.5) continue;
    ++fit.inner;
    fit.worst_radius_error = std::max(fit.worst_radius_error, std::abs(glm::length(p - c) - radius));
    const double cosine = std::clamp(glm::dot(outward, glm::normalize(glm::dvec3(s.normal[i]))), -1.0, 1.0);
    const double angle = std::acos(cosine) * 180.0 / 3.14159265358979;
    angle_sum += angle;
    fit.worst_angle = std::max(fit.worst_angle, angle);
  }
  fit.mean_angle = fit.inner > 0 ? angle_sum / static_cast<double>(fit.inner) : 0.0;
  return fit;
}

void print(const char* name, const SphereFit& f) {
  std::printf("%s: %zu water pixels (%zu inner), radius error up to %.2e m, normal error mean %.2f deg, worst %.2f deg\n",
              name, f.pixels, f.inner, f.worst_radius_error, f.mean_angle, f.worst_angle);
}

class FirstSurfaceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gputest::createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
    ASSERT_TRUE(createSceneTargets(kW, kH, target_));
  }
  void TearDown() override {
    destroySceneTargets(target_);
    gputest::destroyContext(ctx_);
  }
  // The ray caster's first surface of `centres` as spherical metaballs.
  FirstSurface castFirstSurface(const std::vector<glm::vec3>& centres, const RaycastParams& params) {
    RaycastDesc desc;
    desc.base = {kW, kH, shaderDir()};
    RaycastRenderer r;
    createRaycastRenderer(desc, r);
    EXPECT_TRUE(r.ready) << r.error;
    beginRaycastOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
    std::string error;
    EXPECT_TRUE(uploadRaycastParticles(r, centres, error)) << error;
    drawRaycastFluid(r, target_.fbo, camera(), WaterParams{}, params);
    FirstSurface s;
    readRaycastFirstSurface(r, camera(), s);
    destroyRaycastRenderer(r);
    return s;
  }
  gputest::GlContext ctx_;
  SceneTargets target_;
};

// A lone metaball's iso surface is the sphere of radius Rc sqrt(1 - 2 sqrt(T)); the cast bisects
// each crossing and takes the field's gradient as the normal, so both are close to exact.
TEST_F(FirstSurfaceTest, RaycastPointsAndNormalsLieOnTheLoneMetaballsSphere) {
  RaycastParams p;
  p.rc = 0.9f;
  p.threshold = 0.2f;
  const FluidCamera cam = camera();
  const FirstSurface s = castFirstSurface({kCentre}, p);
  ASSERT_EQ(s.hit.size(), static_cast<std::size_t>(kW) * kH);
  const SphereFit fit = fitSphere(s, cam, p.rc * std::sqrt(1.0f - 2.0f * std::sqrt(p.threshold)));
  print("raycast", fit);
  EXPECT_GT(fit.inner, 300u);
  EXPECT_LT(fit.worst_radius_error, 1e-3);
  EXPECT_LT(fit.worst_angle, 1.0);
}

// One sphere splat, unfiltered: its linear depth is the ray-sphere entry, and the composite's
// one-sided differences give the sphere's normal to within about the angle a pixel spans on the
// sphere (2.0° mean, 2.7° worst on llvmpipe, 30 pixels across the radius).
TEST_F(FirstSurfaceTest, ScreenSpacePointsAndNormalsLieOnTheSplattedSphere) {
  FluidRenderDesc desc{kW, kH, shaderDir()};
  ScreenSpaceRenderer r;
  createScreenSpaceRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  beginScreenSpaceOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
  const std::vector<glm::vec3> centres{kCentre};
  std::string error;
  ASSERT_TRUE(uploadScreenSpaceParticles(r, centres, error)) << error;
  ScreenSpaceParams p;
  p.radius = 0.3f;
  p.smoothing_iterations = 0;
  const FluidCamera cam = camera();
  drawScreenSpaceFluid(r, target_.fbo, cam, WaterParams{}, p);
  FirstSurface s;
  readScreenSpaceFirstSurface(r, cam, s);
  destroyScreenSpaceRenderer(r);
  const SphereFit fit = fitSphere(s, cam, p.radius);
  print("screen_space", fit);
  EXPECT_GT(fit.inner, 300u);
  EXPECT_LT(fit.worst_radius_error, 1e-3);
  EXPECT_LT(fit.mean_angle, 3.0);
  EXPECT_LT(fit.worst_angle, 5.0);
}

// One sphere voxelised into depth layers (§4.2), filtered (§4.6) and given Sobel normals (§3.4):
// its points sit within a few layers of the sphere (the filter moves a curved surface: 2.4 layers
// on llvmpipe) and its normals follow it to a few degrees (2.3° mean).
TEST_F(FirstSurfaceTest, VoxelPointsAndNormalsFollowTheVoxelisedSphere) {
  VoxelDesc desc;
  desc.base = {kW, kH, shaderDir()};
  VoxelRenderer r;
  createVoxelRenderer(desc, r);
  ASSERT_TRUE(r.ready) << r.error;
  beginVoxelOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.1f, 1.0f));
  const std::vector<glm::vec3> centres{kCentre};
  std::string error;
  ASSERT_TRUE(uploadVoxelParticles(r, centres, error)) << error;
  VoxelParams p;
  p.radius = 0.3f;
  p.min_gap = 0.05f;
  p.filter_radius = 0.05f;
  const FluidCamera cam = camera();
  drawVoxelFluid(r, target_.fbo, cam, WaterParams{}, p);
  FirstSurface s;
  readVoxelFirstSurface(r, cam, s);
  const float layer = (r.layers.depth.back() - r.layers.depth.front()) / static_cast<float>(r.layers.count);
  destroyVoxelRenderer(r);
  const SphereFit fit = fitSphere(s, cam, p.radius);
  print("voxel", fit);
  std::printf("  mean layer thickness %.3e m\n", static_cast<double>(layer));
  EXPECT_GT(fit.inner, 300u);
  EXPECT_LT(fit.worst_radius_error, 4.0 * layer);
  EXPECT_LT(fit.mean_angle, 4.0);
}

// Nothing drawn: no pixel reads as water.
TEST_F(FirstSurfaceTest, EmptyFrameHasNoSurface) {
  const FirstSurface s = castFirstSurface({glm::vec3(40.0f, 0.0f, 0.0f)}, RaycastParams{});
  EXPECT_EQ(std::count(s.hit.begin(), s.hit.end(), std::uint8_t{1}), 0);
}

}  // namespace
