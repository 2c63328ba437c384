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

// A particle the last collision pass still moved is caught between faces whose pushes undo each
// other: a crate's side pressed against the basin rim, or a crate resting on the basin floor with
// water under its edge, each projection along the face it met handing the particle back to the
// other. The moving collider's nearest exit at `x` (a face the passes did not follow) can still be
// free: `x` moves to the first moving collider's exit that lies outside every collider (at `poses`,
// their end-of-step poses) and true is returned; otherwise `x` stays where the still collider put it
// (still colliders win). Used by the water's passes and the spray's (spray.cpp).
bool escapeSqueeze(const StepContext& context, const std::vector<ColliderPose>& poses, float skin, glm::vec3& x);

}  // namespace fluid::sph_step
