// Scene files: valid ones load with defaults filled in; every malformed one gives an error
// that names the file, the key path and the value.
#include "game/paths.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/sph_fluid.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace {

using game::SceneConfig;

// The first effect of the schema and its first numeric parameter, so these tests follow
// the schema instead of hard-coding one effect's keys.
struct NumericParam {
  std::string effect;
  const game::ParamSpec* spec = nullptr;
};

NumericParam firstNumericEffectParam() {
  for (const game::SectionSpec& section : game::sceneSchema()) {
    if (!section.is_effect) continue;
    for (const game::ParamSpec& param : section.params) {
      if (param.type == game::ParamType::number) return {std::string(section.name), &param};
    }
  }
  return {};
}

::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

TEST(SceneConfig, MinimalSceneTakesSchemaDefaults) {
  SceneConfig scene;
  const auto status = game::parseSceneText(R"({"effects": {}})", "min.json", scene);
  ASSERT_TRUE(status.ok()) << status.error;
  EXPECT_TRUE(scene.effects.empty());
  EXPECT_DOUBLE_EQ(scene.scene.number("step_hz"), 60.0);
  EXPECT_EQ(scene.scene.integer("substeps"), 1);
  EXPECT_DOUBLE_EQ(scene.camera.number("fov_degrees"), 60.0);
}

TEST(SceneConfig, ListedEffectIsPresentAndOthersAreNot) {
  const NumericParam param = firstNumericEffectParam();
  ASSERT_NE(param.spec, nullptr);
  SceneConfig scene;
  const std::string text = R"({"effects": {")" + param.effect + R"(": {}}, "scene": {"substeps": 3}})";
  ASSERT_TRUE(game::parseSceneText(text, "one.json", scene).ok());
  EXPECT_TRUE(scene.has(param.effect));
  EXPECT_EQ(scene.effects.size(), 1u);
  EXPECT_EQ(scene.scene.integer("substeps"), 3);
  for (const game::SectionSpec& section : game::sceneSchema()) {
    if (section.is_effect && section.name != param.effect) {
      EXPECT_FALSE(scene.has(section.name)) << section.name;
    }
  }
  EXPECT_DOUBLE_EQ(scene.effect(param.effect)->number(param.spec->key), param.spec->default_value.number);
}

TEST(SceneConfig, TruncatedJsonNamesFileAndPosition) {
  SceneConfig scene;
  const auto status = game::parseSceneText(R"({"effects": {"rigid)", "cut.json", scene);
  EXPECT_TRUE(contains(status.error, "cut.json: invalid JSON"));
  EXPECT_TRUE(contains(status.error, "line 1"));
}

// nlohmann's whole message: where, what it was parsing and what it expected (it was cut to 60 bytes:
// "parse error at line 2, column 26: syntax error while parsing...").
TEST(SceneConfig, SyntaxErrorKeepsTheWholeMessage) {
  SceneConfig scene;
  const auto status =
      game::parseSceneText("{\n \"scene\": {\"step_hz\": 60,, },\n \"effects\": {}\n}\n", "s.json", scene);
  EXPECT_EQ(
      status.error,
      "s.json: invalid JSON: parse error at line 2, column 26: syntax error while parsing object key - unexpected "
      "','; expected string literal");
  // A quoted token is still cut (an unclosed string would quote the rest of the file), the rest is kept.
  const auto cut = game::parseSceneText("{\"effects\": {\"" + std::string(100, 'x'), "c.json", scene);
  EXPECT_TRUE(contains(cut.error, "last read: '\"xxxxxxxx")) << cut.error;
  EXPECT_TRUE(contains(cut.error, "...'")) << cut.error;
}

