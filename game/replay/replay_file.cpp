// Replay file parser and line writers (format: replay_file.hpp, docs/replay.md).
#include "game/replay/replay_file.hpp"

#include "fluid/core/fnv1a.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace game {
namespace {

// Limits that keep every number a replay carries far inside what the game handles.
constexpr std::uint64_t kMaxStep = 100'000'000;  // ~19 days at 60 Hz
constexpr double kMaxCoordinate = 1e6;           // m
constexpr double kMaxAngle = 1e6;                // degrees (yaw may wind up over a long tour)

struct LineParser {
  const std::string& label;
  int line = 0;
  std::string error;

  bool fail(std::string_view field, const std::string& what) {
    // The field may come from the file (an unknown record's keyword): printable, no quotes, short.
    std::string name;
    for (char c : field.substr(0, 40)) name += (c > 32 && c < 127 && c != '\'') ? c : '?';
    error = label + ":" + std::to_string(line) + ": field '" + name + "': " + what;
    return false;
  }
};

std::vector<std::string_view> splitTokens(std::string_view text) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
    if (i > start) tokens.push_back(text.substr(start, i - start));
  }
  return tokens;
}

std::string quoted(std::string_view token) {
  std::string out = "'";
  for (char c : token.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
  if (token.size() > 40) out += "...";
  return out + "'";
}

bool parseStep(LineParser& p, std::string_view field, std::string_view token, std::uint64_t& out) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  if (ec != std::errc() || end != token.data() + token.size())
    return p.fail(field, "expected a step number (unsigned integer), got " + quoted(token));
  if (out > kMaxStep) return p.fail(field, "step " + std::string(token) + " exceeds " + std::to_string(kMaxStep));
  return true;
}

bool parseFloat(LineParser& p, std::string_view field, std::string_view token, double limit, float& out) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size())
    return p.fail(field, "expected a number, got " + quoted(token));
  if (!std::isfinite(value)) return p.fail(field, "non-finite value " + quoted(token));
  if (std::abs(value) > limit) {
    char range[64];
    std::snprintf(range, sizeof range, " outside [-%g, %g]", limit, limit);
    return p.fail(field, "value " + quoted(token) + range);
  }
  // Written with float round-trip precision (formatCameraLine): the nearest float is the value.
  out = static_cast<float>(value);
  return true;
}

bool parseHash(LineParser& p, std::string_view field, std::string_view token, std::uint64_t& out) {
  if (token.size() != 16) return p.fail(field, "expected 16 hex digits, got " + quoted(token));
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out, 16);
  if (ec != std::errc() || end != token.data() + token.size() ||
      !std::all_of(token.begin(), token.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); }))
    return p.fail(field, "expected 16 hex digits, got " + quoted(token));
  return true;
}

bool expectCount(LineParser& p, std::string_view field, const std::vector<std::string_view>& tokens, std::size_t count,
                 std::string_view usage) {
  if (tokens.size() == count) return true;
  return p.fail(field, "expected '" + std::string(usage) + "', got " + std::to_string(tokens.size() - 1) + " value(s)");
}

bool parseCheckpoint(LineParser& p, const std::vector<std::string_view>& tokens, ReplayEvent& event) {
  event.kind = ReplayEventKind::checkpoint;
  if (tokens.size() < 2) return p.fail("checkpoint", "expected 'checkpoint STEP [HASH name=HASH ...]'");
  if (!parseStep(p, "checkpoint.step", tokens[1], event.step)) return false;
  if (tokens.size() == 2) return true;  // placeholder, filled in by --update-hashes
  event.has_hash = true;
  if (!parseHash(p, "checkpoint.hash", tokens[2], event.hash)) return false;
  for (std::size_t i = 3; i < tokens.size(); ++i) {
    const std::size_t eq = tokens[i].find('=');
    if (eq == std::string_view::npos || eq == 0)
      return p.fail("checkpoint", "expected a subsystem hash 'name=HASH', got " + quoted(tokens[i]));
    NamedHash part;
    part.name = std::string(tokens[i].substr(0, eq));
    if (!parseHash(p, "checkpoint." + part.name, tokens[i].substr(eq + 1), part.value)) return false;
    for (const NamedHash& seen : event.parts)
      if (seen.name == part.name) return p.fail("checkpoint." + part.name, "subsystem listed twice");
    event.parts.push_back(std::move(part));
  }
  return true;
}

