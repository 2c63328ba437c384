// Recording a live session as a replay file (recorder.hpp).
#include "game/replay/recorder.hpp"

#include "game/world/world.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace game {
namespace {

bool writeLine(ReplayRecorder& r, const std::string& line) {
  if (r.file == nullptr || r.stopped) return false;
  // One line at a time, flushed: what was played is on disk even if the game dies next.
  if (std::fprintf(r.file, "%s\n", line.c_str()) < 0 || std::fflush(r.file) != 0) {
    r.stopped = true;
    r.message = r.path.string() + ": write error: " + std::strerror(errno);
    return false;
  }
  return true;
}

bool samePose(const CameraPose& a, const CameraPose& b) {
  return a.position == b.position && a.yaw_degrees == b.yaw_degrees && a.pitch_degrees == b.pitch_degrees;
}

void writeCheckpoint(ReplayRecorder& r) {
  std::vector<NamedHash> parts;
  for (const SubsystemHash& part : r.pending.parts) parts.push_back({std::string(part.name), part.value});
  if (writeLine(r, formatCheckpointLine(r.last_step, r.pending.combined, parts))) r.last_checkpoint_step = r.last_step;
}

}  // namespace

bool startRecording(const std::filesystem::path& path, bool force, const std::string& scene_arg,
                    const SceneConfig& scene, const std::vector<std::string>& overrides, ReplayRecorder& out,
                    std::string& error) {
  std::string bytes;
  if (!readTextFile(scene.source, bytes, error)) return false;
  // O_EXCL: never replace a file without --force, with no window between the check and the create.
  const int flags = O_WRONLY | O_CREAT | (force ? O_TRUNC : O_EXCL);
  const int fd = ::open(path.c_str(), flags, 0644);
  if (fd < 0) {
    error = errno == EEXIST ? path.string() + " exists (pass --force to replace it)"
                            : path.string() + ": cannot create: " + std::strerror(errno);
    return false;
  }
  out.file = ::fdopen(fd, "w");
  out.path = path;
  if (out.file == nullptr) {
    ::close(fd);
    error = path.string() + ": cannot open for writing: " + std::strerror(errno);
    return false;
  }
  std::string header = "fluiddemo_replay " + std::to_string(kReplayFormatVersion) + "\n";
  header += "# recorded by fluiddemo play --record\n";
  header += "scene " + scene_arg + "\n";
  header += "scene_hash " + hashHex(fnv1a64(bytes)) + "\n";
  for (const std::string& assignment : overrides) header += "set " + assignment + "\n";
  char numbers[96];
  std::snprintf(numbers, sizeof numbers, "step_hz %.17g\nseed %d", scene.scene.number("step_hz"),
                scene.scene.integer("seed"));
  header += numbers;
  if (!writeLine(out, header)) {
    error = out.message;
    return false;
  }
  return true;
}

void recordInput(ReplayRecorder& r, const World& world, std::span<const PlayerAction> actions) {
  if (r.stopped) return;
  if (world.steps < r.last_step) {
    r.stopped = true;
    r.message = "the scene was restarted at step " + std::to_string(r.last_step) + ": recording stopped there";
    return;
  }
  const CameraPose pose{world.camera.position, world.camera.yaw_degrees, world.camera.pitch_degrees};
  if (!r.has_pose || !samePose(pose, r.last_pose)) {
    if (!writeLine(r, formatCameraLine(world.steps, pose))) return;
    r.last_pose = pose;
    r.has_pose = true;
  }
  for (PlayerAction action : actions)
    writeLine(r, "action " + std::to_string(world.steps) + " " + std::string(playerActionName(action)));
}

void recordAfterFrame(ReplayRecorder& r, const World& world) {
  if (r.stopped || world.steps == r.last_step) return;
  if (world.steps < r.last_step) {
    r.stopped = true;
    r.message = "the scene was restarted at step " + std::to_string(r.last_step) + ": recording stopped there";
    return;
  }
  r.last_step = world.steps;
  hashWorldState(world, r.scratch, r.pending);
  r.has_pending = true;
  if (r.last_step >= r.last_checkpoint_step + r.checkpoint_every) writeCheckpoint(r);
}

bool finishRecording(ReplayRecorder& r, std::string& error) {
  if (r.file == nullptr) return true;
  if (r.has_pending && r.last_checkpoint_step != r.last_step) {
    const bool was_stopped = r.stopped;
    r.stopped = false;  // a restart ends the events, but the state before it is still worth a checkpoint
    writeCheckpoint(r);
    r.stopped = r.stopped || was_stopped;
  }
  const bool stopped_before_end = r.stopped;
  r.stopped = false;
  writeLine(r, "end " + std::to_string(r.last_step));
  const bool ok = std::fclose(r.file) == 0 && r.message.find("write error") == std::string::npos;
  r.file = nullptr;
  r.stopped = stopped_before_end;
  if (!ok) error = r.message.empty() ? r.path.string() + ": close failed" : r.message;
  return ok;
}

void attachRecorder(ReplayRecorder& recorder, FrameHooks& hooks) {
  auto before = hooks.before_steps;
  hooks.before_steps = [&recorder, before](FrameInput& input) {
    if (before) before(input);
    recordInput(recorder, input.world, input.actions);
  };
  auto after = hooks.after_frame;
  hooks.after_frame = [&recorder, after](const FrameResult& frame) {
    const bool keep_going = after ? after(frame) : true;
    recordAfterFrame(recorder, frame.world);
    return keep_going;
  };
}

}  // namespace game
