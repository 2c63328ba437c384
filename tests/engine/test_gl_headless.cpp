// Headless GL through SDL's offscreen driver (EGL pbuffer on llvmpipe in CI): tiny viewports,
// few frames.
#include "engine/gl/gl.hpp"
#include "engine/platform/platform.hpp"
#include "engine/render/renderer.hpp"
#include "game/run_scene.hpp"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cstdlib>
#include <fstream>

namespace {

namespace fs = std::filesystem;

const fs::path kShaders = fs::path(FLUIDDEMO_SOURCE_DIR) / "shaders";

class Headless : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { setenv("SDL_VIDEODRIVER", "offscreen", 0); }
  void SetUp() override {
    engine::PlatformDesc desc;
    desc.width = 96;
    desc.height = 64;
    desc.headless = true;
    std::string error;
    ASSERT_TRUE(engine::createPlatform(desc, platform_, error)) << error;
    dir_ = fs::temp_directory_path() /
           ("fluiddemo_gl_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    engine::destroyPlatform(platform_);
    fs::remove_all(dir_);
  }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  engine::Platform platform_;
  fs::path dir_;
};

TEST_F(Headless, ContextIsCoreProfile33OrBetter) {
  EXPECT_GE(platform_.gl_major * 10 + platform_.gl_minor, 33);
  EXPECT_FALSE(platform_.gl_renderer.empty());
  GLint profile = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
}

TEST_F(Headless, CompileErrorNamesFileAndLine) {
  write("ok.vert", "#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n");
  write("bad.frag", "#version 330 core\nout vec4 c;\nvoid main() {\n  c = vec4(undeclared_thing);\n}\n");
  std::string error;
  engine::GlProgram program = engine::loadProgram(dir_, "ok.vert", "bad.frag", error);
  EXPECT_FALSE(program);
  EXPECT_NE(error.find((dir_ / "bad.frag").string() + ":4"), std::string::npos) << error;
  EXPECT_NE(error.find("undeclared_thing"), std::string::npos) << error;
}

TEST_F(Headless, LinkErrorAndMissingFileAreNamed) {
  // One uniform declared with two different types in the two stages: a link error.
  write("ok.vert", "#version 330 core\nuniform float u_x;\nvoid main() { gl_Position = vec4(u_x); }\n");
  write("needs_input.frag", "#version 330 core\nuniform vec3 u_x;\nout vec4 c;\nvoid main() { c = vec4(u_x, 1.0); }\n");
  std::string error;
  EXPECT_FALSE(engine::loadProgram(dir_, "ok.vert", "needs_input.frag", error));
  EXPECT_NE(error.find("needs_input.frag (link)"), std::string::npos) << error;
  EXPECT_FALSE(engine::loadProgram(dir_, "ok.vert", "absent.frag", error));
  EXPECT_NE(error.find("absent.frag: cannot open shader file"), std::string::npos) << error;
}

TEST_F(Headless, RendererDrawsSkyAndMeshesWithoutGlErrors) {
  engine::Renderer renderer;
  std::string error;
  ASSERT_TRUE(engine::createRenderer(kShaders, 80, 60, renderer, error)) << error;
  engine::MeshData quad;
  quad.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  quad.normals.assign(4, glm::vec3(0, 1, 0));
  quad.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  quad.indices = {0, 2, 1, 0, 3, 2};
  const engine::GpuMesh mesh = engine::uploadMesh(quad);
  engine::DrawItem item;
  item.mesh = &mesh;
  item.tint = {1.0f, 0.1f, 0.1f};
  item.model = glm::scale(glm::mat4(1.0f), glm::vec3(3.0f));
  engine::FrameView view;
  view.eye = {0, 2, 4};
  view.view = glm::lookAt(view.eye, glm::vec3(0), glm::vec3(0, 1, 0));
  view.projection = glm::perspective(1.0f, 80.0f / 60.0f, 0.1f, 100.0f);
  engine::renderScene(renderer, view, {}, std::span(&item, 1), true);
  std::vector<std::uint8_t> drawn, blank;
  engine::readSceneRgba(renderer, drawn);
  engine::renderScene(renderer, view, {}, {}, false);
  engine::readSceneRgba(renderer, blank);
  EXPECT_EQ(renderer.errors.count, 0) << renderer.errors.first;
  ASSERT_EQ(drawn.size(), 80u * 60u * 4u);
  // Nothing drawn = the clear colour everywhere.
  for (std::size_t i = 0; i < blank.size(); i += 4) ASSERT_EQ(blank[i] + blank[i + 1] + blank[i + 2], 0) << i;
  // Top rows are sky (blue dominant); the centre is the red quad.
  const std::size_t top = ((59u * 80u) + 40u) * 4u;
  EXPECT_GT(drawn[top + 2], drawn[top + 0]);
  const std::size_t bottom = ((8u * 80u) + 40u) * 4u;
  EXPECT_GT(drawn[bottom + 0], drawn[bottom + 1] + 30);
}

TEST_F(Headless, MissingShaderDirectoryIsAnErrorNotACrash) {
  engine::Renderer renderer;
  std::string error;
  EXPECT_FALSE(engine::createRenderer(dir_ / "no_shaders", 32, 32, renderer, error));
  EXPECT_NE(error.find("sky.vert"), std::string::npos) << error;
}

game::SceneConfig fountainScene() {
  game::SceneConfig scene;
  const game::SceneStatus status =
      game::loadSceneFile(fs::path(FLUIDDEMO_SOURCE_DIR) / "content" / "scenes" / "fountain.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

TEST(RunScene, FixedFrameTimeIsOneStepPerFrameAndDeterministic) {
  setenv("SDL_VIDEODRIVER", "offscreen", 0);
  // llvmpipe's threaded rasteriser resolves exact depth ties between overlapping sprites in
  // run-dependent order (measured: a few pixels of the jet flip between runs); without
  // rasteriser threads it is bit-exact, so the comparison below tests our determinism only.
  setenv("LP_NUM_THREADS", "0", 1);
  const game::SceneConfig scene = fountainScene();
  game::RunOptions options;
  options.headless = true;
  options.width = 96;
  options.height = 64;
  options.frames = 12;
  options.show_ui = false;
  options.capture_last_frame = true;
  options.fixed_frame_time = true;
  game::RunReport first, second;
  std::string error;
  ASSERT_EQ(game::runScene(scene, options, first, error), 0) << error;
  ASSERT_EQ(game::runScene(scene, options, second, error), 0) << error;
  EXPECT_EQ(first.frames_rendered, 12);
  EXPECT_EQ(first.simulation_steps, 12u);
  EXPECT_EQ(first.gl_errors, 0);
  EXPECT_EQ(first.nonfinite_state, "");
  EXPECT_EQ(first.systems_constructed,
            (std::vector<std::string>{"rigid_bodies", "explosives", "sph_fluid", "sprite_particles", "fluid_surface",
                                      "gulls", "audio"}));
  ASSERT_EQ(first.last_frame_rgba.size(), 96u * 64u * 4u);
  EXPECT_EQ(first.blank_frame_rgba.size(), first.last_frame_rgba.size());
  EXPECT_NE(first.last_frame_rgba, first.blank_frame_rgba);
  EXPECT_EQ(first.last_frame_rgba, second.last_frame_rgba) << "same inputs must render the same frame";
  unsetenv("LP_NUM_THREADS");
  ASSERT_EQ(first.phases.size(), 6u);
  // Every phase runs once per frame (the fountain lists fluid_surface, so meshing runs too).
  for (const game::PhaseTiming& phase : first.phases) EXPECT_EQ(phase.samples, 12u) << phase.phase;
}

TEST(RunScene, ScreenshotIsWrittenAndUnlistedEffectsDoNotRun) {
  setenv("SDL_VIDEODRIVER", "offscreen", 0);
  game::SceneConfig scene;
  ASSERT_TRUE(game::parseSceneText(R"({"effects": {"sprite_particles": {}}})", "inline.json", scene).ok());
  const fs::path shot = fs::temp_directory_path() / "fluiddemo_gl_runscene_shot.png";
  fs::remove(shot);
  game::RunOptions options;
  options.headless = true;
  options.width = 64;
  options.height = 64;
  options.frames = 3;
  options.show_ui = true;  // the overlay path runs too
  options.fixed_frame_time = true;
  options.screenshot = shot;
  game::RunReport report;
  std::string error;
  ASSERT_EQ(game::runScene(scene, options, report, error), 0) << error;
  EXPECT_TRUE(fs::exists(shot));
  EXPECT_GT(fs::file_size(shot), 100u);
  fs::remove(shot);
  EXPECT_EQ(report.systems_constructed, std::vector<std::string>{"sprite_particles"});
  EXPECT_EQ(report.gl_errors, 0);
  for (const game::PhaseTiming& phase : report.phases) {
    if (phase.phase == "physics") {
      EXPECT_EQ(phase.samples, 0u);
    }
  }
}

TEST(RunScene, BadShaderDirectoryFailsCleanly) {
  setenv("SDL_VIDEODRIVER", "offscreen", 0);
  setenv("FLUIDDEMO_SHADER_DIR", "/nonexistent/shaders", 1);
  game::RunOptions options;
  options.headless = true;
  options.width = 64;
  options.height = 64;
  options.frames = 1;
  game::RunReport report;
  std::string error;
  EXPECT_NE(game::runScene(fountainScene(), options, report, error), 0);
  unsetenv("FLUIDDEMO_SHADER_DIR");
  EXPECT_NE(error.find("/nonexistent/shaders/sky.vert"), std::string::npos) << error;
}

}  // namespace
