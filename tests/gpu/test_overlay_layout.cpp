// The game's overlay on llvmpipe (issue 35 item 4): compact by default (a thin strip and the key
// hint, taking no input), the full panels on F1 inside the display, apart, with no line cut at
// their right edge, at 1280x720 and 960x540 and across resizes between them, for every scene.
// Measured on ImGui's own window records after real frames drawn by the SDL2 + OpenGL3 backends.
#include "engine/platform/platform.hpp"
#include "engine/profile/profiler.hpp"
#include "engine/ui/overlay.hpp"
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"
#include "game/scene_panel.hpp"
#include "game/world/world.hpp"

#include <SDL.h>
#include <gtest/gtest.h>
#include <imgui.h>
#include <imgui_internal.h>

#include <cstdlib>
#include <string>

namespace {

struct Size {
  int width, height;
};

// A context with an SDL window the ImGui backend reads its display size from.
class OverlayLayoutTest : public ::testing::Test {
 protected:
  void SetUp() override {
    setenv("SDL_VIDEODRIVER", "offscreen", 1);
    engine::PlatformDesc desc;
    desc.headless = true;
    desc.width = 1280;
    desc.height = 720;
    std::string error;
    ASSERT_TRUE(engine::createPlatform(desc, platform_, error)) << error;
    ASSERT_TRUE(engine::createOverlay(platform_, overlay_, error)) << error;
    // Frames with every phase timed and some flagged, as a running game has them.
    for (int frame = 0; frame < 200; ++frame) {
      engine::beginFrame(profiler_);
      for (int p = 0; p < engine::kPhaseCount; ++p)
        engine::addPhaseTime(profiler_, static_cast<engine::Phase>(p), 0.5 + 0.1 * p + 0.01 * (frame % 7));
      if (frame % 50 == 0) engine::flagFrame(profiler_);
      engine::endFrame(profiler_);
    }
  }
  void TearDown() override {
    engine::destroyOverlay(overlay_);
    engine::destroyPlatform(platform_);
  }

  void buildScene(const char* name) {
    game::SceneConfig scene;
    const game::SceneStatus st = game::loadSceneFile(game::scenesDir() / (std::string(name) + ".json"), scene);
    ASSERT_TRUE(st.ok()) << st.error;
    std::string error;
    ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world_, error)) << error;
    for (int step = 0; step < 5; ++step) game::stepWorld(world_, nullptr);  // statuses with values
  }

  // Draws `frames` overlay frames at `size` (ImGui settles auto-sized windows over two frames).
  void drawFrames(Size size, int frames) {
    SDL_SetWindowSize(platform_.window, size.width, size.height);
    for (int f = 0; f < frames; ++f) {
      engine::beginOverlayFrame(overlay_);
      game::drawGameOverlay(world_, overlay_, profiler_, "llvmpipe (LLVM 15.0.6, 256 bits)");
      engine::endOverlayFrame(overlay_);
    }
    const ImVec2 display = ImGui::GetIO().DisplaySize;
    ASSERT_EQ(static_cast<int>(display.x), size.width);
    ASSERT_EQ(static_cast<int>(display.y), size.height);
  }

  engine::Platform platform_;
  engine::Overlay overlay_;
  engine::Profiler profiler_;
  game::World world_;
};

ImRect windowRect(const ImGuiWindow& window) {
  return ImRect(window.Pos.x, window.Pos.y, window.Pos.x + window.Size.x, window.Pos.y + window.Size.y);
}

// The window was drawn this frame, lies inside the display and no line runs past its right edge
// (a cut line widens the window's contents beyond its content region).
void expectFits(const char* name, Size size, bool may_scroll) {
  SCOPED_TRACE(std::string(name) + " at " + std::to_string(size.width) + "x" + std::to_string(size.height));
  const ImGuiWindow* window = ImGui::FindWindowByName(name);
  ASSERT_NE(window, nullptr);
  ASSERT_TRUE(window->WasActive);
  const ImRect rect = windowRect(*window);
  EXPECT_GE(rect.Min.x, 0.0f);
  EXPECT_GE(rect.Min.y, 0.0f);
  EXPECT_LE(rect.Max.x, static_cast<float>(size.width));
  EXPECT_LE(rect.Max.y, static_cast<float>(size.height));
  // 1 px of slack: ImGui rounds a full-width widget's edge to whole pixels.
  EXPECT_LE(window->ContentSize.x, window->ContentRegionRect.GetWidth() + 1.0f)
      << "contents " << window->ContentSize.x << " px wide in a region of " << window->ContentRegionRect.GetWidth();
  if (!may_scroll) {
    EXPECT_EQ(window->ScrollMax.y, 0.0f) << "contents " << window->ContentSize.y << " px tall";
  }
}

