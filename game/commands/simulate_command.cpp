// `fluiddemo simulate`: runs an SPH scene from fluid/sph without a window, writes particle
// frames (DIR/frame_00000.xyz at time i/F, "x y z id" by ascending id) and a CSV of per-step
// statistics (DIR/stats.csv); a progress line on stderr when that is a terminal.
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"

#include "fluid/io/particle_io.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

namespace game {
namespace {

std::string keyHelp() {
  std::string text = "\nScene keys for --set key=value (default: meaning):\n";
  for (const std::string& scene : fluid::sphSceneNames()) {
    std::vector<fluid::SphSceneKey> keys;
    fluid::sphSceneKeys(scene, keys);
    text += "  " + scene + ":\n";
    for (const auto& k : keys) {
      char line[256];
      char value[32];
      if (k.value < 0.0f)  // computed from the scene (fluid::sphSceneKeys)
        std::snprintf(value, sizeof value, "auto");
      else
        std::snprintf(value, sizeof value, "%g", static_cast<double>(k.value));
      std::snprintf(line, sizeof line, "    %-20s %-10s %s\n", k.name.c_str(), value, k.help.c_str());
      text += line;
    }
  }
  return text;
}

// --out before the run: the folder made and writable, and no earlier run's stats.csv or frames
// replaced without --force (the frame writer would otherwise refuse only at the first frame).
int checkSimulateOutputs(const std::filesystem::path& dir, bool force) {
  if (const int code = prepareOutputFolder("simulate", "--out", dir); code >= 0) return code;
  if (const int code = checkOutputFile("simulate", "--out", dir / "stats.csv", force); code >= 0) return code;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("frame_") && name.ends_with(".xyz"))
      if (const int code = checkOutputFile("simulate", "--out", entry.path(), force); code >= 0) return code;
  }
  return -1;
}

}  // namespace

