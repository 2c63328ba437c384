#pragma once
// Fixed simulation step decoupled from rendering (the classic accumulator): the simulation
// always advances in whole steps of `step_seconds` (optionally split into substeps), and
// rendering interpolates between the last two simulated states with `alpha`.
// Same sequence of frame times in -> same sequence of steps out, so runs are deterministic.

#include <cstdint>

namespace engine {

struct FixedStepDesc {
  double step_seconds = 1.0 / 60.0;  // simulation step; clamped to [1e-4, 0.1]
  int substeps = 1;                  // physics substeps per step; clamped to [1, 16]
  int max_steps_per_frame = 5;       // avoids the spiral of death after a hitch; >= 1
};

struct FixedStepClock {
  FixedStepDesc desc;
  double accumulator = 0.0;
  std::uint64_t steps_taken = 0;
  std::uint64_t frames_dropped = 0;  // frames whose backlog was discarded
};

FixedStepClock makeFixedStepClock(const FixedStepDesc& desc);

// Adds `frame_seconds` of real time (negative/NaN treated as 0, capped at 0.25 s) and returns
// how many whole steps to simulate now. Backlog beyond max_steps_per_frame is dropped.
int advanceFrame(FixedStepClock& clock, double frame_seconds);

// Interpolation factor in [0, 1) between the previous and the current simulated state.
double interpolationAlpha(const FixedStepClock& clock);

double substepSeconds(const FixedStepClock& clock);

}  // namespace engine
