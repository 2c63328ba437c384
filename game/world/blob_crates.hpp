#pragma once
// The blob's goo and the crates, both ways (Bullet boxes; the water's coupling,
// game/world/body_fluid_coupling.hpp, is the model and lends its stability cap):
//  1. before the goo's step, the crates near the body join its colliders after the level's, at their
//     Bullet pose and velocity, so a thrown crate dents the blob;
//  2. after it, the momentum the particles lost to each crate becomes a force and torque on the
//     crate for the next physics step, capped at kBlobCrateForceLimit times the buoyancy of the fully
//     submerged crate (rho |g| V), the torque at that force times the half diagonal. Within one step
//     the crate is a kinematic collider, so a falling crate drags every particle it meets to its own
//     speed and the momentum handed back can exceed what the crate brought (measured: 1,266 N s in 3
//     steps on a 54 kg crate dropped 2.5 m, which Bullet fires away upward without the cap).

#include "game/world/blob_monster.hpp"
#include "game/world/rigid_bodies.hpp"

namespace game {

constexpr float kBlobCrateForceLimit = 3.0f;

// Step 1: world.colliders keeps the level's [0, level_colliders) and gets the crates in reach after it
// (BlobMonster::crate_of_collider says which crate each is).
void blobCollidersFromCrates(BlobMonster& blob, const RigidBodies& bodies);

// Step 2: each crate collider's impulse over the step just run, as a capped force and torque on its
// crate (BlobMonster::crate_forces_capped counts the caps).
void blobImpulsesToCrates(BlobMonster& blob, RigidBodies& bodies, double step_seconds);

}  // namespace game
