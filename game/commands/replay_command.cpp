// `fluiddemo replay FILE`: plays a replay file (game/replay) one fixed step per rendered frame,
// checks its checkpoints, prints per-phase percentiles and writes the per-frame CSV and its plot.
// `fluiddemo replay --compare A.csv B.csv`: per-phase p50/p95 ratios B/A of two such CSVs.
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"
#include "engine/audio/synth.hpp"
#include "game/paths.hpp"
#include "game/replay/frame_times.hpp"
#include "game/replay/replay_file.hpp"
#include "game/replay/replay_runner.hpp"
#include "game/run_scene.hpp"

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

namespace game {
namespace {

struct ReplayArgs {
  std::string file;
  ReplayRunOptions run;
  int threads = 0;
  std::string csv, png;
  int plot_width = 1200, plot_height = 600;
  std::vector<std::string> screenshot_at;
  std::vector<std::string> compare;
  std::vector<std::string> sets;  // render-only --set overrides
  bool update_hashes = false, force = false, no_ui = false;
  std::string wav;        // --wav: the audio effect's sound, rendered offline
  bool wav_mono = false;  // --wav-mono: one channel (L+R)/2
};

int usageError(const std::string& message) {
  std::fprintf(stderr, "fluiddemo replay: %s\n", message.c_str());
  return 2;
}

// The Python with matplotlib: FLUIDDEMO_PYTHON, else Debian's /usr/bin/python3 (where
// python3-matplotlib installs), else python3 from PATH.
std::string pythonCommand() {
  if (const char* python = std::getenv("FLUIDDEMO_PYTHON"); python != nullptr && *python != '\0') return python;
  if (std::filesystem::exists("/usr/bin/python3")) return "/usr/bin/python3";
  return "python3";
}

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

int plot(const std::filesystem::path& csv, const ReplayArgs& args, const std::string& title) {
  const std::string command = shellQuote(pythonCommand()) + " " +
                              shellQuote((projectRoot() / "scripts" / "plot_frame_times.py").string()) + " " +
                              shellQuote(csv.string()) + " " + shellQuote(args.png) + " --width " +
                              std::to_string(args.plot_width) + " --height " + std::to_string(args.plot_height) +
                              " --title " + shellQuote(title) + (args.force ? " --force" : "");
  const int status = std::system(command.c_str());
  if (status != 0) {
    std::fprintf(stderr, "fluiddemo replay: plotting failed (%s)\n", command.c_str());
    return 1;
  }
  std::printf("plot: %s\n", args.png.c_str());
  return 0;
}

int compareCommand(const ReplayArgs& args) {
  std::vector<FrameRow> a, b;
  std::string error;
  if (!readFrameCsv(args.compare[0], a, error) || !readFrameCsv(args.compare[1], b, error)) {
    std::fprintf(stderr, "fluiddemo replay --compare: %s\n", error.c_str());
    return 1;
  }
  printComparison(stdout, args.compare[0], a, args.compare[1], b);
  return 0;
}

// Checks the flags against each other and the output files against --force. -1 = go on.
int checkArgs(ReplayArgs& args) {
  if (!args.compare.empty()) {
    if (!args.file.empty()) return usageError("--compare takes two CSV files and no replay FILE");
    return -1;
  }
  if (args.file.empty()) return usageError("a replay FILE is required (or --compare A.csv B.csv)");
  if (args.update_hashes && !args.force)
    return usageError("--update-hashes rewrites the replay file's checkpoints: it needs --force too");
  if (args.update_hashes && args.run.frames > 0)
    return usageError("--update-hashes needs the whole replay: drop --frames");
  if (args.threads < 0)
    return usageError("--threads must be >= 0 (0 = all cores), got " + std::to_string(args.threads));
  if (!args.csv.empty()) {
    if (const int code = checkOutputFile("replay", "--csv", args.csv, args.force); code >= 0) return code;
  }
  if (!args.png.empty()) {
    if (const int code = checkPngOutput("replay", "--png", args.png, args.force); code >= 0) return code;
  }
  for (const std::string& assignment : args.sets) {
    std::string error;
    if (!renderOnlyOverride(assignment, error)) return usageError(error);
    args.run.extra_overrides.push_back(assignment);
  }
  for (const std::string& spec : args.screenshot_at) {
    const std::size_t colon = spec.find(':');
    std::uint64_t step = 0;
    const char* end = spec.data() + (colon == std::string::npos ? spec.size() : colon);
    const auto parsed = std::from_chars(spec.data(), end, step);
    if (colon == std::string::npos || colon + 1 == spec.size() || parsed.ec != std::errc() || parsed.ptr != end ||
        step == 0)
      return usageError("--screenshot-at expects STEP:FILE.png with STEP >= 1, got '" + spec + "'");
    const std::string path = spec.substr(colon + 1);
    if (const int code = checkPngOutput("replay", "--screenshot-at", path, args.force); code >= 0) return code;
    args.run.screenshots.emplace_back(step, path);
  }
  return -1;
}

// --png plots with Python and matplotlib after the run: without them the run would be wasted.
int checkPlotter(const ReplayArgs& args) {
  if (args.png.empty()) return -1;
  const std::string command = shellQuote(pythonCommand()) + " -c 'import matplotlib' >/dev/null 2>&1";
  if (std::system(command.c_str()) == 0) return -1;
  std::fprintf(stderr,
               "fluiddemo replay: --png needs %s with matplotlib (Debian: python3-matplotlib; or set "
               "FLUIDDEMO_PYTHON)\n",
               pythonCommand().c_str());
  return 1;
}

// A --screenshot-at step the run never reaches would write nothing and still exit 0.
int checkScreenshotSteps(const ReplayArgs& args, const ReplayFile& replay) {
  const std::uint64_t last = args.run.frames > 0
                                 ? std::min<std::uint64_t>(static_cast<std::uint64_t>(args.run.frames), replay.end_step)
                                 : replay.end_step;
  for (const auto& [step, path] : args.run.screenshots) {
    if (step > last)
      return usageError("--screenshot-at " + std::to_string(step) + ":" + path.string() + ": the run ends at step " +
                        std::to_string(last) + (args.run.frames > 0 && last < replay.end_step ? " (--frames)" : "") +
                        ", so that frame is never drawn");
  }
  return -1;
}

// --update-hashes writes FILE.tmp beside the replay and renames it over the file.
int checkReplayWritable(const ReplayArgs& args) {
  if (!args.update_hashes) return -1;
  return checkOutputFile("replay", "--update-hashes", args.file + ".tmp", true);
}

int writeOutputs(const ReplayArgs& args, const ReplayFile& replay, const ReplayResult& result) {
  std::string error;
  std::filesystem::path csv = args.csv;
  if (csv.empty() && !args.png.empty())
    csv = std::filesystem::temp_directory_path() / ("fluiddemo_replay_" + std::to_string(::getpid()) + ".csv");
  if (!csv.empty()) {
    if (!writeFrameCsv(csv, result.rows, error)) {
      std::fprintf(stderr, "fluiddemo replay: %s\n", error.c_str());
      return 1;
    }
    if (!args.csv.empty()) std::printf("csv: %s (%zu rows)\n", args.csv.c_str(), result.rows.size());
  }
  int code = 0;
  if (!args.png.empty()) {
    code =
        plot(csv, args, std::filesystem::path(replay.label).stem().string() + " (" + result.report.gl_renderer + ")");
    if (args.csv.empty()) std::filesystem::remove(csv);
  }
  return code;
}

int updateHashes(const ReplayFile& replay, const ReplayResult& result) {
  std::string text, rewritten, error;
  if (!readTextFile(replay.label, text, error) || !rewriteHashes(text, replay, result, rewritten, error)) {
    std::fprintf(stderr, "fluiddemo replay --update-hashes: %s\n", error.c_str());
    return 1;
  }
  // Write next to it, then rename over it: an interrupted update leaves the old file whole.
  const std::filesystem::path target = replay.label;
  const std::filesystem::path temporary = target.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << rewritten;
    if (!out.flush()) {
      std::fprintf(stderr, "fluiddemo replay --update-hashes: cannot write %s: %s\n", temporary.c_str(),
                   std::strerror(errno));
      return 1;
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, target, ec);
  if (ec) {
    std::fprintf(stderr, "fluiddemo replay --update-hashes: %s: %s\n", target.c_str(), ec.message().c_str());
    return 1;
  }
  std::printf("updated %zu checkpoints and the scene hash in %s\n", result.checkpoints.size(), target.c_str());
  return 0;
}

// The offline render's figures: per kind of sound its events, their rate, the pitch range, and
// its loudness (its own sum, after the volume, before the limiter) as the peak and the RMS over the
// frames it sounded; then the output's peak and RMS, and the main thread's cost per step.
void printAudioSummary(const ReplayAudio& a) {
  const auto db = [](double x) { return x > 1e-9 ? 20.0 * std::log10(x) : -180.0; };
  const double frames = static_cast<double>(a.samples.size() / 2);
  const double seconds = frames / a.sample_rate;
  const engine::audio::ProducerCost& c = a.cost;
  const double steps = c.steps > 0 ? static_cast<double>(c.steps) : 1.0;
  std::printf("audio: %.2f s at %d Hz; main-thread cost per step (%llu steps): wall mean %.4f ms, max %.4f ms; "
              "CPU mean %.4f ms, max %.4f ms\n",
              seconds, a.sample_rate, static_cast<unsigned long long>(c.steps), c.wall_ms_sum / steps, c.wall_ms_max,
              c.cpu_ms_sum / steps, c.cpu_ms_max);
  std::printf("  %-13s %8s %9s %8s %17s %10s %10s\n", "kind", "events", "per s", "dropped", "pitch (Hz)", "peak dBFS",
              "rms dBFS");
  for (std::size_t k = 0; k < engine::audio::kSoundKinds; ++k) {
    const engine::audio::KindStats& s = a.stats[k];
    const double rms = s.active_frames > 0 ? std::sqrt(s.sum_squares / static_cast<double>(s.active_frames)) : 0.0;
    char pitch[32] = "-";
    if (s.max_frequency > 0.0f) std::snprintf(pitch, sizeof pitch, "%.0f-%.0f", s.min_frequency, s.max_frequency);
    std::printf("  %-13s %8llu %9.1f %8llu %17s %10.1f %10.1f\n",
                std::string(engine::audio::soundKindName(static_cast<engine::audio::SoundKind>(k))).c_str(),
                static_cast<unsigned long long>(s.events), seconds > 0.0 ? static_cast<double>(s.events) / seconds : 0.0,
                static_cast<unsigned long long>(s.dropped), pitch, db(s.peak), db(rms));
  }
  float peak = 0.0f;
  double sum = 0.0;
  std::size_t nonfinite = 0;
  for (float x : a.samples) {
    if (!std::isfinite(x)) ++nonfinite;
    peak = std::max(peak, std::abs(x));
    sum += static_cast<double>(x) * x;
  }
  std::printf("  output: peak %.2f dBFS, rms %.1f dBFS, clamped samples %llu, NaN/inf %zu (voices dropped for NaN %llu)\n",
              db(peak), db(a.samples.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(a.samples.size()))),
              static_cast<unsigned long long>(a.clipped), nonfinite, static_cast<unsigned long long>(a.nonfinite));
}

int writeAudio(const ReplayArgs& args, const ReplayResult& result) {
  if (!result.audio.present) {
    std::fprintf(stderr, "fluiddemo replay: --wav %s: the scene '%s' lists no audio effect\n", args.wav.c_str(),
                 result.scene.name.c_str());
    return 1;
  }
  printAudioSummary(result.audio);
  std::string error;
  std::vector<float> mono;
  std::span<const float> samples = result.audio.samples;
  if (args.wav_mono) {
    engine::audio::stereoToMono(samples, mono);
    samples = mono;
  }
  if (!engine::audio::writeWav16(args.wav.c_str(), samples, args.wav_mono ? 1 : 2, result.audio.sample_rate, &error)) {
    std::fprintf(stderr, "fluiddemo replay: --wav %s\n", error.c_str());
    return 1;
  }
  std::printf("wav: %s (%s, %d Hz, 16-bit, %.2f s)\n", args.wav.c_str(), args.wav_mono ? "mono" : "stereo",
              result.audio.sample_rate,
              static_cast<double>(result.audio.samples.size() / 2) / result.audio.sample_rate);
  return 0;
}

}  // namespace

