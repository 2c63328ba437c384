#pragma once
// `fluiddemo play SCENE --record FILE`: writes every input of a live session as a replay file
// (replay_file.hpp), one line per event, flushed as it goes, so a crash or a closed window keeps
// every event up to that point (a file cut short lacks only its `end` record).
// Recorded: the camera pose at each step where it changed, every player action, and a checkpoint
// (the state hash) every `checkpoint_every` steps and at the last step.
// Not recorded: live parameter edits in the overlay and scene restarts (the recording stops at a
// restart, with a message): a replay of such a session would not match its checkpoints.

#include "game/replay/replay_file.hpp"
#include "game/replay/state_hash.hpp"
#include "game/run_scene.hpp"
#include "game/scene/scene_config.hpp"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace game {

struct ReplayRecorder {
  std::FILE* file = nullptr;  // owned; closed by finishRecording
  std::filesystem::path path;
  std::uint64_t checkpoint_every = 60;  // steps
  bool has_pose = false;
  CameraPose last_pose;
  std::uint64_t last_step = 0;             // world.steps at the last after-frame
  std::uint64_t last_checkpoint_step = 0;  // 0 = none written yet
  bool stopped = false;                    // a restart or a write error ended the recording
  std::string message;                     // why it stopped
  StateHashScratch scratch;
  StateHash pending;  // the hash at last_step (written as the final checkpoint)
  bool has_pending = false;
};

// Creates `path` (refused when it exists and !force) and writes the header: `scene_arg` as given
// on the command line, the scene file's hash, every --set in order, step rate and seed.
bool startRecording(const std::filesystem::path& path, bool force, const std::string& scene_arg,
                    const SceneConfig& scene, const std::vector<std::string>& overrides, ReplayRecorder& out,
                    std::string& error);

// Frame hooks: before the frame's steps (after the player's input), and after the frame.
void recordInput(ReplayRecorder& recorder, const World& world, std::span<const PlayerAction> actions);
void recordAfterFrame(ReplayRecorder& recorder, const World& world);

// Writes the final checkpoint and `end`, closes the file. False + message on a write error.
bool finishRecording(ReplayRecorder& recorder, std::string& error);

// Installs recordInput/recordAfterFrame into `hooks` (chained after any hooks already there).
void attachRecorder(ReplayRecorder& recorder, FrameHooks& hooks);

}  // namespace game