// Header records: version, scene, scene_hash, set, step_hz, seed. Returns false on error; sets
// `handled` when the keyword was a header keyword.
bool parseHeader(LineParser& p, const std::vector<std::string_view>& tokens, ReplayFile& out, bool& handled) {
  const std::string_view key = tokens[0];
  handled = true;
  if (key == "scene") {
    if (!out.scene.empty()) return p.fail("scene", "given twice");
    if (!expectCount(p, "scene", tokens, 2, "scene NAME_OR_PATH")) return false;
    out.scene = std::string(tokens[1]);
    out.scene_line = p.line;
    return true;
  }
  if (key == "scene_hash") {
    if (out.has_scene_hash) return p.fail("scene_hash", "given twice");
    if (!expectCount(p, "scene_hash", tokens, 2, "scene_hash HEX16")) return false;
    out.has_scene_hash = true;
    out.scene_hash_line = p.line;
    return parseHash(p, "scene_hash", tokens[1], out.scene_hash);
  }
  if (key == "set") {
    if (!expectCount(p, "set", tokens, 2, "set section.key=value")) return false;
    if (tokens[1].find('=') == std::string_view::npos || tokens[1].find('.') == std::string_view::npos)
      return p.fail("set", "expected 'section.key=value', got " + quoted(tokens[1]));
    out.sets.emplace_back(tokens[1]);
    out.set_lines.push_back(p.line);
    return true;
  }
  if (key == "step_hz") {
    if (out.step_hz > 0.0) return p.fail("step_hz", "given twice");
    if (!expectCount(p, "step_hz", tokens, 2, "step_hz HZ")) return false;
    float hz = 0.0f;
    if (!parseFloat(p, "step_hz", tokens[1], 1e6, hz)) return false;
    if (!(hz >= 1.0f && hz <= 10000.0f)) return p.fail("step_hz", "value " + quoted(tokens[1]) + " outside [1, 10000]");
    out.step_hz = hz;
    out.step_hz_line = p.line;
    return true;
  }
  if (key == "seed") {
    if (out.seed_line > 0) return p.fail("seed", "given twice");
    out.seed_line = p.line;
    if (!expectCount(p, "seed", tokens, 2, "seed N")) return false;
    const auto [end, ec] = std::from_chars(tokens[1].data(), tokens[1].data() + tokens[1].size(), out.seed);
    if (ec != std::errc() || end != tokens[1].data() + tokens[1].size() || out.seed < 0)
      return p.fail("seed", "expected a non-negative integer, got " + quoted(tokens[1]));
    return true;
  }
  handled = false;
  return true;
}

bool parseEvent(LineParser& p, const std::vector<std::string_view>& tokens, ReplayEvent& event, bool& handled) {
  const std::string_view key = tokens[0];
  handled = true;
  event.line = p.line;
  if (key == "camera") {
    event.kind = ReplayEventKind::camera;
    if (!expectCount(p, "camera", tokens, 7, "camera STEP X Y Z YAW PITCH")) return false;
    return parseStep(p, "camera.step", tokens[1], event.step) &&
           parseFloat(p, "camera.x", tokens[2], kMaxCoordinate, event.position.x) &&
           parseFloat(p, "camera.y", tokens[3], kMaxCoordinate, event.position.y) &&
           parseFloat(p, "camera.z", tokens[4], kMaxCoordinate, event.position.z) &&
           parseFloat(p, "camera.yaw", tokens[5], kMaxAngle, event.yaw_degrees) &&
           parseFloat(p, "camera.pitch", tokens[6], 90.0, event.pitch_degrees);
  }
  if (key == "action") {
    event.kind = ReplayEventKind::action;
    if (!expectCount(p, "action", tokens, 3, "action STEP NAME")) return false;
    if (!parseStep(p, "action.step", tokens[1], event.step)) return false;
    if (!parsePlayerAction(tokens[2], event.action))
      return p.fail("action.name", "unknown action " + quoted(tokens[2]) + " (known: throw_crate, throw_explosive)");
    return true;
  }
  if (key == "checkpoint") return parseCheckpoint(p, tokens, event);
  handled = false;
  return true;
}

