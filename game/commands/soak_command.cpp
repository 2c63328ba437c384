// `fluiddemo soak`: every scene (or the named ones) for a long stretch of game time at a tiny
// headless viewport, one fixed step per frame and every frame rendered, with seeded throws of
// crates and explosives; fails on an abort, a NaN/inf or solver/mesher error, a particle or crate
// inside a collider, memory that grows after warm-up, or a pool level that drifts (game/soak_monitor.hpp,
// game/soak_checks.hpp). --no-render: the same steps, throws and checks without GL, meshing or rendering.
//
// Each scene runs in a child process (this executable again, `soak --scene S --in-process`): an
// assertion or a crash kills only that child, and the parent still names the scene and the step it
// died in (the child writes each step's number to a pipe before running it) and goes on with the
// other scenes. --in-process runs the scenes in this process instead (for a debugger).
#include "game/commands.hpp"
#include "game/commands/cli_parse.hpp"
#include "game/paths.hpp"
#include "game/run_scene.hpp"
#include "game/soak_monitor.hpp"
#include "game/world/world.hpp"

#include <CLI/CLI.hpp>

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace game {
namespace {

struct SoakOptions {
  double seconds = 60.0;
  std::uint32_t seed = 1;
  int width = 160;
  int height = 90;
  double throw_every = 2.0;
  double explosive_share = 0.25;
  std::vector<std::string> overrides;
  bool no_memory_check = false;
  bool no_render = false;  // simulation only: no GL, meshing or rendering
  int progress_fd = -1;
  std::uint64_t abort_at_step = 0;  // testing aid: abort() before this step (0 = never)
  std::size_t leak_per_step = 0;    // testing aid: bytes allocated, touched and kept every step
};

// The scene with the --set overrides applied; false + error naming the file/key.
bool loadSoakScene(const std::string& name, const std::vector<std::string>& overrides, SceneConfig& out,
                   std::string& error) {
  std::filesystem::path path;
  SceneStatus status = resolveScene(name, scenesDir(), path);
  if (status.ok()) status = loadSceneFile(path, out);
  for (std::size_t i = 0; status.ok() && i < overrides.size(); ++i) status = applyOverride(out, overrides[i]);
  error = status.error;
  return status.ok();
}

// The scene's line: passed or failed, with the monitor's summary. Returns 0 (passed) or 1.
int reportSoak(const std::string& name, SoakMonitor& monitor) {
  finishSoak(monitor);
  if (monitor.failure.empty() && monitor.stats.steps < monitor.desc.steps) {
    monitor.failure =
        "ran " + std::to_string(monitor.stats.steps) + " of " + std::to_string(monitor.desc.steps) + " steps";
  }
  const bool passed = monitor.failure.empty();
  std::printf("soak %-12s %s  %s\n", name.c_str(), passed ? "ok  " : "FAIL", soakSummary(monitor).c_str());
  if (!passed) std::printf("soak %-12s FAIL  %s\n", name.c_str(), monitor.failure.c_str());
  std::fflush(stdout);
  return passed ? 0 : 1;
}

// --no-render: the same steps, throws and checks as the rendered soak without GL, meshing or the
// render (as `replay --no-render`), for runs of an hour of game time and more, which rendering every
// frame on a machine without a GPU would stretch to several hours.
int soakSimulationOnly(const std::string& name, const SceneConfig& scene, const SoakOptions& o, SoakMonitor& monitor,
                       std::uint64_t report_every) {
  World world;
  std::string error;
  if (!buildWorld(scene, contentDir(), world, error)) {
    std::printf("soak %-12s FAIL  %s\n", name.c_str(), error.c_str());
    return 1;
  }
  using Clock = std::chrono::steady_clock;
  Clock::duration stepping{}, checking{};
  for (bool go_on = true; go_on;) {
    const std::uint64_t step = world.steps;
    soakBeforeStep(monitor, world, step);
    if (step + 1 == o.abort_at_step) std::abort();
    const Clock::time_point start = Clock::now();
    stepWorld(world, nullptr);
    const Clock::time_point stepped = Clock::now();
    go_on = soakAfterFrame(monitor, world);
    stepping += stepped - start;
    checking += Clock::now() - stepped;
    if (report_every > 0 && world.steps % report_every == 0) {
      std::printf("soak %-12s ...   %s\n", name.c_str(), soakSummary(monitor).c_str());
      std::fflush(stdout);
    }
  }
  const double frames = static_cast<double>(std::max<std::uint64_t>(world.steps, 1));
  std::printf("soak %-12s time  simulation %.2f ms per step, checks %.2f ms per step (mean, wall clock)\n",
              name.c_str(), std::chrono::duration<double, std::milli>(stepping).count() / frames,
              std::chrono::duration<double, std::milli>(checking).count() / frames);
  return reportSoak(name, monitor);
}

// One scene in this process. Returns 0 (passed) or 1 (failed), after printing the scene's line.
int soakInProcess(const std::string& name, const SoakOptions& o) {
  SceneConfig scene;
  std::string error;
  if (!loadSoakScene(name, o.overrides, scene, error)) {
    std::printf("soak %-12s FAIL  %s\n", name.c_str(), error.c_str());
    return 1;
  }
  const double step_seconds = 1.0 / scene.scene.number("step_hz");
  SoakDesc desc;
  desc.steps = static_cast<std::uint64_t>(std::llround(o.seconds / step_seconds));
  desc.seed = o.seed;
  desc.throws.mean_interval_s = o.throw_every;
  desc.throws.explosive_share = o.explosive_share;
  desc.progress_fd = o.progress_fd;
  desc.check_memory = !o.no_memory_check;
  SoakMonitor monitor = makeSoakMonitor(desc, step_seconds);
  // Long runs (10 min of play and more) say how far they are every tenth of the way.
  const std::uint64_t report_every = desc.steps >= 36000 ? desc.steps / 10 : 0;

  if (o.no_render) return soakSimulationOnly(name, scene, o, monitor, report_every);

  RunOptions options;
  options.headless = true;
  options.width = o.width;
  options.height = o.height;
  options.show_ui = false;
  options.fixed_frame_time = true;  // one fixed step per frame, whatever the machine's speed
  options.frames = static_cast<int>(std::min<std::uint64_t>(desc.steps, 2000000000ull));
  std::vector<std::vector<char>> leaked;  // --leak-per-step: kept until the run ends
  // One fixed step per frame (fixed_frame_time), so the frame's hook runs before that step.
  options.hooks.before_steps = [&](FrameInput& input) {
    const std::uint64_t step = input.world.steps;
    soakBeforeStep(monitor, input.world, step);
    if (step + 1 == o.abort_at_step) std::abort();  // what a failed assertion does (tests the report)
    if (o.leak_per_step > 0) {
      // Every page written through a volatile pointer: resident, and not optimised away.
      volatile char* bytes = leaked.emplace_back(o.leak_per_step).data();
      for (std::size_t i = 0; i < o.leak_per_step; i += 512) bytes[i] = 1;
    }
  };
  options.hooks.after_frame = [&](const FrameResult& frame) {
    const World& world = frame.world;
    const bool go_on = soakAfterFrame(monitor, world);
    if (report_every > 0 && world.steps % report_every == 0) {
      std::printf("soak %-12s ...   %s\n", name.c_str(), soakSummary(monitor).c_str());
      std::fflush(stdout);
    }
    return go_on;
  };
  RunReport report;
  if (runScene(scene, options, report, error) != 0) {
    std::printf("soak %-12s FAIL  %s\n", name.c_str(), error.c_str());
    return 1;
  }
  if (report.gl_errors > 0 && monitor.failure.empty())
    monitor.failure = std::to_string(report.gl_errors) + " GL errors";
  return reportSoak(name, monitor);
}

// Runs `soak --scene NAME --in-process --progress-fd N ...` as a child and waits for it. Returns
// 0/1 from a child that finished; a child that died is a failure, named with its last step.
int soakInChild(const std::string& name, const SoakOptions& o) {
  char exe[4096];
  const ssize_t length = ::readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  int fds[2];
  if (length <= 0 || ::pipe2(fds, O_CLOEXEC) != 0) {
    std::printf("soak %-12s FAIL  cannot start a child process: %s\n", name.c_str(), std::strerror(errno));
    return 1;
  }
  exe[length] = '\0';
  std::vector<std::string> words = {exe,
                                    "soak",
                                    "--scene",
                                    name,
                                    "--in-process",
                                    "--seconds",
                                    std::to_string(o.seconds),
                                    "--seed",
                                    std::to_string(o.seed),
                                    "--width",
                                    std::to_string(o.width),
                                    "--height",
                                    std::to_string(o.height),
                                    "--throw-every",
                                    std::to_string(o.throw_every),
                                    "--explosive-share",
                                    std::to_string(o.explosive_share),
                                    "--progress-fd",
                                    std::to_string(fds[1])};
  for (const std::string& assignment : o.overrides) words.insert(words.end(), {"--set", assignment});
  if (o.no_memory_check) words.emplace_back("--no-memory-check");
  if (o.no_render) words.emplace_back("--no-render");
  if (o.abort_at_step > 0) words.insert(words.end(), {"--abort-at-step", std::to_string(o.abort_at_step)});
  if (o.leak_per_step > 0) words.insert(words.end(), {"--leak-per-step", std::to_string(o.leak_per_step)});
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    // The write end survives exec; the read end closes. The child dies with its parent (no
    // orphaned hour-long run, or hung one, after a ctest timeout kills the parent).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::fcntl(fds[1], F_SETFD, 0);
    ::execv(argv[0], argv.data());
    _exit(127);
  }
  ::close(fds[1]);
  if (pid < 0) {
    ::close(fds[0]);
    std::printf("soak %-12s FAIL  fork: %s\n", name.c_str(), std::strerror(errno));
    return 1;
  }
  // Read progress until the child closes the pipe (exits or dies); keep the last full number.
  std::string pending;
  unsigned long long last_step = 0;
  char buffer[4096];
  for (;;) {
    const ssize_t got = ::read(fds[0], buffer, sizeof(buffer));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    pending.append(buffer, static_cast<std::size_t>(got));
    const std::size_t end = pending.rfind('\n');
    if (end == std::string::npos) continue;
    const std::string lines = pending.substr(0, end);
    const std::size_t begin = lines.rfind('\n');
    last_step = std::strtoull(lines.c_str() + (begin == std::string::npos ? 0 : begin + 1), nullptr, 10);
    pending.erase(0, end + 1);
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) {
    if (WEXITSTATUS(status) == 127) std::printf("soak %-12s FAIL  cannot run %s\n", name.c_str(), exe);
    return WEXITSTATUS(status) == 0 ? 0 : 1;
  }
  const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  if (last_step == 0) {
    std::printf("soak %-12s FAIL  killed by signal %d (%s) before the first step (loading or start-up)\n", name.c_str(),
                signal, strsignal(signal));
  } else {
    std::printf(
        "soak %-12s FAIL  killed by signal %d (%s) in frame %llu: its simulation step %llu, the meshing or "
        "the render after it (the child's own message, if any, is above)\n",
        name.c_str(), signal, strsignal(signal), last_step, last_step);
  }
  return 1;
}

}  // namespace

