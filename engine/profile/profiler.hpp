#pragma once
// Scoped CPU profiler: per-phase wall time of every frame, a ring of the last kHistory frames
// for the overlay's plot, and running statistics (mean/max/samples) for the run's summary.
// Usage per frame: beginFrame(p); { ScopedPhase s(p, Phase::physics); ... } endFrame(p);
// Time spent in the same phase several times in one frame is summed.

#include <array>
#include <chrono>
#include <cstdint>
#include <string_view>

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
  int head = 0;    // next slot to write
  int filled = 0;  // valid entries in the rings, <= kHistory
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

// Mean over the frames in which the phase ran (0 if it never ran).
double phaseMeanMs(const Profiler& profiler, Phase phase);
double frameMeanMs(const Profiler& profiler);
// Value of the ring `i` entries ago (0 = the last finished frame).
float historyAt(const Profiler& profiler, Phase phase, int frames_ago);

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