// Checks that every required header record is present (called at the first event and at `end`).
bool headerComplete(LineParser& p, const ReplayFile& out) {
  if (out.scene.empty()) return p.fail("scene", "missing from the header (expected 'scene NAME' before any event)");
  if (!out.has_scene_hash) return p.fail("scene_hash", "missing from the header");
  if (out.step_hz <= 0.0) return p.fail("step_hz", "missing from the header");
  if (out.seed_line == 0) return p.fail("seed", "missing from the header");
  return true;
}

}  // namespace

ReplayStatus parseReplayText(std::string_view text, const std::string& label, ReplayFile& out) {
  out = ReplayFile{};
  out.label = label;
  LineParser p{label, 0, {}};
  bool seen_version = false, in_events = false, seen_end = false;
  std::uint64_t last_step = 0;
  int last_step_line = 0;
  auto fail = [&](std::string_view field, const std::string& what) {
    p.fail(field, what);
    return ReplayStatus{p.error, 1};
  };
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t newline = text.find('\n', pos);
    ++p.line;
    if (newline == std::string_view::npos)
      return fail("end", "the last line has no newline at its end (file truncated?)");
    std::string_view content = text.substr(pos, newline - pos);
    pos = newline + 1;
    if (!content.empty() && content.back() == '\r') content.remove_suffix(1);
    if (const std::size_t hash = content.find('#'); hash != std::string_view::npos) content = content.substr(0, hash);
    if (content.find('\0') != std::string_view::npos) return fail("line", "contains a NUL byte");
    const std::vector<std::string_view> tokens = splitTokens(content);
    if (tokens.empty()) continue;
    if (seen_end) return fail(tokens[0], "record after 'end' (end must be the last record)");
    if (!seen_version) {
      if (tokens[0] != "fluiddemo_replay")
        return fail("fluiddemo_replay",
                    "the first record must be 'fluiddemo_replay VERSION', got " + quoted(tokens[0]));
      if (tokens.size() != 2 || tokens[1] != std::to_string(kReplayFormatVersion))
        return fail("fluiddemo_replay", "unknown format version " + quoted(tokens.size() > 1 ? tokens[1] : "") +
                                            " (this build reads version " + std::to_string(kReplayFormatVersion) + ")");
      out.version = kReplayFormatVersion;
      seen_version = true;
      continue;
    }
    if (tokens[0] == "fluiddemo_replay") return fail("fluiddemo_replay", "given twice");
    bool handled = false;
    if (!parseHeader(p, tokens, out, handled)) return {p.error, 1};
    if (handled) {
      if (in_events) return fail(tokens[0], "header record after the first event (move it above the events)");
      continue;
    }
    if (tokens[0] == "end") {
      if (!headerComplete(p, out)) return {p.error, 1};
      if (tokens.size() != 2) return fail("end", "expected 'end STEP'");
      if (!parseStep(p, "end.step", tokens[1], out.end_step)) return {p.error, 1};
      if (out.end_step < last_step)
        return fail("end.step", "end " + std::to_string(out.end_step) + " is before the event at step " +
                                    std::to_string(last_step) + " (line " + std::to_string(last_step_line) + ")");
      if (out.end_step == 0) return fail("end.step", "a replay needs at least one step");
      seen_end = true;
      continue;
    }
    ReplayEvent event;
    if (!parseEvent(p, tokens, event, handled)) return {p.error, 1};
    if (!handled) return fail(tokens[0], "unknown record " + quoted(tokens[0]));
    if (!in_events) {
      if (!headerComplete(p, out)) return {p.error, 1};
      in_events = true;
    }
    if (event.kind == ReplayEventKind::checkpoint && event.step == 0)
      return fail("checkpoint.step", "a checkpoint is the state after STEP steps: STEP must be >= 1");
    if (event.step < last_step)
      return fail(std::string(tokens[0]) + ".step", "step " + std::to_string(event.step) + " goes backwards (line " +
                                                        std::to_string(last_step_line) + " is at step " +
                                                        std::to_string(last_step) + ")");
    last_step = event.step;
    last_step_line = p.line;
    out.events.push_back(std::move(event));
  }
  if (!seen_version) {
    p.line = std::max(p.line, 1);
    return fail("fluiddemo_replay", "empty file: no records (expected 'fluiddemo_replay 1' first)");
  }
  if (!seen_end) {
    ++p.line;
    return fail("end",
                "missing 'end STEP' record (file truncated? a recording cut short keeps its events: append "
                "'end STEP' to replay it)");
  }
  return {};
}