// nlohmann keeps the last of two equal keys without a word: the scene would lose a value silently.
TEST(SceneConfig, DuplicateKeyIsAnErrorNamingIt) {
  SceneConfig scene;
  auto status = game::parseSceneText(R"({"effects": {}, "scene": {"step_hz": 60, "step_hz": 30}})", "d.json", scene);
  EXPECT_EQ(status.error, "d.json: scene.step_hz: the key appears twice (one value would be lost)");
  status = game::parseSceneText(R"({"effects": {}, "effects": {}})", "d.json", scene);
  EXPECT_EQ(status.error, "d.json: effects: the key appears twice (one value would be lost)");
  // Equal keys in different objects, or inside arrays of objects, are not duplicates.
  status = game::parseSceneText(R"({"effects": {}, "scene": {"seed": 1}, "camera": {"position": [0, 1, 2]}})",
                                "ok.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
}

TEST(SceneConfig, WrongTypeNamesKeyAndValue) {
  SceneConfig scene;
  auto status = game::parseSceneText(R"({"effects": {}, "scene": {"substeps": "two"}})", "t.json", scene);
  EXPECT_EQ(status.error, R"(t.json: scene.substeps: expected an integer (got "two"))");
  status = game::parseSceneText(R"({"effects": {}, "scene": {"substeps": 2.5}})", "t.json", scene);
  EXPECT_EQ(status.error, "t.json: scene.substeps: value 2.5 is not an integer");
  status = game::parseSceneText(R"({"effects": {}, "camera": {"position": [1, 2]}})", "t.json", scene);
  EXPECT_EQ(status.error, "t.json: camera.position: expected an array of 3 numbers (got [1,2])");
  status = game::parseSceneText(R"({"effects": []})", "t.json", scene);
  EXPECT_TRUE(contains(status.error, "t.json: effects: expected an object of effects"));
  status = game::parseSceneText(R"([1, 2])", "t.json", scene);
  EXPECT_TRUE(contains(status.error, "t.json: the top level must be an object"));
}

TEST(SceneConfig, UnknownEffectSectionAndKeyAreErrors) {
  SceneConfig scene;
  auto status = game::parseSceneText(R"({"effects": {"warp_drive": {}}})", "u.json", scene);
  EXPECT_TRUE(contains(status.error, "u.json: effects.warp_drive: unknown effect (known: "));
  status = game::parseSceneText(R"({"effects": {}, "lighting": {}})", "u.json", scene);
  EXPECT_TRUE(contains(status.error, "u.json: lighting: unknown top-level key"));
  status = game::parseSceneText(R"({"effects": {}, "camera": {"zoom": 2}})", "u.json", scene);
  EXPECT_TRUE(contains(status.error, "u.json: camera.zoom: unknown key (known: position"));
  status = game::parseSceneText(R"({"camera": {}})", "u.json", scene);
  EXPECT_TRUE(contains(status.error, "u.json: effects: missing"));
}

TEST(SceneConfig, OutOfRangeValueNamesRange) {
  SceneConfig scene;
  auto status = game::parseSceneText(R"({"effects": {}, "camera": {"fov_degrees": 500}})", "r.json", scene);
  EXPECT_EQ(status.error, "r.json: camera.fov_degrees: value 500 is out of range [20, 120]");
  const NumericParam param = firstNumericEffectParam();
  ASSERT_NE(param.spec, nullptr);
  const std::string text =
      R"({"effects": {")" + param.effect + R"(": {")" + std::string(param.spec->key) + R"(": -1e30}}})";
  status = game::parseSceneText(text, "r.json", scene);
  EXPECT_TRUE(contains(status.error, "r.json: effects." + param.effect + "." + std::string(param.spec->key) +
                                         ": value -1e+30 is out of range"));
  EXPECT_TRUE(scene.effects.empty());  // a failed parse leaves nothing half-filled
}

TEST(SceneConfig, OverridesUseTheSameValidation) {
  SceneConfig scene;
  ASSERT_TRUE(game::parseSceneText(R"({"effects": {}})", "o.json", scene).ok());
  scene.name = "o";
  EXPECT_TRUE(game::applyOverride(scene, "camera.fov_degrees=75").ok());
  EXPECT_DOUBLE_EQ(scene.camera.number("fov_degrees"), 75.0);
  EXPECT_TRUE(game::applyOverride(scene, "camera.position=1,2,3").ok());
  EXPECT_EQ(scene.camera.vec3("position"), glm::vec3(1, 2, 3));
  EXPECT_TRUE(game::applyOverride(scene, "camera.position=[4,5,6]").ok());
  EXPECT_EQ(scene.camera.vec3("position"), glm::vec3(4, 5, 6));

  EXPECT_EQ(game::applyOverride(scene, "camera.fov_degrees=500").error,
            "--set camera.fov_degrees=500: value 500 is out of range [20, 120]");
  EXPECT_TRUE(contains(game::applyOverride(scene, "camera.fov=70").error, "unknown key 'fov'"));
  EXPECT_TRUE(contains(game::applyOverride(scene, "warp.speed=1").error, "unknown section 'warp'"));
  EXPECT_TRUE(contains(game::applyOverride(scene, "camera.fov_degrees").error, "expected section.key=value"));
  EXPECT_TRUE(contains(game::applyOverride(scene, "camera.fov_degrees=abc").error, "cannot parse value 'abc'"));
  EXPECT_TRUE(contains(game::applyOverride(scene, "scene.substeps=1.5").error, "is not an integer"));
  const NumericParam param = firstNumericEffectParam();
  ASSERT_NE(param.spec, nullptr);
  EXPECT_TRUE(contains(game::applyOverride(scene, param.effect + "." + std::string(param.spec->key) + "=1").error,
                       "effect '" + param.effect + "' is not used by scene 'o'"));
  EXPECT_DOUBLE_EQ(scene.camera.number("fov_degrees"), 75.0);  // failed overrides change nothing
}

// fluid::SphParams::warm_start (DFSPH 2017 §4.3) as the optional sph_fluid key `warm_start`:
// default on, false accepted from a file and from --set, anything but a JSON boolean refused
// with file, key path and value.
TEST(SceneConfig, SphFluidWarmStartKey) {
  SceneConfig scene;
  ASSERT_TRUE(game::parseSceneText(R"({"effects": {"sph_fluid": {}}})", "w.json", scene).ok());
  EXPECT_TRUE(scene.effect("sph_fluid")->boolean("warm_start"));
  auto status = game::parseSceneText(R"({"effects": {"sph_fluid": {"warm_start": false}}})", "w.json", scene);
  ASSERT_TRUE(status.ok()) << status.error;
  EXPECT_FALSE(scene.effect("sph_fluid")->boolean("warm_start"));
  scene.name = "w";
  EXPECT_TRUE(game::applyOverride(scene, "sph_fluid.warm_start=true").ok());
  EXPECT_TRUE(scene.effect("sph_fluid")->boolean("warm_start"));

  status = game::parseSceneText(R"({"effects": {"sph_fluid": {"warm_start": 0}}})", "bad.json", scene);
  EXPECT_EQ(status.error, "bad.json: effects.sph_fluid.warm_start: expected true or false (got 0)");
  EXPECT_TRUE(scene.effects.empty());
  status = game::parseSceneText(R"({"effects": {"sph_fluid": {"warm_start": "off"}}})", "bad.json", scene);
  EXPECT_EQ(status.error, R"(bad.json: effects.sph_fluid.warm_start: expected true or false (got "off"))");

  ASSERT_TRUE(game::parseSceneText(R"({"effects": {"sph_fluid": {}}})", "w.json", scene).ok());
  scene.name = "w";
  EXPECT_TRUE(contains(game::applyOverride(scene, "sph_fluid.warm_start=2").error,
                       "--set sph_fluid.warm_start=2: expected true or false"));
  EXPECT_TRUE(scene.effect("sph_fluid")->boolean("warm_start"));  // a refused override changes nothing
}

// The key reaches the solver: sph_fluid's parameters and the SphWorld built from them.
TEST(SceneConfig, SphFluidWarmStartReachesTheSolver) {
  for (const bool on : {false, true}) {
    SceneConfig scene;
    const std::string text = std::string(R"({"effects": {"sph_fluid": {"max_particles": 50, "warm_start": )") +
                             (on ? "true" : "false") + "}}}";
    ASSERT_TRUE(game::parseSceneText(text, "w.json", scene).ok());
    game::SphFluidParams params;
    std::string error;
    ASSERT_TRUE(game::sphParamsFrom(*scene.effect("sph_fluid"), params, error)) << error;
    EXPECT_EQ(params.warm_start, on);
    game::SphFluid fluid;
    std::shared_ptr<const game::LevelColliders> colliders;
    ASSERT_TRUE(game::ensureFountainColliders(game::contentDir(), colliders, error)) << error;
    ASSERT_TRUE(game::initSphFluid(fluid, params, game::FountainGeometry{}, colliders, glm::vec3(0, -9.81f, 0), error))
        << error;
    EXPECT_EQ(fluid.world.params.warm_start, on);
  }
}

TEST(SceneConfig, FilesLoadAndMissingOnesAreNamed) {
  const auto dir = std::filesystem::temp_directory_path() / "fluiddemo_scene_test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "good.json") << R"({"description": "x", "effects": {}})";
  std::ofstream(dir / "bad.json") << R"({"effects": {}, "scene": {"seed": -4}})";
  SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile(dir / "good.json", scene).ok());
  EXPECT_EQ(scene.name, "good");
  EXPECT_EQ(scene.description, "x");
  EXPECT_TRUE(contains(game::loadSceneFile(dir / "bad.json", scene).error, "bad.json: scene.seed: value -4"));
  EXPECT_TRUE(contains(game::loadSceneFile(dir / "none.json", scene).error, "none.json: scene file not found"));

  std::filesystem::path resolved;
  EXPECT_TRUE(game::resolveScene("good", dir, resolved).ok());
  EXPECT_EQ(resolved, dir / "good.json");
  EXPECT_EQ(game::resolveScene("nope", dir, resolved).error, "unknown scene 'nope' (available: bad, good)");
}

TEST(SceneConfig, EveryShippedSceneIsValid) {
  const auto names = game::availableScenes(game::scenesDir());
  ASSERT_FALSE(names.empty()) << "no scenes in " << game::scenesDir();
  for (const std::string& name : names) {
    SceneConfig scene;
    const auto status = game::loadSceneFile(game::scenesDir() / (name + ".json"), scene);
    EXPECT_TRUE(status.ok()) << status.error;
  }
}

}  // namespace
