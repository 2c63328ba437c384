// The goo style on llvmpipe (headless): the skin texture is sampled at the mesh's per-vertex
// (u, v) where the skin weight says so (the blob's tentacles, fluid/blob/tentacle_uv.hpp), and the
// goo is translucent where thin, opaque where told to be.
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/render/renderer.hpp"
#include "tests/gpu/fluid_scene.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <gtest/gtest.h>

#include <memory>

#include <cmath>
#include <limits>

using namespace engine;
using namespace gputest;

namespace {

constexpr int kW = 128, kH = 96;
constexpr int kStripes = 4;  // along v: red, blue, red, blue

class GooTextureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << "no headless GL context: " << ctx_.error;
    FluidRenderDesc d;
    d.width = kW;
    d.height = kH;
    d.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
    createFluidRenderer(d, renderer_);
    ASSERT_TRUE(renderer_.ready) << renderer_.error;
    std::string error;
    ASSERT_TRUE(createFluidScene(scene_, kW, kH, {2.4f, 0.9f, 0.3f}, error)) << error;
    ASSERT_TRUE(extractMesh(scene_, fluid::SurfaceOrder::backToFront, false, error)) << error;
    ASSERT_GT(scene_.mesh.indices.size(), 300u);
    // Stripes along v (image rows: row r holds t = (r + 0.5) / 64 once uploaded), red and blue.
    ImageData stripes;
    stripes.width = stripes.height = 64;
    stripes.rgba.resize(64 * 64 * 4);
    for (int r = 0; r < 64; ++r)
      for (int c = 0; c < 64; ++c) {
        const bool red = (r * kStripes / 64) % 2 == 0;
        unsigned char* px = &stripes.rgba[static_cast<std::size_t>(r * 64 + c) * 4];
        px[0] = red ? 255 : 0, px[1] = 0, px[2] = red ? 0 : 255, px[3] = 255;
      }
    texture_ = uploadTexture(stripes);
    // v = height within the mesh (0 at its lowest vertex, 1 at its highest), u around the vertical.
    y_lo_ = std::numeric_limits<float>::max(), y_hi_ = -y_lo_;
    for (const glm::vec3& p : scene_.mesh.positions) y_lo_ = std::min(y_lo_, p.y), y_hi_ = std::max(y_hi_, p.y);
    ASSERT_GT(y_hi_ - y_lo_, 0.3f);
    target_ = std::make_unique<ColourTarget>(kW, kH, GL_RGBA8);
  }
  void TearDown() override {
    target_.reset();
    texture_ = GpuTexture{};
    destroyFluidScene(scene_);
    destroyFluidRenderer(renderer_);
    destroyContext(ctx_);
  }

  float vOf(glm::vec3 p) const { return (p.y - y_lo_) / (y_hi_ - y_lo_); }

  // Per-vertex (u, v, weight, 0); empty when `weight` < 0 (no attributes uploaded).
  std::vector<glm::vec4> attributes(float weight) const {
    std::vector<glm::vec4> out;
    if (weight < 0.0f) return out;
    for (const glm::vec3& p : scene_.mesh.positions) {
      const float u = std::atan2(p.z, p.x) / 6.2831853f + 0.5f;
      out.emplace_back(u, vOf(p), weight, 0.0f);
    }
    return out;
  }

  // The goo over a plain background (`background`, no backdrop) into the target; RGBA8 rows bottom first.
  std::vector<unsigned char> render(const WaterParams& p, float weight, glm::vec3 background = glm::vec3(0.1f)) {
    beginOpaquePass(renderer_, glm::vec4(background, 1.0f));
    std::string error;
    const std::vector<glm::vec4> attr = attributes(weight);
    EXPECT_TRUE(
        uploadFluidMesh(renderer_, scene_.mesh.positions, scene_.mesh.normals, scene_.mesh.indices, attr, error))
        << error;
    drawFluid(renderer_, target_->fbo, scene_.camera, p);
    std::vector<unsigned char> px(static_cast<std::size_t>(kW) * kH * 4);
    glBindFramebuffer(GL_FRAMEBUFFER, target_->fbo);
    glReadPixels(0, 0, kW, kH, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return px;
  }

  // CPU rasterisation of the projected mesh at pixel centres, nearest triangle kept: per pixel the
  // v of the visible surface (screen-space interpolation of the vertices' v), NaN where uncovered.
  std::vector<float> visibleV() const {
    std::vector<float> v(static_cast<std::size_t>(kW) * kH, NAN), depth(v.size(), 2.0f);
    const glm::mat4 vp = scene_.camera.projection * scene_.camera.view;
    const auto& m = scene_.mesh;
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      glm::vec3 s[3];  // screen x, y (px) and window depth
      float tv[3];
      for (int c = 0; c < 3; ++c) {
        const glm::vec3 p = m.positions[m.indices[t + static_cast<std::size_t>(c)]];
        const glm::vec4 clip = vp * glm::vec4(p, 1.0f);
        const glm::vec3 ndc = glm::vec3(clip) / clip.w;
        s[c] = {(ndc.x * 0.5f + 0.5f) * kW, (ndc.y * 0.5f + 0.5f) * kH, ndc.z};
        tv[c] = vOf(p);
      }
      const float area = (s[1].x - s[0].x) * (s[2].y - s[0].y) - (s[1].y - s[0].y) * (s[2].x - s[0].x);
      if (std::abs(area) < 1e-9f) continue;
      const int x0 = std::max(0, static_cast<int>(std::min({s[0].x, s[1].x, s[2].x})));
      const int x1 = std::min(kW - 1, static_cast<int>(std::max({s[0].x, s[1].x, s[2].x})));
      const int y0 = std::max(0, static_cast<int>(std::min({s[0].y, s[1].y, s[2].y})));
      const int y1 = std::min(kH - 1, static_cast<int>(std::max({s[0].y, s[1].y, s[2].y})));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const float px = static_cast<float>(x) + 0.5f, py = static_cast<float>(y) + 0.5f;
          const float b1 = ((px - s[0].x) * (s[2].y - s[0].y) - (py - s[0].y) * (s[2].x - s[0].x)) / area;
          const float b2 = ((s[1].x - s[0].x) * (py - s[0].y) - (s[1].y - s[0].y) * (px - s[0].x)) / area;
          const float b0 = 1.0f - b1 - b2;
          if (b0 < 0.0f || b1 < 0.0f || b2 < 0.0f) continue;
          const float z = b0 * s[0].z + b1 * s[1].z + b2 * s[2].z;
          const std::size_t k = static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x);
          if (z >= depth[k]) continue;
          depth[k] = z;
          v[k] = b0 * tv[0] + b1 * tv[1] + b2 * tv[2];
        }
    }
    return v;
  }

  struct Agreement {
    std::size_t pixels = 0, expect_red = 0, agree = 0;
    double fraction() const { return pixels > 0 ? static_cast<double>(agree) / static_cast<double>(pixels) : 0.0; }
  };
  // Over covered pixels well inside a stripe (v not within 0.2 stripe widths of a boundary): how
  // often the pixel is redder than blue exactly where the texture's stripe at that v is red.
  Agreement agreement(const std::vector<unsigned char>& image, const std::vector<float>& v) const {
    Agreement a;
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (std::isnan(v[k])) continue;
      const float s = v[k] * kStripes;
      const float in_stripe = s - std::floor(s);
      if (in_stripe < 0.2f || in_stripe > 0.8f || s < 0.0f || s >= kStripes) continue;
      const bool expect_red = static_cast<int>(s) % 2 == 0;
      const bool red = image[k * 4] > image[k * 4 + 2];
      ++a.pixels;
      a.expect_red += expect_red;
      a.agree += red == expect_red;
    }
    return a;
  }

  GlContext ctx_;
  FluidRenderer renderer_;
  FluidScene scene_;
  GpuTexture texture_;
  float y_lo_ = 0.0f, y_hi_ = 0.0f;
  std::unique_ptr<ColourTarget> target_;  // made once the context exists
};

