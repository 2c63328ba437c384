#pragma once
// Scoped CPU profiler: per-phase wall time of every frame, a ring of the last kHistory frames
// for the overlay's plot, and running statistics (mean/max/samples) for the run's summary.
// Usage per frame: beginFrame(p); { ScopedPhase s(p, Phase::physics); ... } endFrame(p);
// Time spent in the same phase several times in one frame is summed.

#include <array>
#include <chrono>
#include <cstdint>
#include <string_view>
#include <vector>

namespace engine {

enum class Phase : int { input, physics, fluid, meshing, render, ui, count };
constexpr int kPhaseCount = static_cast<int>(Phase::count);
std::string_view phaseName(Phase phase);

struct PhaseStats {
  double sum_ms = 0.0;
  double max_ms = 0.0;
  std::uint64_t frames = 0;  // frames in which the phase ran at least once
};

struct Profiler {
  static constexpr int kHistory = 300;
  using Clock = std::chrono::steady_clock;

  std::array<double, kPhaseCount> current_ms{};  // this frame, so far
  std::array<bool, kPhaseCount> ran{};           // phase entered this frame
  // history[phase][i]: ms of frame (head - kHistory + i); frame_ms likewise for whole frames.
  std::array<std::array<float, kHistory>, kPhaseCount> history{};
  std::array<float, kHistory> frame_history{};
  // Warning flags: flagFrame marks the frame in progress (a system saw a clamp, a NaN/inf, ...);
  // flag_history rings with the others, the overlay draws a red marker over each flagged frame.
  std::array<std::uint8_t, kHistory> flag_history{};
  bool flagged = false;              // this frame, so far
  std::uint64_t flagged_frames = 0;  // finished frames that were flagged
  int head = 0;                      // next slot to write
  int filled = 0;                    // valid entries in the rings, <= kHistory
  std::array<PhaseStats, kPhaseCount> stats{};
  double frame_sum_ms = 0.0;
  double frame_max_ms = 0.0;
  std::uint64_t frames = 0;
  Clock::time_point frame_start{};
  bool in_frame = false;
};

void beginFrame(Profiler& profiler);
void endFrame(Profiler& profiler);
void addPhaseTime(Profiler& profiler, Phase phase, double ms);
// Marks the frame in progress as one where a warning counter fired (no-op outside a frame).
void flagFrame(Profiler& profiler);

// Mean over the frames in which the phase ran (0 if it never ran).
double phaseMeanMs(const Profiler& profiler, Phase phase);
double frameMeanMs(const Profiler& profiler);
// Value of the ring `i` entries ago (0 = the last finished frame).
float historyAt(const Profiler& profiler, Phase phase, int frames_ago);
// The flagged frames among the ring's, as frames_ago (0 = the last finished frame), oldest first:
// where the overlay's plot draws its red markers. `out` is cleared and refilled.
void flaggedFramesAgo(const Profiler& profiler, std::vector<int>& out);

class ScopedPhase {
 public:
  ScopedPhase(Profiler& profiler, Phase phase) : profiler_(profiler), phase_(phase), start_(Profiler::Clock::now()) {}
  ~ScopedPhase() {
    const auto elapsed = Profiler::Clock::now() - start_;
    addPhaseTime(profiler_, phase_, std::chrono::duration<double, std::milli>(elapsed).count());
  }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  Profiler& profiler_;
  Phase phase_;
  Profiler::Clock::time_point start_;
};

}  // namespace engine