int soakCommand(const Args& args) {
  CLI::App app{
      "Run scenes headless for a long stretch of game time with crate and explosive throws; fail on an abort, a "
      "NaN, a particle inside a collider or memory growth.",
      "fluiddemo soak"};
  SoakOptions o;
  std::vector<std::string> scene_names;
  bool all = false, in_process = false;
  auto* scene_option = app.add_option("--scene", scene_names, "scene name or path (repeatable)");
  app.add_flag("--all", all, "every scene in content/scenes (the default)")->excludes(scene_option);
  app.add_option("--seconds", o.seconds, "game time per scene, s (60 = 3,600 steps at 60 Hz)")
      ->check(numberIn(0.1, 1e6))
      ->capture_default_str();
  app.add_option("--seed", o.seed, "seed of the throws")->capture_default_str();
  app.add_option("--width", o.width, "framebuffer width")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--height", o.height, "framebuffer height")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--throw-every", o.throw_every, "mean seconds between throws (uniform in 0.5x..1.5x; 0 = none)")
      ->check(numberIn(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--explosive-share", o.explosive_share,
                 "chance that a throw is a fused explosive instead of a crate (0 = crates only)")
      ->check(numberIn(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--set", o.overrides, "override a scene parameter: section.key=value (repeatable)");
  app.add_flag("--in-process", in_process, "run the scenes in this process (no child per scene)");
  app.add_flag("--no-memory-check", o.no_memory_check,
               "print the resident set but do not judge it (sanitizer builds, whose allocators keep freed memory)");
  app.add_flag("--no-render", o.no_render,
               "simulation only: the same steps, throws and checks without GL, meshing or rendering (runs of an "
               "hour of game time and more)");
  app.add_option("--progress-fd", o.progress_fd, "(internal) write each step's number to this fd")->group("");
  app.add_option("--abort-at-step", o.abort_at_step, "(testing) abort before step N, to check the crash report")
      ->group("");
  app.add_option("--leak-per-step", o.leak_per_step,
                 "(testing) keep N more bytes every step, to check the memory check")
      ->group("");
  if (int code = parseCommandLine(app, "soak", args); code >= 0) return code;

  std::vector<std::string> scenes = scene_names;
  if (all || scenes.empty()) {
    scenes = availableScenes(scenesDir());
    if (scenes.empty()) {
      std::fprintf(stderr, "fluiddemo soak: no scenes in %s\n", scenesDir().string().c_str());
      return 1;
    }
  }
  // Every scene and --set checked before the first run, with play's exit codes: a scene that is
  // missing or bad fails (1), a --set the command line got wrong is a usage error (2).
  for (const std::string& name : scenes) {
    std::filesystem::path path;
    SceneConfig scene;
    SceneStatus status = resolveScene(name, scenesDir(), path);
    if (status.ok()) status = loadSceneFile(path, scene);
    const bool scene_ok = status.ok();
    for (std::size_t i = 0; status.ok() && i < o.overrides.size(); ++i) status = applyOverride(scene, o.overrides[i]);
    if (!status.ok()) {
      std::fprintf(stderr, "fluiddemo soak: %s\n", status.error.c_str());
      return scene_ok ? 2 : 1;
    }
  }
  int failures = 0;
  for (const std::string& name : scenes) failures += in_process ? soakInProcess(name, o) : soakInChild(name, o);
  // A child's one scene is summed up by its parent.
  if (o.progress_fd < 0)
    std::printf("soak: %zu passed, %d failed\n", scenes.size() - static_cast<std::size_t>(failures), failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace game
