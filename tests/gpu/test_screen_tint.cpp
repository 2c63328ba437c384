// The frame's screen tint pass (engine/render/frame.hpp, pass 4): a colour blended over the whole
// frame by its alpha, the scene's alpha kept at 1, and no pass at all at alpha 0. On llvmpipe.
#include "engine/render/frame.hpp"
#include "engine/render/renderer.hpp"
#include "gl_test_context.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace {

class ScreenTintTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gputest::createContext(ctx_);
    ASSERT_TRUE(ctx_.ok()) << ctx_.error;
    std::string error;
    passes_.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
    ASSERT_TRUE(engine::createRenderer(passes_.shader_dir, 48, 32, renderer_, error, 256)) << error;
    view_.view = glm::lookAt(glm::vec3(0, 1, 4), glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0));
    view_.projection = glm::perspective(glm::radians(60.0f), 1.5f, 0.05f, 100.0f);
    view_.eye = glm::vec3(0, 1, 4);
  }
  void TearDown() override {
    engine::releaseFramePasses(passes_);
    renderer_ = engine::Renderer{};
    gputest::destroyContext(ctx_);
  }
  std::vector<std::uint8_t> frame(glm::vec4 tint) {
    engine::FrameBatches batches;
    batches.screen_tint = tint;
    engine::renderFrame(renderer_, passes_, view_, engine::Lighting{}, batches);
    std::vector<std::uint8_t> rgba;
    engine::readSceneRgba(renderer_, rgba);
    EXPECT_EQ(renderer_.errors.count, 0) << renderer_.errors.first;
    return rgba;
  }

  gputest::GlContext ctx_;
  engine::Renderer renderer_;
  engine::FramePasses passes_;
  engine::FrameView view_;
};

TEST_F(ScreenTintTest, BlendsItsColourOverEveryPixelByItsAlpha) {
  const std::vector<std::uint8_t> sky = frame(glm::vec4(0.0f));
  const std::vector<std::uint8_t> tinted = frame(glm::vec4(0.9f, 0.1f, 0.05f, 0.4f));
  ASSERT_EQ(sky.size(), tinted.size());
  for (std::size_t p = 0; p < sky.size(); p += 4) {
    // out = 0.4 tint + 0.6 scene, per channel, in the 8-bit target (1 unit of rounding).
    const float expected_r = 0.4f * 0.9f * 255.0f + 0.6f * sky[p];
    const float expected_g = 0.4f * 0.1f * 255.0f + 0.6f * sky[p + 1];
    ASSERT_NEAR(tinted[p], expected_r, 1.5f) << "pixel " << p / 4;
    ASSERT_NEAR(tinted[p + 1], expected_g, 1.5f) << "pixel " << p / 4;
    ASSERT_EQ(tinted[p + 3], 255) << "the scene's alpha stays 1";
  }
}

TEST_F(ScreenTintTest, NoTintLeavesTheFrameAsItWas) {
  const std::vector<std::uint8_t> first = frame(glm::vec4(0.0f));
  const std::vector<std::uint8_t> again = frame(glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));  // a colour at alpha 0
  EXPECT_EQ(first, again);
}

}  // namespace
