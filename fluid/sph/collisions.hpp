#pragma once
// Internal to fluid/sph: colliders as hard constraints at the end of a step (Kolb et al. 2004
// §3.3.2 double check, fluid::resolveCollision), and the pose a collider reaches during a step.
#include "fluid/sph/step_context.hpp"

namespace fluid::sph_step {

// pose advanced by its linear and angular velocity over dt.
ColliderPose advancedPose(const ColliderPose& pose, float dt);

// Projects every particle out of every collider at the collider's end-of-step pose (reflecting
// its velocity), accumulates the reactions into each collider's force/torque and counts them in
// context.stats.collisions. Reads scratch.start_samples and old_position (the step start).
void resolveCollisions(StepContext& context);

}  // namespace fluid::sph_step
