#pragma once
// Internal to fluid/sph: the adaptive time step of one SPH step.
#include "fluid/sph/step_context.hpp"

namespace fluid::sph_step {

// The step length for a fastest particle speed `max_speed` (m/s; the colliders' approach near the
// fluid is bounded from context.wall_approach_speed) and the largest total acceleration `max_acceleration`
// (m/s^2, read only with wcsph_bounds): the minimum of context.max_dt, the CFL condition, the
// force condition, the viscosity condition and (wcsph_bounds) Becker & Teschner 2007 §4; never
// below min_time_step unless the caller asked for less. `spread`: stepSphWithin's equal split of
// context.span (see the definition). `held_at_min` (optional): set to whether the bounds asked for
// less than min_time_step, so the step was held at it.
float chooseTimeStep(const StepContext& context, float max_speed, float max_acceleration, bool wcsph_bounds,
                     bool spread = true, bool* held_at_min = nullptr);

}  // namespace fluid::sph_step