bool readTextFile(const std::filesystem::path& path, std::string& out, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path.string() + ": cannot open: " + std::strerror(errno);
    return false;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    error = path.string() + ": read error";
    return false;
  }
  out = std::move(buffer).str();
  return true;
}

ReplayStatus loadReplayFile(const std::filesystem::path& path, ReplayFile& out) {
  std::string text, error;
  if (!readTextFile(path, text, error)) return {error, 1};
  return parseReplayText(text, path.string(), out);
}

std::uint64_t fnv1a64(std::string_view bytes) {
  return fluid::fnv1a64(bytes.data(), bytes.size());
}

std::string hashHex(std::uint64_t value) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

bool cameraPoseAt(const ReplayFile& replay, std::uint64_t step, CameraPose& out) {
  const ReplayEvent* before = nullptr;  // last keyframe with step < `step`
  const ReplayEvent* after = nullptr;   // first keyframe with step >= `step`
  // Events are in non-decreasing step order: binary search to the first event at `step` or later.
  const auto first = std::lower_bound(replay.events.begin(), replay.events.end(), step,
                                      [](const ReplayEvent& e, std::uint64_t s) { return e.step < s; });
  for (auto it = first; it != replay.events.begin();) {
    --it;
    if (it->kind == ReplayEventKind::camera) {
      before = &*it;
      break;
    }
  }
  for (auto it = first; it != replay.events.end(); ++it) {
    if (it->kind == ReplayEventKind::camera) {
      after = &*it;
      break;
    }
  }
  const ReplayEvent* only = nullptr;
  if (before == nullptr) only = after;
  if (after == nullptr) only = before;
  if (after != nullptr && after->step == step) only = after;
  if (only != nullptr || before == nullptr) {
    if (only == nullptr) return false;
    out = {only->position, only->yaw_degrees, only->pitch_degrees};
    return true;
  }
  const float t =
      static_cast<float>(static_cast<double>(step - before->step) / static_cast<double>(after->step - before->step));
  out.position = before->position + (after->position - before->position) * t;
  out.yaw_degrees = before->yaw_degrees + (after->yaw_degrees - before->yaw_degrees) * t;
  out.pitch_degrees = before->pitch_degrees + (after->pitch_degrees - before->pitch_degrees) * t;
  return true;
}

std::string formatCameraLine(std::uint64_t step, const CameraPose& pose) {
  // %.9g: enough digits that the parser's nearest float is the recorded float.
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, "camera %llu %.9g %.9g %.9g %.9g %.9g", static_cast<unsigned long long>(step),
                pose.position.x, pose.position.y, pose.position.z, pose.yaw_degrees, pose.pitch_degrees);
  return buffer;
}

std::string formatCheckpointLine(std::uint64_t step, std::uint64_t hash, const std::vector<NamedHash>& parts) {
  std::string line = "checkpoint " + std::to_string(step) + " " + hashHex(hash);
  for (const NamedHash& part : parts) line += " " + part.name + "=" + hashHex(part.value);
  return line;
}

}  // namespace game