WaterParams gooParams(GLuint texture) {
  WaterParams p;
  p.style = FluidStyle::goo;
  p.goo_colour = {0.35f, 0.8f, 0.2f};
  p.goo_texture = texture;
  return p;
}

}  // namespace

// With (u, v) and full skin weight the goo takes the stripes of the texture where the mesh's v
// says: red where the stripe at the visible surface's v is red, blue where blue. Without the
// attributes, with weight 0, or without a texture it is plain (green) goo, which matches the
// stripes only by chance.
TEST_F(GooTextureTest, SkinFollowsTheMeshV) {
  const std::vector<float> v = visibleV();
  const WaterParams textured = gooParams(texture_.texture.id());
  const Agreement skin = agreement(render(textured, 1.0f), v);
  ASSERT_GT(skin.pixels, 800u);
  // Both stripe colours are in view, so agreeing by chance (a flat colour) scores at most the larger share.
  const double red_share = static_cast<double>(skin.expect_red) / static_cast<double>(skin.pixels);
  ASSERT_GT(red_share, 0.2);
  ASSERT_LT(red_share, 0.8);
  EXPECT_GT(skin.fraction(), 0.9) << skin.agree << " of " << skin.pixels;

  const Agreement no_uv = agreement(render(textured, -1.0f), v);
  const Agreement no_weight = agreement(render(textured, 0.0f), v);
  const Agreement no_texture = agreement(render(gooParams(0), 1.0f), v);
  for (const Agreement& flat : {no_uv, no_weight, no_texture})
    EXPECT_LE(flat.fraction(), std::max(red_share, 1.0 - red_share) + 0.02) << flat.agree << " of " << flat.pixels;
  std::printf(
      "[ metric ] goo skin: %.3f of %zu px match the stripe at their v (red share %.2f); plain: %.3f / %.3f / %.3f\n",
      skin.fraction(), skin.pixels, red_share, no_uv.fraction(), no_weight.fraction(), no_texture.fraction());
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// The goo is blended, not opaque: over a black and a white background the covered pixels differ
// where the body is thin (its edges), and not at all with full coverage forced.
TEST_F(GooTextureTest, GooIsTranslucentWhereThin) {
  const std::vector<float> v = visibleV();
  auto changed = [&](const WaterParams& p) {
    const auto dark = render(p, 1.0f, glm::vec3(0.0f));
    const auto light = render(p, 1.0f, glm::vec3(1.0f));
    std::size_t covered = 0, through = 0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (std::isnan(v[k])) continue;
      ++covered;
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(dark[k * 4 + c]) - int(light[k * 4 + c])));
      through += d > 20;
    }
    return std::pair{covered, through};
  };
  const auto [covered, through] = changed(gooParams(texture_.texture.id()));
  WaterParams opaque = gooParams(texture_.texture.id());
  opaque.goo_min_coverage = 1.0f;
  const auto [covered2, through_opaque] = changed(opaque);
  EXPECT_GT(through, covered / 50) << through << " of " << covered;
  EXPECT_LT(through, covered / 2) << "the thick body should hide the background";
  EXPECT_EQ(through_opaque, 0u);
  std::printf("[ metric ] goo translucency: %zu of %zu covered px show the background (> 20/255), %zu when opaque\n",
              through, covered, through_opaque);
}

// Bad attributes are refused with a message, as bad positions are.
TEST_F(GooTextureTest, BadAttributesAreRefused) {
  std::string error;
  std::vector<glm::vec4> attr = attributes(1.0f);
  attr.pop_back();
  EXPECT_FALSE(
      uploadFluidMesh(renderer_, scene_.mesh.positions, scene_.mesh.normals, scene_.mesh.indices, attr, error));
  EXPECT_NE(error.find("attributes"), std::string::npos) << error;
  attr = attributes(1.0f);
  attr[3].y = NAN;
  EXPECT_FALSE(
      uploadFluidMesh(renderer_, scene_.mesh.positions, scene_.mesh.normals, scene_.mesh.indices, attr, error));
  EXPECT_NE(error.find("vertex 3"), std::string::npos) << error;
}
