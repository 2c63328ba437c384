// runReplay(): a replay file driving runScene() through its frame hooks (replay_runner.hpp).
#include "game/replay/replay_runner.hpp"

#include "engine/ui/overlay.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <thread>

namespace game {
namespace {

std::string where(const ReplayFile& replay, int line, std::string_view field) {
  return replay.label + ":" + std::to_string(line) + ": field '" + std::string(field) + "': ";
}

// Compares a computed state hash with a checkpoint's; empty when equal, else which subsystems
// differ (the first one with both values).
std::string compareCheckpoint(const ReplayEvent& expected, const StateHash& got) {
  for (const NamedHash& part : expected.parts) {
    const bool present =
        std::any_of(got.parts.begin(), got.parts.end(), [&](const SubsystemHash& g) { return g.name == part.name; });
    if (!present) return "subsystem '" + part.name + "' is in the checkpoint but not in this scene's world";
  }
  std::string first, all;
  for (const SubsystemHash& part : got.parts) {
    for (const NamedHash& want : expected.parts) {
      if (want.name != part.name || want.value == part.value) continue;
      if (first.empty())
        first = "first differing subsystem '" + want.name + "': expected " + hashHex(want.value) + ", got " +
                hashHex(part.value);
      all += (all.empty() ? "" : ", ") + want.name;
    }
  }
  if (!first.empty()) return first + " (differing: " + all + ")";
  if (expected.hash != got.combined)
    return "combined hash differs (expected " + hashHex(expected.hash) + ", got " + hashHex(got.combined) +
           ") while every listed subsystem matches";
  return {};
}

int finish(ReplayResult& result, std::string& error) {
  if (!result.mismatch.empty()) {
    error = result.mismatch;
    return 1;
  }
  if (!result.report.nonfinite_state.empty()) {
    error = "non-finite simulation state: " + result.report.nonfinite_state;
    return 1;
  }
  // A replay is a check: a system that refused content fails it, though the frames went on.
  if (result.report.runtime_failures > 0) {
    error =
        std::to_string(result.report.runtime_failures) + " run-time failures, first: " + result.report.first_failure;
    return 1;
  }
  return 0;
}

// The replay without GL: build the world, then per frame inputs, one step, checkpoints. The rows
// carry the simulation phases (physics, fluid) from a profiler of their own.
int simulateReplay(ReplayPlayer& player, int frames, const ReplayRunOptions& options, ReplayResult& result,
                   std::string& error) {
  const bool audio = options.audio;
  World world;
  if (!buildWorld(result.scene, contentDir(), world, error)) return 1;
  engine::audio::Mixer* mixer = audio ? world.links.audio : nullptr;
  ReplayAudio& sound = result.audio;
  if (mixer != nullptr) {
    sound.present = true;
    sound.sample_rate = mixer->params.sample_rate;
    sound.samples.reserve(2 * audioStepFrames(0, world.step_seconds, sound.sample_rate) *
                          static_cast<std::size_t>(frames + 1));
  }
  result.report.systems_constructed = world.systems;
  result.report.gl_renderer =
      options.mesh_without_render ? "none (simulation and meshing only)" : "none (simulation only)";
  engine::Profiler profiler;
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options.pace_hz > 0.0 ? 1.0 / options.pace_hz : 0.0));
  Clock::time_point next_frame = Clock::now();
  for (int frame = 0; frame < frames; ++frame) {
    if (options.pace_hz > 0.0) {
      // As vsync: a frame starts on a tick of the display's clock; a frame that ran past its tick
      // waits for the next one instead of starting at once (the display shows the late frame a tick
      // later), so work left to other threads gets the idle time it would get in the game.
      std::this_thread::sleep_until(next_frame);
      next_frame += period;
      const Clock::time_point now = Clock::now();
      if (now > next_frame) next_frame += period * ((now - next_frame) / period + 1);
    }
    engine::beginFrame(profiler);
    {
      engine::ScopedPhase phase(profiler, engine::Phase::input);
      applyReplayInputs(player, world);
    }
    // The listener is the replay's camera for this step; the step queues its sounds, which the
    // mixer then renders: the same renderMixer SDL's callback calls live.
    if (mixer != nullptr)
      engine::audio::setListener(*mixer, {world.camera.position, engine::cameraForward(world.camera)});
    stepWorld(world, &profiler);
    if (options.mesh_without_render) meshWorld(world, &profiler);
    if (mixer != nullptr) {
      const std::size_t n = audioStepFrames(world.steps - 1, world.step_seconds, sound.sample_rate);
      const std::size_t at = sound.samples.size();
      sound.samples.resize(at + 2 * n);
      engine::audio::renderMixer(*mixer, sound.samples.data() + at, n);
    }
    engine::endFrame(profiler);
    FrameRow row;
    row.frame = frame;
    for (int p = 0; p < engine::kPhaseCount; ++p) row.phase_ms[p] = profiler.current_ms[p];
    row.frame_ms =
        profiler.frame_history[(profiler.head - 1 + engine::Profiler::kHistory) % engine::Profiler::kHistory];
    const bool keep_going = checkReplayStep(player, world, row, result);
    result.rows.push_back(row);
    ++result.report.frames_rendered;
    ++result.report.simulation_steps;
    if (!keep_going) break;
  }
  if (mixer != nullptr) {
    const std::lock_guard<std::mutex> hold(mixer->lock);
    sound.stats = mixer->stats;
    sound.clipped = mixer->clipped;
    sound.nonfinite = mixer->nonfinite;
    sound.cost = mixer->producer;
  }
  result.report.nonfinite_state = world.nonfinite_state;
  result.report.runtime_failures = world.failures.count;
  result.report.first_failure = world.failures.first;
  result.report.last_failure = world.failures.last;
  result.report.mean_frame_ms = engine::frameMeanMs(profiler);
  fillSphHealth(world, profiler, result.report);
  for (int p = 0; p < engine::kPhaseCount; ++p) {
    const auto phase = static_cast<engine::Phase>(p);
    result.report.phases.push_back({std::string(engine::phaseName(phase)), engine::phaseMeanMs(profiler, phase),
                                    profiler.stats[p].max_ms, profiler.stats[p].frames});
  }
  return finish(result, error);
}

}  // namespace

