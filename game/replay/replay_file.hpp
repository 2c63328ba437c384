#pragma once
// Replay files (content/replays/*.replay): a scripted or recorded game session, keyed by
// simulation step, as text with one record per line (docs/replay.md is the reference).
//
//   fluiddemo_replay 1                       format version (first record)
//   scene fountain                           scene name in content/scenes, or a path to a .json
//   scene_hash 9f2c4e1a00b3d6e7              FNV-1a 64 of the scene file's bytes (16 hex digits)
//   set sph_fluid.rate=600                   --set override (any number, applied in order)
//   step_hz 60                               must equal the scene's scene.step_hz
//   seed 7                                   must equal the scene's scene.seed
//   camera 0 0.5 2.6 9.5 -93 -11             STEP x y z yaw pitch: camera keyframe
//   action 120 throw_crate                   STEP NAME: a player action (throw_crate, throw_explosive)
//   checkpoint 600 0123456789abcdef rigid_bodies=... sph_fluid=...   expected state hashes
//   end 1200                                 last step (required: a file without it is truncated)
//
// '#' starts a comment (whole line or after a record); blank lines are ignored. Header records
// come before the first event; events come in non-decreasing step order and are applied in file
// order within one step. Camera poses between two keyframes are interpolated linearly (position,
// yaw and pitch as written: a full turn is yaw 0 -> 360), held before the first and after the last.

#include "game/run_scene.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace game {

constexpr int kReplayFormatVersion = 1;

enum class ReplayEventKind { camera, action, checkpoint };

// One named subsystem hash of a checkpoint ("rigid_bodies", "sph_fluid", ...).
struct NamedHash {
  std::string name;
  std::uint64_t value = 0;
};

struct ReplayEvent {
  ReplayEventKind kind = ReplayEventKind::camera;
  std::uint64_t step = 0;
  int line = 0;  // 1-based line in the file (for messages and in-place rewrites)
  // camera
  glm::vec3 position{0.0f};
  float yaw_degrees = 0.0f;
  float pitch_degrees = 0.0f;
  // action
  PlayerAction action = PlayerAction::throw_crate;
  // checkpoint: has_hash is false for a placeholder `checkpoint STEP` still to be filled in by
  // `fluiddemo replay FILE --update-hashes --force`.
  bool has_hash = false;
  std::uint64_t hash = 0;        // the combined state hash
  std::vector<NamedHash> parts;  // per-subsystem hashes, as written
};

struct ReplayFile {
  std::string label;  // file name used in messages
  int version = 0;
  std::string scene;  // name or path, as written
  bool has_scene_hash = false;
  std::uint64_t scene_hash = 0;
  std::vector<std::string> sets;  // "section.key=value"
  std::vector<int> set_lines;     // line of each set record
  double step_hz = 0.0;
  std::int64_t seed = 0;
  std::uint64_t end_step = 0;
  // Lines of the header records (0 = absent), for messages and for rewriting scene_hash.
  int scene_line = 0, scene_hash_line = 0, step_hz_line = 0, seed_line = 0;
  std::vector<ReplayEvent> events;  // file order == application order
};

// An error names file, line and field; `exit_code` is 1 (a file that cannot be read is a failure,
// like a bad record: game/commands.hpp's rule keeps 2 for usage errors).
struct ReplayStatus {
  std::string error;
  int exit_code = 0;
  bool ok() const { return error.empty(); }
};

// Parses replay text. `label` names the file in messages ("FILE:LINE: field 'F': ...").
ReplayStatus parseReplayText(std::string_view text, const std::string& label, ReplayFile& out);
ReplayStatus loadReplayFile(const std::filesystem::path& path, ReplayFile& out);

// Reads a whole file into `out` (binary); false with a message naming the path.
bool readTextFile(const std::filesystem::path& path, std::string& out, std::string& error);

// FNV-1a 64 of bytes (the scene_hash of the header).
std::uint64_t fnv1a64(std::string_view bytes);

// 16 lower-case hex digits.
std::string hashHex(std::uint64_t value);

struct CameraPose {
  glm::vec3 position{0.0f};
  float yaw_degrees = 0.0f;
  float pitch_degrees = 0.0f;
};

// The camera pose at the start of `step`, before that step's own events: the first keyframe at
// `step` if there is one, else interpolated between the last keyframe before and the first after
// (held before the first and after the last keyframe). False when the file has no keyframe.
bool cameraPoseAt(const ReplayFile& replay, std::uint64_t step, CameraPose& out);

// Writers used by the recorder and by --update-hashes (same number formats as the parser reads:
// floats with round-trip precision, so a recorded pose replays bit for bit).
std::string formatCameraLine(std::uint64_t step, const CameraPose& pose);
std::string formatCheckpointLine(std::uint64_t step, std::uint64_t hash, const std::vector<NamedHash>& parts);

}  // namespace game