int simulateCommand(const Args& args) {
  CLI::App app{
      "Run an SPH scene without a window: frames DIR/frame_00000.xyz (time i/F, one particle per line "
      "as x y z id, by ascending id) and per-step statistics DIR/stats.csv. On a terminal, a progress line "
      "goes to stderr.",
      "fluiddemo simulate"};
  std::string scene_name;
  double seconds = 0.0;
  std::string solver_name = "dfsph";
  std::string out_dir;
  double fps = 30.0;
  std::vector<std::string> sets;
  bool force = false;
  int threads = 0;
  app.add_option("--scene", scene_name, "dambreak|column|fountain|dambreak_box")->required();
  app.add_option("--seconds", seconds, "simulated time (s), > 0")->required();
  app.add_option("--solver", solver_name, "dfsph (default) or wcsph");
  app.add_option("--out", out_dir,
                 "output directory for frames and stats.csv (created if missing); without it nothing is written "
                 "and only the summary is printed (a line on stdout says so)");
  app.add_option("--fps", fps, "frames per simulated second (default 30)");
  app.add_option("--set", sets, "scene/solver parameter override key=value (repeatable)");
  app.add_flag("--force", force, "replace existing frame and stats files in --out");
  app.add_option("--threads", threads,
                 "most threads a parallel loop runs on (default 0: all cores); the same cap in TSan builds "
                 "(fluid/core/parallel.hpp)");
  app.footer(keyHelp());

  if (const int code = parseCommandLine(app, "simulate", args); code >= 0) return code;
  if (!(seconds > 0.0) || !std::isfinite(seconds) || seconds > 1e6) {
    std::fprintf(stderr, "fluiddemo simulate: --seconds must be in (0, 1e6], got %g\n", seconds);
    return 2;
  }
  if (!(fps > 0.0) || !std::isfinite(fps) || fps > 10000.0) {
    std::fprintf(stderr, "fluiddemo simulate: --fps must be in (0, 10000], got %g\n", fps);
    return 2;
  }
  if (threads < 0) {
    std::fprintf(stderr, "fluiddemo simulate: --threads must be >= 0 (0 = all cores), got %d\n", threads);
    return 2;
  }
  fluid::SphSolverKind solver;
  if (!fluid::parseSphSolver(solver_name, solver)) {
    std::fprintf(stderr, "fluiddemo simulate: unknown --solver '%s' (expected dfsph or wcsph)\n", solver_name.c_str());
    return 2;
  }
  std::vector<std::pair<std::string, std::string>> overrides;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "fluiddemo simulate: --set expects key=value, got '%s'\n", s.c_str());
      return 2;
    }
    overrides.emplace_back(s.substr(0, eq), s.substr(eq + 1));
  }
  // oneTBB's max_allowed_parallelism caps both builds' loops: oneTBB's workers, and the
  // std::threads fluid::par starts instead in TSan builds.
  std::optional<tbb::global_control> limit;
  if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));

  auto scene = std::make_unique<fluid::SphScene>();
  if (fluid::SphStatus st = fluid::makeSphScene(scene_name, solver, overrides, *scene); !st.ok()) {
    std::fprintf(stderr, "fluiddemo simulate: %s\n", st.error.c_str());
    return 2;
  }
  fluid::SphWorld& world = scene->world;

  const fluid::OverwritePolicy policy = force ? fluid::OverwritePolicy::replace : fluid::OverwritePolicy::refuse;
  std::ofstream csv;
  const std::filesystem::path dir(out_dir);
  if (out_dir.empty()) {
    // The summary alone is what a timing run wants (docs/sph.md); say so rather than stay silent.
    std::printf("simulate: no --out: frames and stats.csv are not written, only this summary\n");
  } else {
    if (const int code = checkSimulateOutputs(dir, force); code >= 0) return code;
    const auto csv_path = dir / "stats.csv";
    csv.open(csv_path);
    if (!csv) {
      std::fprintf(stderr, "fluiddemo simulate: cannot write %s: %s\n", csv_path.c_str(), std::strerror(errno));
      return 1;
    }
    csv << "step,time_s,dt_s,density_iterations,divergence_iterations,avg_density_error,p99_density_error,"
           "max_density_error,"
           "kinetic_energy_J,ms_per_step,neighbor_ms,particles,collisions,surge_front_m\n";
  }

  // Frames list the particles by id ("x y z id", ascending id): the solver re-sorts its store by
  // grid cell every step, so storage order would not let a particle be followed from frame to frame.
  fluid::ParticlePositions frame;
  // The world takes the solver's own steps whatever --fps is (fluid::advanceSphUntil: no step is
  // cut to land on a frame time, so the output rate does not change the physics); a frame shows
  // the state at its own time, interpolated within the step that passed it (sphPositionsAt).
  std::vector<glm::vec3> at_time;
  std::vector<std::uint32_t> order, ids;
  auto writeFrame = [&](long index, double time) -> bool {
    if (out_dir.empty()) return true;
    fluid::sphPositionsAt(world, time, at_time);
    const auto& id = world.particles.id;
    order.resize(id.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return id[a] < id[b]; });
    frame.clear();
    ids.clear();
    for (const std::uint32_t i : order) {
      frame.push_back(at_time[i]);
      ids.push_back(id[i]);
    }
    char name[64];
    std::snprintf(name, sizeof name, "frame_%05ld.xyz", index);
    const fluid::IoStatus st = fluid::writeParticleXyzWithIds(dir / name, frame, ids, policy);
    if (!st.ok())
      std::fprintf(stderr, "fluiddemo simulate: %s%s\n", st.error.c_str(), force ? "" : " (pass --force to replace)");
    return st.ok();
  };

  std::uint64_t steps = 0;
  double sum_dt = 0.0, sum_err = 0.0, sum_ms = 0.0, sum_nb_ms = 0.0, frame_err_sum = 0.0;
  float max_err = 0.0f, p99_err = 0.0f;
  long frames_measured = 0;
  bool first_step_of_frame = false;
  auto onStep = [&](const fluid::SphStepStats& s) {
    ++steps;
    sum_dt += s.dt;
    sum_err += s.avg_density_error;
    sum_ms += s.step_ms;
    sum_nb_ms += s.neighbor_ms;
    max_err = std::max(max_err, s.max_density_error);
    p99_err = std::max(p99_err, s.p99_density_error);
    if (first_step_of_frame) {  // its density error describes the frame's state
      frame_err_sum += s.avg_density_error;
      ++frames_measured;
      first_step_of_frame = false;
    }
    if (csv.is_open()) {
      char line[512];
      std::snprintf(line, sizeof line, "%llu,%.9g,%.9g,%d,%d,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%zu,%zu,%.9g\n",
                    static_cast<unsigned long long>(world.step_count), world.time, static_cast<double>(s.dt),
                    s.density_iterations, s.divergence_iterations, static_cast<double>(s.avg_density_error),
                    static_cast<double>(s.p99_density_error), static_cast<double>(s.max_density_error),
                    static_cast<double>(s.kinetic_energy), static_cast<double>(s.step_ms),
                    static_cast<double>(s.neighbor_ms), s.particles, s.collisions,
                    static_cast<double>(fluid::sphSurgeFront(world)));
      csv << line;
    }
  };

  // A progress line on a terminal (stderr), at most four times a second; nothing when piped.
  const bool progress = isatty(fileno(stderr)) != 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto last_report = t0;
  auto report = [&](bool final_line) {
    const auto now = std::chrono::steady_clock::now();
    if (!progress || (!final_line && now - last_report < std::chrono::milliseconds(250))) return;
    last_report = now;
    std::fprintf(stderr, "\rsimulate: %.3f of %.3f s simulated, %llu steps, %.1f s wall%s", world.time, seconds,
                 static_cast<unsigned long long>(steps), std::chrono::duration<double>(now - t0).count(),
                 final_line ? "\n" : "");
    std::fflush(stderr);
  };
  auto advanceTo = [&](double t) -> bool {
    first_step_of_frame = true;
    const fluid::SphStatus st = fluid::advanceSphUntil(world, t, [&](const fluid::SphStepStats& s) {
      onStep(s);
      report(false);
    });
    if (!st.ok()) std::fprintf(stderr, "%sfluiddemo simulate: %s\n", progress ? "\n" : "", st.error.c_str());
    return st.ok();
  };
  const long last_frame = static_cast<long>(std::floor(seconds * fps + 1e-9));
  for (long i = 0; i <= last_frame; ++i) {
    const double time = std::min(static_cast<double>(i) / fps, seconds);
    if (!advanceTo(time) || !writeFrame(i, time)) return 1;
  }
  if (!advanceTo(seconds)) return 1;
  report(true);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("scene %s, solver %s, %zu particles, %.3f s simulated in %llu steps\n", scene_name.c_str(),
              fluid::sphSolverName(solver), world.particles.size(), world.time, static_cast<unsigned long long>(steps));
  if (steps > 0) {
    std::printf("mean dt %.3f ms, ms per step %.2f (neighbour search %.2f), compute s per simulated s %.2f\n",
                1e3 * sum_dt / steps, sum_ms / steps, sum_nb_ms / steps, sum_ms / 1e3 / world.time);
    std::printf(
        "mean density error %.4f %% (steps), %.4f %% (frames), p99 %.3f %% (worst step), max %.3f %%; "
        "wall time %.2f s\n",
        100.0 * sum_err / steps, frames_measured ? 100.0 * frame_err_sum / frames_measured : 0.0, 100.0 * p99_err,
        100.0 * max_err, wall);
  }
  if (scene->column_width > 0.0f)
    std::printf("surge front %.4f m = %.3f a\n", fluid::sphSurgeFront(world),
                fluid::sphSurgeFront(world) / scene->column_width);
  return 0;
}

}  // namespace game