std::size_t audioStepFrames(std::uint64_t step, double step_seconds, int sample_rate) {
  const double per_step = step_seconds * sample_rate;
  return static_cast<std::size_t>(std::floor(static_cast<double>(step + 1) * per_step) -
                                  std::floor(static_cast<double>(step) * per_step));
}

void applyReplayInputs(ReplayPlayer& player, World& world) {
  const ReplayFile& replay = *player.replay;
  const std::uint64_t step = world.steps;
  const auto setPose = [&world](const CameraPose& p) {
    world.camera.position = p.position;
    world.camera.yaw_degrees = p.yaw_degrees;
    world.camera.pitch_degrees = p.pitch_degrees;
  };
  CameraPose pose;
  if (cameraPoseAt(replay, step, pose)) setPose(pose);
  std::size_t& cursor = player.input_cursor;
  while (cursor < replay.events.size() && replay.events[cursor].step < step) ++cursor;
  // This step's events in file order: a throw uses the pose of the keyframes above it.
  for (; cursor < replay.events.size() && replay.events[cursor].step == step; ++cursor) {
    const ReplayEvent& e = replay.events[cursor];
    if (e.kind == ReplayEventKind::camera) setPose({e.position, e.yaw_degrees, e.pitch_degrees});
    if (e.kind == ReplayEventKind::action) applyPlayerAction(world, e.action);
  }
}

bool checkReplayStep(ReplayPlayer& player, const World& world, FrameRow& row, ReplayResult& result) {
  const ReplayFile& replay = *player.replay;
  row.step = world.steps;
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->reportColumns(row.columns);
  if (row.columns.get("raycast_pool") > 0.0) {
    const auto cell = [&row](std::string_view name) { return static_cast<std::uint64_t>(row.columns.get(name)); };
    RaycastTally& t = result.raycast;
    ++t.frames;
    t.records_max = std::max(t.records_max, cell("raycast_records"));
    t.dropped_total += cell("raycast_dropped");
    t.frames_dropping += cell("raycast_dropped") > 0;
    t.pool_records_max = std::max(t.pool_records_max, cell("raycast_pool"));
    t.pool_bound = std::max(t.pool_bound, cell("raycast_pool_bound"));
  }
  std::size_t& cursor = player.checkpoint_cursor;
  for (; cursor < replay.events.size() && replay.events[cursor].step <= world.steps; ++cursor) {
    const ReplayEvent& e = replay.events[cursor];
    if (e.kind != ReplayEventKind::checkpoint || e.step != world.steps) continue;
    if (!row.has_hash) hashWorldState(world, player.scratch, player.hash);
    row.has_hash = true;
    row.state_hash = player.hash.combined;
    CheckpointOutcome outcome{cursor, e.step, player.hash.combined, {}, false};
    for (const SubsystemHash& part : player.hash.parts) outcome.parts.push_back({std::string(part.name), part.value});
    const std::string difference = player.update_hashes ? std::string() : compareCheckpoint(e, player.hash);
    outcome.matched = difference.empty();
    result.checkpoints.push_back(std::move(outcome));
    if (!difference.empty()) {
      result.mismatch = replay.label + ":" + std::to_string(e.line) + ": checkpoint at step " + std::to_string(e.step) +
                        " failed: " + difference;
      ++cursor;
      return false;
    }
    ++player.matched;
  }
  return true;
}

