#include "engine/profile/profiler.hpp"

#include <algorithm>
#include <cassert>

namespace engine {

std::string_view phaseName(Phase phase) {
  switch (phase) {
    case Phase::input:
      return "input";
    case Phase::physics:
      return "physics";
    case Phase::fluid:
      return "fluid";
    case Phase::meshing:
      return "meshing";
    case Phase::render:
      return "render";
    case Phase::ui:
      return "ui";
    case Phase::count:
      break;
  }
  return "?";
}

void beginFrame(Profiler& profiler) {
  assert(!profiler.in_frame && "beginFrame twice without endFrame");
  profiler.current_ms.fill(0.0);
  profiler.ran.fill(false);
  profiler.frame_start = Profiler::Clock::now();
  profiler.in_frame = true;
}

void addPhaseTime(Profiler& profiler, Phase phase, double ms) {
  const int index = static_cast<int>(phase);
  assert(index >= 0 && index < kPhaseCount);
  profiler.current_ms[index] += std::max(ms, 0.0);
  profiler.ran[index] = true;
}

void endFrame(Profiler& profiler) {
  assert(profiler.in_frame && "endFrame without beginFrame");
  const double frame_ms =
      std::chrono::duration<double, std::milli>(Profiler::Clock::now() - profiler.frame_start).count();
  for (int p = 0; p < kPhaseCount; ++p) {
    profiler.history[p][profiler.head] = static_cast<float>(profiler.current_ms[p]);
    if (profiler.ran[p]) {
      PhaseStats& s = profiler.stats[p];
      s.sum_ms += profiler.current_ms[p];
      s.max_ms = std::max(s.max_ms, profiler.current_ms[p]);
      ++s.frames;
    }
  }
  profiler.frame_history[profiler.head] = static_cast<float>(frame_ms);
  profiler.flag_history[profiler.head] = profiler.flagged ? 1 : 0;
  profiler.flagged_frames += profiler.flagged ? 1 : 0;
  profiler.flagged = false;
  profiler.head = (profiler.head + 1) % Profiler::kHistory;
  profiler.filled = std::min(profiler.filled + 1, Profiler::kHistory);
  profiler.frame_sum_ms += frame_ms;
  profiler.frame_max_ms = std::max(profiler.frame_max_ms, frame_ms);
  ++profiler.frames;
  profiler.in_frame = false;
}

void flagFrame(Profiler& profiler) {
  if (profiler.in_frame) profiler.flagged = true;
}

void flaggedFramesAgo(const Profiler& profiler, std::vector<int>& out) {
  out.clear();
  for (int frames_ago = profiler.filled - 1; frames_ago >= 0; --frames_ago) {
    const int slot = (profiler.head - 1 - frames_ago + 2 * Profiler::kHistory) % Profiler::kHistory;
    if (profiler.flag_history[slot]) out.push_back(frames_ago);
  }
}

double phaseMeanMs(const Profiler& profiler, Phase phase) {
  const PhaseStats& s = profiler.stats[static_cast<int>(phase)];
  return s.frames == 0 ? 0.0 : s.sum_ms / static_cast<double>(s.frames);
}

double frameMeanMs(const Profiler& profiler) {
  return profiler.frames == 0 ? 0.0 : profiler.frame_sum_ms / static_cast<double>(profiler.frames);
}

float historyAt(const Profiler& profiler, Phase phase, int frames_ago) {
  if (frames_ago < 0 || frames_ago >= profiler.filled) return 0.0f;
  const int slot = (profiler.head - 1 - frames_ago + 2 * Profiler::kHistory) % Profiler::kHistory;
  return profiler.history[static_cast<int>(phase)][slot];
}

}  // namespace engine
