#include "engine/loop/fixed_step.hpp"

#include <algorithm>
#include <cmath>

namespace engine {

FixedStepClock makeFixedStepClock(const FixedStepDesc& desc) {
  FixedStepClock clock;
  clock.desc.step_seconds = std::isfinite(desc.step_seconds) ? std::clamp(desc.step_seconds, 1e-4, 0.1) : 1.0 / 60.0;
  clock.desc.substeps = std::clamp(desc.substeps, 1, 16);
  clock.desc.max_steps_per_frame = std::max(desc.max_steps_per_frame, 1);
  return clock;
}

int advanceFrame(FixedStepClock& clock, double frame_seconds) {
  if (!std::isfinite(frame_seconds) || frame_seconds < 0.0) frame_seconds = 0.0;
  clock.accumulator += std::min(frame_seconds, 0.25);
  // Small epsilon so that exactly N steps' worth of time yields N steps despite rounding.
  const double step = clock.desc.step_seconds;
  int steps = static_cast<int>(std::floor(clock.accumulator / step + 1e-9));
  if (steps > clock.desc.max_steps_per_frame) {
    steps = clock.desc.max_steps_per_frame;
    clock.accumulator = 0.0;
    ++clock.frames_dropped;
  } else {
    clock.accumulator = std::max(0.0, clock.accumulator - steps * step);
  }
  clock.steps_taken += static_cast<std::uint64_t>(steps);
  return steps;
}

double interpolationAlpha(const FixedStepClock& clock) {
  return std::clamp(clock.accumulator / clock.desc.step_seconds, 0.0, 0.999999);
}

double substepSeconds(const FixedStepClock& clock) { return clock.desc.step_seconds / clock.desc.substeps; }

}  // namespace engine