ReplayStatus prepareReplayScene(const ReplayFile& replay, const std::filesystem::path& scenes_dir,
                                bool allow_scene_change, const std::vector<std::string>& extra_overrides,
                                SceneConfig& out, std::uint64_t& scene_hash, std::string& warning) {
  warning.clear();
  const int scene_line = replay.scene_line;
  std::filesystem::path path;
  if (SceneStatus status = resolveScene(replay.scene, scenes_dir, path); !status.ok())
    return {where(replay, scene_line, "scene") + status.error, 1};
  std::string bytes, error;
  if (!readTextFile(path, bytes, error)) return {where(replay, scene_line, "scene") + error, 1};
  scene_hash = fnv1a64(bytes);
  if (scene_hash != replay.scene_hash) {
    const std::string message = where(replay, replay.scene_hash_line, "scene_hash") + "scene file " + path.string() +
                                " has hash " + hashHex(scene_hash) + ", the replay was made with " +
                                hashHex(replay.scene_hash);
    if (!allow_scene_change)
      return {message +
                  " (the scene changed: pass --allow-scene-change to replay anyway, or --update-hashes --force "
                  "to re-baseline)",
              1};
    warning = message;
  }
  if (SceneStatus status = loadSceneFile(path, out); !status.ok())
    return {where(replay, scene_line, "scene") + status.error, 1};
  for (std::size_t i = 0; i < replay.sets.size(); ++i) {
    if (SceneStatus status = applyOverride(out, replay.sets[i]); !status.ok())
      return {where(replay, replay.set_lines[i], "set") + status.error, 1};
  }
  for (const std::string& assignment : extra_overrides) {
    if (SceneStatus status = applyOverride(out, assignment); !status.ok()) return {status.error, 1};
  }
  if (out.scene.number("step_hz") != replay.step_hz)
    return {where(replay, replay.step_hz_line, "step_hz") + "the replay steps at " + std::to_string(replay.step_hz) +
                " Hz, the scene at " + std::to_string(out.scene.number("step_hz")) + " Hz",
            1};
  if (out.scene.integer("seed") != replay.seed)
    return {where(replay, replay.seed_line, "seed") + "the replay has seed " + std::to_string(replay.seed) +
                ", the scene " + std::to_string(out.scene.integer("seed")),
            1};
  return {};
}

int runReplay(const ReplayFile& replay, const ReplayRunOptions& options, ReplayResult& result, std::string& error) {
  result = ReplayResult{};
  if (ReplayStatus st = prepareReplayScene(replay, scenesDir(), options.allow_scene_change || options.update_hashes,
                                           options.extra_overrides, result.scene, result.scene_hash, result.warning);
      !st.ok()) {
    error = st.error;
    return st.exit_code;
  }
  for (const ReplayEvent& e : replay.events) {
    if (e.kind != ReplayEventKind::checkpoint) continue;
    ++result.checkpoints_in_file;
    if (!e.has_hash && !options.update_hashes) {
      error = where(replay, e.line, "checkpoint.hash") +
              "missing (fill it in with `fluiddemo replay FILE --update-hashes --force`)";
      return 1;
    }
  }
  const auto frames =
      static_cast<int>(options.frames > 0 ? std::min<std::uint64_t>(options.frames, replay.end_step) : replay.end_step);
  result.rows.reserve(static_cast<std::size_t>(frames));
  ReplayPlayer player;
  player.replay = &replay;
  player.update_hashes = options.update_hashes;
  if (!options.render) return simulateReplay(player, frames, options, result, error);

  RunOptions run = options.run;
  run.frames = frames;
  run.fixed_frame_time = true;  // exactly one simulation step per rendered frame
  run.hooks.before_steps = [&](FrameInput& input) {
    input.actions.clear();  // the script plays; the mouse does not
    applyReplayInputs(player, input.world);
    for (const auto& [shot_step, path] : options.screenshots)
      if (shot_step == input.world.steps + 1) input.screenshot = path;
  };
  run.hooks.after_frame = [&](const FrameResult& frame) {
    FrameRow row;
    row.frame = frame.frame;
    row.phase_ms = frame.phase_ms;
    row.frame_ms = frame.frame_ms;
    const bool keep_going = checkReplayStep(player, frame.world, row, result);
    result.rows.push_back(row);
    return keep_going;
  };
  run.hooks.draw_overlay = [&]() {
    const std::uint64_t step = result.rows.empty() ? 0 : result.rows.back().step;
    char detail[160];
    std::snprintf(detail, sizeof detail, "%s  step %llu / %llu  checkpoints %zu ok of %zu", replay.label.c_str(),
                  static_cast<unsigned long long>(step), static_cast<unsigned long long>(replay.end_step),
                  player.matched, result.checkpoints_in_file);
    engine::drawProgressWindow("Replay", static_cast<float>(static_cast<double>(step) / replay.end_step), detail);
  };
  if (const int code = runScene(result.scene, run, result.report, error); code != 0) return code;
  return finish(result, error);
}