constexpr const char* kFramePanel = "Frame (F1: hide panels)";
constexpr const char* kScenePanel = "Scene";

void expectFullPanelsFit(Size size) {
  expectFits(kFramePanel, size, false);
  expectFits(kScenePanel, size, true);  // the knobs scroll; its lines still may not be cut
  const ImGuiWindow* frame = ImGui::FindWindowByName(kFramePanel);
  const ImGuiWindow* scene = ImGui::FindWindowByName(kScenePanel);
  ASSERT_TRUE(frame != nullptr && scene != nullptr);
  EXPECT_FALSE(windowRect(*frame).Overlaps(windowRect(*scene)))
      << "frame panel x " << frame->Pos.x << ".." << frame->Pos.x + frame->Size.x << ", scene panel x "
      << scene->Pos.x << ".." << scene->Pos.x + scene->Size.x;
}

constexpr Size kSizes[] = {{1280, 720}, {960, 540}, {1280, 720}, {960, 540}};

TEST_F(OverlayLayoutTest, CompactByDefaultAThinStripAndTheKeysTakingNoInput) {
  buildScene("fountain");
  EXPECT_EQ(overlay_.mode, engine::OverlayMode::compact);
  for (const Size size : kSizes) {
    drawFrames(size, 3);
    expectFits("##frame_strip", size, false);
    expectFits("##key_hint", size, false);
    const ImGuiWindow* strip = ImGui::FindWindowByName("##frame_strip");
    const ImGuiWindow* hint = ImGui::FindWindowByName("##key_hint");
    ASSERT_TRUE(strip != nullptr && hint != nullptr);
    // Thin: one line of text each.
    const float one_line = ImGui::GetFrameHeight() + 2.0f * ImGui::GetStyle().WindowPadding.y;
    EXPECT_LE(strip->Size.y, one_line);
    EXPECT_LE(hint->Size.y, one_line);
    EXPECT_LE(strip->Size.x, 0.5f * static_cast<float>(size.width));
    EXPECT_TRUE(strip->Flags & ImGuiWindowFlags_NoInputs);
    EXPECT_TRUE(hint->Flags & ImGuiWindowFlags_NoInputs);
    EXPECT_FALSE(engine::overlayWantsMouse(overlay_));
    EXPECT_EQ(ImGui::FindWindowByName(kScenePanel), nullptr) << "the full panels appeared in compact mode";
  }
  EXPECT_NE(game::keyHint(world_).find("G charge"), std::string::npos) << "the fountain lists explosives";
}

TEST_F(OverlayLayoutTest, F1CyclesCompactFullHidden) {
  EXPECT_EQ(engine::nextOverlayMode(engine::OverlayMode::compact), engine::OverlayMode::full);
  EXPECT_EQ(engine::nextOverlayMode(engine::OverlayMode::full), engine::OverlayMode::hidden);
  EXPECT_EQ(engine::nextOverlayMode(engine::OverlayMode::hidden), engine::OverlayMode::compact);
}

class FullPanelsTest : public OverlayLayoutTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(FullPanelsTest, FitApartAndUncutAtBothSizesAndAcrossResizes) {
  buildScene(GetParam());
  overlay_.mode = engine::OverlayMode::full;
  for (const Size size : kSizes) {
    drawFrames(size, 3);
    expectFullPanelsFit(size);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, FullPanelsTest, ::testing::Values("fountain", "crate_yard", "blob_monster"));

// The panel's layout for any display from 640x360 up: inside it, apart, each at least 200 px.
TEST(OverlayLayout, PanelsStayInsideAndApartForAnyDisplay) {
  for (float width = 640.0f; width <= 3840.0f; width += 160.0f) {
    for (float height = 360.0f; height <= 2160.0f; height += 180.0f) {
      const engine::OverlayLayout layout = engine::overlayLayout(width, height, true);
      EXPECT_GE(layout.frame.x, 0.0f);
      EXPECT_LT(layout.frame.x + layout.frame.width, layout.game.x) << width << "x" << height;
      EXPECT_LE(layout.game.x + layout.game.width, width);
      EXPECT_GE(layout.frame.width, 200.0f);
      EXPECT_GE(layout.game.width, 200.0f);
      EXPECT_LE(layout.game.y + layout.game.max_height, height);
    }
  }
}

}  // namespace
