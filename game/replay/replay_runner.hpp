#pragma once
// Runs a parsed replay through runScene(): one fixed simulation step per rendered frame, the
// file's camera keyframes and actions applied before each step, the state hashed and checked
// at every checkpoint, and one timing row kept per frame.

#include "engine/audio/synth.hpp"
#include "game/replay/frame_times.hpp"
#include "game/replay/replay_file.hpp"
#include "game/replay/state_hash.hpp"
#include "game/run_scene.hpp"
#include "game/scene/scene_config.hpp"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace game {

// Resolves the replay's scene (scenes_dir for a bare name), checks its content hash against the
// header (a mismatch is an error unless allow_scene_change, then `warning` says so), applies the
// header's `set` records and then `extra_overrides`, and checks step_hz and seed against the result.
// Errors name the replay file, line and field; exit_code 1.
ReplayStatus prepareReplayScene(const ReplayFile& replay, const std::filesystem::path& scenes_dir,
                                bool allow_scene_change, const std::vector<std::string>& extra_overrides,
                                SceneConfig& out, std::uint64_t& scene_hash, std::string& warning);

struct ReplayRunOptions {
  RunOptions run;  // size, headless, show_ui; frames/fixed_frame_time/hooks are set by runReplay
  int frames = 0;  // replay frames to run, <= end step; 0 = the whole replay
  // false: the same steps, inputs and checkpoints with no window, GL, meshing or rendering (the
  // state hash never depends on them); the rows then time the simulation phases only.
  bool render = true;
  // With render false: each frame's surfaces are meshed as a rendered run meshes them (the effects'
  // prepareFrame, asynchronous where the scene says so), still with no GL or drawing, so the rows
  // time simulation + meshing with no renderer on the cores.
  bool mesh_without_render = false;
  // With render false and > 0: frames start on the ticks of a 1/pace_hz s clock, as vsync holds the
  // game's loop (a frame that ran past its tick waits for the next one), so work left to other
  // threads (the asynchronous mesher) runs in the frame's idle time as it would in the game.
  double pace_hz = 0.0;
  bool allow_scene_change = false;
  bool update_hashes = false;  // record the hashes at checkpoints instead of checking them
  // Applied after the header's set records: `fluiddemo replay --set` passes render-only keys
  // (renderOnlyOverride); tests pass a perturbed constant, which must fail the gate.
  std::vector<std::string> extra_overrides;
  std::vector<std::pair<std::uint64_t, std::filesystem::path>> screenshots;  // (step, PNG)
  // Render the audio effect's sound offline (simulation-only runs): before each step the listener
  // takes the replay's camera, after it the mixer renders the step's share of samples
  // (audioStepFrames) into ReplayResult::audio. Needs the scene to list `audio`.
  bool audio = false;
};

// Interleaved stereo samples of a replay's sound and what the mixer counted while making them.
struct ReplayAudio {
  bool present = false;  // the scene lists audio and ReplayRunOptions::audio was set
  int sample_rate = 0;
  std::vector<float> samples;  // interleaved stereo, in [-1, 1]
  std::array<engine::audio::KindStats, engine::audio::kSoundKinds> stats{};
  std::uint64_t clipped = 0, nonfinite = 0;
  engine::audio::ProducerCost cost;  // the audio effect's step on the main thread
};

// Frames of sound belonging to step `step` (0-based) at `sample_rate`: floor((k + 1) R dt) - floor(k R dt),
// so any run of steps holds exactly its duration's samples.
std::size_t audioStepFrames(std::uint64_t step, double step_seconds, int sample_rate);

struct CheckpointOutcome {
  std::size_t event = 0;  // index into ReplayFile::events
  std::uint64_t step = 0;
  std::uint64_t combined = 0;
  std::vector<NamedHash> parts;  // as computed
  bool matched = false;
};

// fluid_surface.method = raycast, over the frames rendered: the fragment-list demand and what the
// pool dropped (engine::RaycastRenderer), so a run shows whether its pool held every record.
struct RaycastTally {
  std::size_t frames = 0;              // frames drawn by the ray caster
  std::uint64_t records_max = 0;       // most records one frame asked for
  std::uint64_t dropped_total = 0;     // records dropped, all frames
  std::size_t frames_dropping = 0;     // frames that dropped any
  std::uint64_t pool_records_max = 0;  // largest pool (16 bytes a record)
  std::uint64_t pool_bound = 0;        // the most records the pool may grow to
};

struct ReplayResult {
  SceneConfig scene;
  std::uint64_t scene_hash = 0;  // of the scene file as it is now
  std::string warning;           // e.g. the scene changed (allow_scene_change)
  RunReport report;
  std::vector<FrameRow> rows;
  std::vector<CheckpointOutcome> checkpoints;  // every checkpoint reached, in order
  std::size_t checkpoints_in_file = 0;
  std::string mismatch;  // the first failed checkpoint: step, line, first differing subsystem
  RaycastTally raycast;
  ReplayAudio audio;  // ReplayRunOptions::audio
};

// `fluiddemo replay --set`: true when `assignment` (section.key=value) names a key that changes
// only how frames are drawn, never the simulation state the checkpoints hash (docs/replay.md,
// "State hash": the fluid surface mesh and GPU state are left out), so the checkpoints still gate.
// Today that is every fluid_surface key. False + an error naming the key otherwise.
bool renderOnlyOverride(std::string_view assignment, std::string& error);

// Applies a replay to a World step by step (shared by the rendered and the simulation-only runs).
struct ReplayPlayer {
  const ReplayFile* replay = nullptr;
  bool update_hashes = false;
  std::size_t input_cursor = 0;       // first event not yet applied
  std::size_t checkpoint_cursor = 0;  // first event not yet checked
  std::size_t matched = 0;
  StateHashScratch scratch;
  StateHash hash;
};

// Before the step world.steps -> world.steps + 1: the camera pose of that step, then the step's
// events in file order (camera keyframes, actions).
void applyReplayInputs(ReplayPlayer& player, World& world);
// After a step: the row's counts, and the checkpoints at world.steps hashed and compared into
// `result` (its mismatch set on the first failure). Returns false on a mismatch.
bool checkReplayStep(ReplayPlayer& player, const World& world, FrameRow& row, ReplayResult& result);

// Returns 0 when every checkpoint reached matched (or update_hashes), 1 otherwise with `error`
// set (a mismatch, a scene error, a GL failure, a non-finite state).
int runReplay(const ReplayFile& replay, const ReplayRunOptions& options, ReplayResult& result, std::string& error);

// The replay text with every checkpoint line of `outcomes` and the scene_hash line rewritten
// (everything else byte for byte as it was). False + message when a checkpoint was not reached.
bool rewriteHashes(std::string_view text, const ReplayFile& replay, const ReplayResult& result, std::string& out,
                   std::string& error);

}  // namespace game
