// `fluiddemo play` and `fluiddemo smoke`: command-line front ends of runScene().
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"
#include "game/paths.hpp"
#include "game/replay/recorder.hpp"
#include "game/run_scene.hpp"
#include "game/smoke_checks.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace game {
namespace {

struct SceneChoice {
  SceneConfig config;
  std::string error;
  int exit_code = 0;  // 1: the scene is missing or its file is bad; 2: a --set the command line got wrong
};

SceneChoice loadScene(const std::string& name_or_path, const std::vector<std::string>& overrides) {
  SceneChoice choice;
  std::filesystem::path path;
  SceneStatus status = resolveScene(name_or_path, scenesDir(), path);
  if (status.ok()) status = loadSceneFile(path, choice.config);
  if (!status.ok()) {
    choice.error = status.error;
    choice.exit_code = 1;
    return choice;
  }
  for (const std::string& assignment : overrides) {
    if (status = applyOverride(choice.config, assignment); !status.ok()) {
      choice.error = status.error;
      choice.exit_code = 2;
      return choice;
    }
  }
  return choice;
}

constexpr int kDefaultHeadlessFrames = 240;

}  // namespace

int playCommand(const Args& args) {
  CLI::App app{"Play a scene: a window when a display exists, otherwise headless.", "fluiddemo play"};
  std::string scene_name = "fountain";
  std::vector<std::string> overrides;
  RunOptions options;
  bool no_ui = false;
  std::string screenshot;
  bool force = false;
  app.add_option("scene", scene_name, "scene name in content/scenes or path to a scene .json")->capture_default_str();
  app.add_flag("--headless", options.headless, "no window: render offscreen (automatic without a display)");
  app.add_option("--frames", options.frames, "render N frames then exit (0 = until closed; headless default 240)")
      ->check(CLI::Range(0, 10000000));
  app.add_option("--width", options.width, "framebuffer width")->check(CLI::Range(64, 8192))->capture_default_str();
  app.add_option("--height", options.height, "framebuffer height")->check(CLI::Range(64, 8192))->capture_default_str();
  app.add_option("--screenshot", screenshot, "write the last frame to this .png file (an existing file needs --force)");
  app.add_flag("--force", force, "replace the --screenshot or --record file if it exists");
  app.add_option("--set", overrides, "override a scene parameter: section.key=value (repeatable)");
  app.add_flag("--no-ui", no_ui, "start with the overlay hidden");
  std::string record;
  app.add_option("--record", record, "record every input as a replay file (docs/replay.md), flushed as it goes");
  if (int code = parseCommandLine(app, "play", args); code >= 0) return code;
  if (!screenshot.empty()) {
    if (const int code = checkPngOutput("play", "--screenshot", screenshot, force); code >= 0) return code;
  }
  if (!record.empty()) {
    if (const int code = checkOutputFile("play", "--record", record, force); code >= 0) return code;
  }

  SceneChoice choice = loadScene(scene_name, overrides);
  if (!choice.error.empty()) {
    std::fprintf(stderr, "fluiddemo play: %s\n", choice.error.c_str());
    return choice.exit_code;
  }
  if (!displayAvailable()) options.headless = true;
  if (options.headless && options.frames == 0) options.frames = kDefaultHeadlessFrames;
  // Headless frames take as long as the software rasterizer needs; feeding the loop one fixed
  // step per frame keeps a headless run deterministic and independent of the machine's speed.
  options.fixed_frame_time = options.headless;
  options.screenshot = screenshot;
  options.show_ui = !no_ui;

  RunReport report;
  std::string error;
  ReplayRecorder recorder;
  if (!record.empty()) {
    if (!startRecording(record, force, scene_name, choice.config, overrides, recorder, error)) {
      std::fprintf(stderr, "fluiddemo play: --record %s\n", error.c_str());
      return 1;  // checked above: what is left is the file system's answer (checkOutputFile)
    }
    attachRecorder(recorder, options.hooks);
  }
  const int code = runScene(choice.config, options, report, error);
  if (!record.empty()) {
    std::string record_error;
    if (!finishRecording(recorder, record_error)) std::fprintf(stderr, "fluiddemo play: %s\n", record_error.c_str());
    if (!recorder.message.empty()) std::fprintf(stderr, "fluiddemo play: --record: %s\n", recorder.message.c_str());
    std::printf("recorded: %s (%llu steps)\n", record.c_str(), static_cast<unsigned long long>(recorder.last_step));
  }
  if (code != 0) {
    std::fprintf(stderr, "fluiddemo play: %s\n", error.c_str());
    return code;
  }
  printRunSummary(stdout, choice.config, options, report);
  if (!report.nonfinite_state.empty()) {
    std::fprintf(stderr, "fluiddemo play: non-finite simulation state: %s\n", report.nonfinite_state.c_str());
    return 1;
  }
  if (!screenshot.empty()) std::printf("screenshot: %s\n", screenshot.c_str());
  return 0;
}