bool rewriteHashes(std::string_view text, const ReplayFile& replay, const ReplayResult& result, std::string& out,
                   std::string& error) {
  std::vector<std::string> replacement;  // by line, empty = keep
  const auto set = [&replacement](int line, std::string content) {
    if (replacement.size() <= static_cast<std::size_t>(line)) replacement.resize(static_cast<std::size_t>(line) + 1);
    replacement[static_cast<std::size_t>(line)] = std::move(content);
  };
  std::size_t done = 0;
  for (const CheckpointOutcome& c : result.checkpoints) {
    set(replay.events[c.event].line, formatCheckpointLine(c.step, c.combined, c.parts));
    ++done;
  }
  if (done != result.checkpoints_in_file) {
    error = "only " + std::to_string(done) + " of " + std::to_string(result.checkpoints_in_file) +
            " checkpoints were reached: --update-hashes needs the whole replay (drop --frames)";
    return false;
  }
  if (replay.scene_hash_line > 0) set(replay.scene_hash_line, "scene_hash " + hashHex(result.scene_hash));
  out.clear();
  std::size_t pos = 0;
  int line = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    ++line;
    std::string_view content = text.substr(pos, end - pos);
    if (static_cast<std::size_t>(line) < replacement.size() && !replacement[static_cast<std::size_t>(line)].empty()) {
      // Keep a trailing comment of the line.
      const std::size_t comment = content.find('#');
      out += replacement[static_cast<std::size_t>(line)];
      if (comment != std::string_view::npos) out += "  " + std::string(content.substr(comment));
    } else {
      out += content;
    }
    if (end < text.size()) out += '\n';
    pos = end + 1;
  }
  return true;
}

bool renderOnlyOverride(std::string_view assignment, std::string& error) {
  const std::string_view path = assignment.substr(0, assignment.find('='));
  const std::size_t dot = path.find('.');
  const std::string_view section = dot == std::string_view::npos ? path : path.substr(0, dot);
  constexpr std::string_view kRenderOnly = "fluid_surface";
  // The blob's surface keys: how its goo is meshed and drawn, never how the body moves.
  constexpr std::array<std::string_view, 6> kBlobSurface = {"blob.async",     "blob.smoothing", "blob.cube",
                                                            "blob.threshold", "blob.colour",    "blob.visible"};
  if (section == kRenderOnly || section == "graphics") return true;  // the graphics presets set render-only keys
  if (std::find(kBlobSurface.begin(), kBlobSurface.end(), path) != kBlobSurface.end()) return true;
  std::string keys;
  if (const SectionSpec* spec = findSection(kRenderOnly))
    for (const ParamSpec& param : spec->params) keys += (keys.empty() ? "" : ", ") + std::string(param.key);
  std::string blob_keys;
  for (const std::string_view key : kBlobSurface) blob_keys += (blob_keys.empty() ? "" : ", ") + std::string(key);
  error = "--set " + std::string(assignment) + ": '" + std::string(path) +
          "' is not render-only (it could change the simulation the checkpoints hash); a replay accepts --set for " +
          std::string(kRenderOnly) + ".* keys (" + keys + "), graphics.* and the blob's surface keys (" + blob_keys +
          ") only";
  return false;
}

}  // namespace game
