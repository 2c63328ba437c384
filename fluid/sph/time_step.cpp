// The adaptive time step (time_step.hpp).
#include "fluid/sph/time_step.hpp"

#include <algorithm>
#include <cmath>

namespace fluid::sph_step {

float chooseTimeStep(const StepContext& context, float max_speed, float max_acceleration, bool wcsph_bounds,
                     bool spread, bool* held_at_min) {
  const SphParams& params = context.params;
  const float d = context.spacing;
  const float max_dt = context.max_dt;
  float t = max_dt;
  if (max_speed > 0.0f) t = std::min(t, params.cfl * d / max_speed);
  // A wall closing on the water advances at most half a spacing per step (at most cfl d): the
  // end-of-step push-out and the speculative contacts follow each particle's nearest face, which a
  // crate's edge sweeping past further does not stay.
  if (context.wall_approach_speed > 0.0f)
    t = std::min(t, std::min(params.cfl, 0.5f) * d / context.wall_approach_speed);
  // Force condition: a step may compress the fluid by at most ~0.1 % of d (at cfl = 0.4) from the
  // non-pressure acceleration alone (|a| dt^2 <= 0.0025 cfl d). The pressure solvers stop at a
  // mean density error tolerance, so a larger per-step compression (a resting column under
  // gravity, which the CFL velocity bound does not limit) is left partly unresolved every step and
  // builds up into noise.
  const float body = glm::length(params.gravity);
  if (body > 0.0f && params.force_bound > 0.0f) t = std::min(t, std::sqrt(params.force_bound * params.cfl * d / body));
  // Explicit viscosity stability (diffusion number): dt <= 0.125 d^2 / nu (Morris et al. 1997).
  if (params.viscosity > 0.0f) t = std::min(t, 0.125f * d * d / params.viscosity);
  if (wcsph_bounds) {
    // Becker & Teschner 2007 §4: dt <= 0.4 h / (c_s (1 + 0.6 alpha)), dt <= 0.25 sqrt(h / |a|max)
    // with the total acceleration (pressure included); their smoothing length h is d (support 2h = H).
    const float h = d;
    t = std::min(t, 0.4f * h / (params.sound_speed * (1.0f + 0.6f * params.artificial_viscosity)));
    if (max_acceleration > 0.0f) t = std::min(t, 0.25f * std::sqrt(h / max_acceleration));
  }
  const float floor_dt = std::min(params.min_time_step, max_dt);  // the caller's bound wins over min_time_step
  if (held_at_min) *held_at_min = t < floor_dt;
  t = std::max(t, floor_dt);
  // stepSphWithin: the time left to the caller's target is split into equal steps no longer
  // than t, and this step is one of them, so the last step of a frame is never a sliver. DFSPH's
  // constant-density solve removes the whole predicted compression within one step (Bender &
  // Koschier 2015 §4.2, eq. 8-12: kappa ~ (rho* - rho_0) / dt^2, a velocity change
  // ~ (rho* - rho_0) / dt), so in a sliver the compression the tolerance leaves standing would
  // become metres per second. With equal steps each step is at least half of t (the next bound
  // may differ, then the rest is split again).
  // (The 1e-5 slack: max_dt is the float of span, which may round below it.)
  const double span = context.span;
  if (spread && span > static_cast<double>(t))
    t = static_cast<float>(span / std::ceil(span / static_cast<double>(t) * (1.0 - 1e-5)));
  return t;
}

}  // namespace fluid::sph_step