int smokeCommand(const Args& args) {
  CLI::App app{"Run scenes headless for a few frames and check every frame for failure.", "fluiddemo smoke"};
  std::string scene_name;
  bool all = false;
  int frames = 30;
  int width = 160;
  int height = 120;
  std::string out_dir;
  auto* scene_option = app.add_option("--scene", scene_name, "one scene name or path");
  app.add_flag("--all", all, "every scene in content/scenes")->excludes(scene_option);
  app.add_option("--frames", frames, "frames per scene")->check(CLI::Range(1, 100000))->capture_default_str();
  app.add_option("--width", width, "framebuffer width")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--height", height, "framebuffer height")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--out", out_dir, "write each scene's last frame to DIR/<scene>.png (replacing it)");
  if (int code = parseCommandLine(app, "smoke", args); code >= 0) return code;

  std::vector<std::string> scenes;
  if (all || scene_name.empty()) {
    scenes = availableScenes(scenesDir());
    if (scenes.empty()) {
      std::fprintf(stderr, "fluiddemo smoke: no scenes in %s\n", scenesDir().string().c_str());
      return 1;
    }
  } else {
    scenes.push_back(scene_name);
  }
  if (!out_dir.empty()) {
    if (const int code = prepareOutputFolder("smoke", "--out", out_dir); code >= 0) return code;
  }

  int failures = 0;
  for (const std::string& name : scenes) {
    SceneChoice choice = loadScene(name, {});
    std::string failure = choice.error;
    RunReport report;
    if (failure.empty()) {
      RunOptions options;
      options.headless = true;
      options.frames = frames;
      options.width = width;
      options.height = height;
      options.show_ui = false;
      options.capture_last_frame = true;
      options.fixed_frame_time = true;
      if (!out_dir.empty()) options.screenshot = std::filesystem::path(out_dir) / (choice.config.name + ".png");
      std::string error;
      if (runScene(choice.config, options, report, error) != 0) {
        failure = error;
      } else if (report.gl_errors > 0) {
        failure = std::to_string(report.gl_errors) + " GL errors";
      } else if (!report.nonfinite_state.empty()) {
        failure = "non-finite simulation state: " + report.nonfinite_state;
      } else if (report.runtime_failures > 0) {
        failure = std::to_string(report.runtime_failures) + " run-time failures, first: " + report.first_failure;
      } else if (report.frames_rendered != frames) {
        failure = "rendered " + std::to_string(report.frames_rendered) + " of " + std::to_string(frames) + " frames";
      } else {
        const FrameCheck check =
            checkFrame(report.last_frame_rgba, report.blank_frame_rgba, report.frame_width, report.frame_height);
        failure = check.failure;
      }
    }
    if (failure.empty()) {
      std::string systems;
      for (const std::string& system : report.systems_constructed) systems += (systems.empty() ? "" : ",") + system;
      std::printf("smoke %-16s ok    %d frames, %.2f ms/frame, systems: %s\n", name.c_str(), report.frames_rendered,
                  report.mean_frame_ms, systems.c_str());
    } else {
      ++failures;
      std::printf("smoke %-16s FAIL  %s\n", name.c_str(), failure.c_str());
    }
  }
  std::printf("smoke: %zu passed, %d failed\n", scenes.size() - static_cast<std::size_t>(failures), failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace game
