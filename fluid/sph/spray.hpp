#pragma once
// Internal to fluid/sph: spray (SphParams::spray_speed; Ihmsen et al. 2012, "Unified spray, foam
// and bubbles for particle-based fluids", §4: particles with fewer than 6 fluid neighbours are
// spray, moved by gravity and drag alone). Drops that leave the water fly ballistic outside the
// SPH solve, so the solve's CFL step (dt <= cfl d / v_max) follows the bulk of the water, not the
// fastest drop of a blast; they rejoin where they land among water. The spray is the last
// ParticleStore::spray_count particles of the store: the SPH units see only the first
// sphCount() (StepContext::count).
#include "fluid/sph/step_context.hpp"

namespace fluid::sph_step {

// At the step's start, after the sinks and emitters: an SPH particle faster than spray_speed
// becomes spray if it had fewer than spray_neighbours calm neighbours (no faster than
// spray_speed) in the last step, or is faster than a full step's CFL speed (cfl d /
// max_time_step) whatever its neighbours; spray that the last step's advanceSpray let back in
// rejoins (all of it when spray is off). A stable partition of every per-particle array: the SPH
// water first, the spray last, each in its old order, so the result is the same for any thread count. Counts the moves in `stats`; returns
// whether any particle moved.
bool applySprayTransitions(SphWorld& world, SphStepStats& stats);

// After the SPH collisions: slows the drops inside the water by its drag (the water takes the
// momentum; SphParams::spray_water_drag), moves the spray dt ballistic (gravity less the water's
// buoyancy, quadratic air drag, in sub-steps of at most half a spacing) with the Kolb et al. 2004
// §3.3.2 reaction against every collider at its end-of-step pose (the reactions add to the
// colliders' force and torque, like the water's), then picks the drops that rejoin at the next
// step's start: slow, on a collider or among calm water, and not crowding it (counted in
// SphStepStats::rejoins_crowded when they must wait).
// Writes old_position for the spray (sphPositionsAt) and zero density and pressure.
void advanceSpray(StepContext& context);

// After advanceSpray: each SPH particle faster than spray_speed counts its calm neighbours (the
// step's list, the end velocities) for the next step's transitions; the others are marked as
// staying (kUnknownNeighbours). Nothing when spray is off.
void countCalmNeighbours(StepContext& context);

}  // namespace fluid::sph_step