int replayCommand(const Args& args) {
  CLI::App app{
      "Play a replay file one fixed step per rendered frame, check its checkpoint hashes and time every "
      "frame per phase (docs/replay.md).",
      "fluiddemo replay"};
  ReplayArgs a;
  a.run.run.width = 1280;
  a.run.run.height = 720;
  app.add_option("file", a.file, "replay file (content/replays/*.replay)");
  app.add_flag("--headless", a.run.run.headless, "no window: render offscreen (automatic without a display)");
  app.add_option("--frames", a.run.frames, "run only the first N steps (0 = the whole replay)")
      ->check(CLI::Range(0, 100000000));
  app.add_option("--threads", a.threads, "most threads a parallel loop runs on (0 = all cores)");
  app.add_option("--width", a.run.run.width, "framebuffer width")->check(CLI::Range(64, 8192))->capture_default_str();
  app.add_option("--height", a.run.run.height, "framebuffer height")
      ->check(CLI::Range(64, 8192))
      ->capture_default_str();
  app.add_option("--csv", a.csv, "write one row per frame: phase times, counts, checkpoint hashes");
  app.add_option("--png", a.png, "plot the per-phase frame times (scripts/plot_frame_times.py, matplotlib)");
  app.add_option("--plot-width", a.plot_width, "plot width in pixels")
      ->check(CLI::Range(200, 8000))
      ->capture_default_str();
  app.add_option("--plot-height", a.plot_height, "plot height in pixels")
      ->check(CLI::Range(150, 8000))
      ->capture_default_str();
  app.add_option("--screenshot-at", a.screenshot_at, "STEP:FILE.png: write the frame after STEP steps (repeatable)");
  app.add_flag("--update-hashes", a.update_hashes,
               "rewrite the file's checkpoint hashes and scene_hash (needs --force)");
  app.add_flag("--force", a.force, "replace existing --csv/--png/--screenshot-at files; allow --update-hashes");
  app.add_flag("--allow-scene-change", a.run.allow_scene_change, "replay even if the scene file's hash changed");
  app.add_option("--compare", a.compare, "A.csv B.csv: per-phase p50/p95 ratios B/A")->expected(2);
  app.add_option("--set", a.sets,
                 "a render-only override, section.key=value (repeatable; fluid_surface.* and the blob's surface "
                 "keys only, so the checkpoints still hold), e.g. fluid_surface.method=raycast, blob.async=false");
  app.add_flag("--no-ui", a.no_ui, "start with the overlay hidden");
  app.add_option("--wav", a.wav,
                 "write the audio effect's sound as 16-bit WAV, rendered offline (simulation only, as --no-render; "
                 "the same samples at any --threads)");
  app.add_flag("--wav-mono", a.wav_mono, "--wav as one channel");
  bool no_render = false;
  app.add_flag("--no-render", no_render,
               "simulation only: the same steps, inputs and checkpoints without GL, meshing or rendering");
  bool mesh = false;
  app.add_flag("--mesh", mesh,
               "with --no-render: mesh the surfaces every frame as a rendered run does (asynchronous where the "
               "scene says so), still without GL or drawing: simulation + meshing with no renderer on the cores");
  double pace = 0.0;
  app.add_option("--pace", pace,
                 "with --no-render: start frames no faster than HZ per second, as vsync holds the game's loop "
                 "(work left to other threads then runs in each frame's idle time)")
      ->check(numberIn(1.0, 1000.0));
  if (const int code = parseCommandLine(app, "replay", args); code >= 0) return code;
  if (const int code = checkArgs(a); code >= 0) return code;
  if (!a.compare.empty()) return compareCommand(a);
  if (!a.wav.empty()) no_render = true;  // the offline render is the simulation-only run
  if (mesh && !no_render) return usageError("--mesh goes with --no-render (a rendered run meshes anyway)");
  if (pace > 0.0 && !no_render) return usageError("--pace goes with --no-render");
  if (no_render && !a.run.screenshots.empty())
    return usageError("--screenshot-at needs rendering: drop --no-render (and --wav)");
  if (a.wav_mono && a.wav.empty()) return usageError("--wav-mono needs --wav");
  if (!a.wav.empty())
    if (const int code = checkOutputFile("replay", "--wav", a.wav, a.force); code >= 0) return code;

  ReplayFile replay;
  if (ReplayStatus st = loadReplayFile(a.file, replay); !st.ok()) {
    std::fprintf(stderr, "fluiddemo replay: %s\n", st.error.c_str());
    return st.exit_code;
  }
  if (const int code = checkScreenshotSteps(a, replay); code >= 0) return code;
  if (const int code = checkReplayWritable(a); code >= 0) return code;
  if (const int code = checkPlotter(a); code >= 0) return code;
  if (!displayAvailable()) a.run.run.headless = true;
  a.run.run.show_ui = !a.no_ui;
  a.run.update_hashes = a.update_hashes;
  a.run.render = !no_render;
  a.run.mesh_without_render = mesh;
  a.run.pace_hz = pace;
  a.run.audio = !a.wav.empty();
  std::optional<tbb::global_control> limit;
  if (a.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(a.threads));

  ReplayResult result;
  std::string error;
  const int code = runReplay(replay, a.run, result, error);
  if (!result.warning.empty()) std::fprintf(stderr, "fluiddemo replay: warning: %s\n", result.warning.c_str());
  if (result.report.frames_rendered > 0) {
    printRunSummary(stdout, result.scene, a.run.run, result.report);
    printPercentileTable(stdout, result.rows);
    const std::size_t ok = static_cast<std::size_t>(
        std::count_if(result.checkpoints.begin(), result.checkpoints.end(), [](const auto& c) { return c.matched; }));
    std::printf("checkpoints: %zu %s of %zu in the file (%zu steps of %llu run)\n", ok,
                a.update_hashes ? "hashed" : "matched", result.checkpoints_in_file, result.rows.size(),
                static_cast<unsigned long long>(replay.end_step));
    if (const RaycastTally& t = result.raycast; t.frames > 0)
      std::printf(
          "raycast: %zu frames, most records in a frame %llu, dropped %llu in %zu frames, largest pool %llu "
          "records (%.1f MiB; bound %.1f MiB)\n",
          t.frames, static_cast<unsigned long long>(t.records_max), static_cast<unsigned long long>(t.dropped_total),
          t.frames_dropping, static_cast<unsigned long long>(t.pool_records_max),
          static_cast<double>(t.pool_records_max) * 16.0 / (1024.0 * 1024.0),
          static_cast<double>(t.pool_bound) * 16.0 / (1024.0 * 1024.0));
  }
  if (code != 0) {
    std::fprintf(stderr, "fluiddemo replay: %s\n", error.c_str());
    // The timing of what ran is still worth keeping.
    if (!result.rows.empty()) (void)writeOutputs(a, replay, result);
    return code;
  }
  if (const int out = writeOutputs(a, replay, result); out != 0) return out;
  if (!a.wav.empty())
    if (const int out = writeAudio(a, result); out != 0) return out;
  if (a.update_hashes) return updateHashes(replay, result);
  return 0;
}

}  // namespace game
