#pragma once
// One 64-bit hash over the CPU simulation state of a World, and one per subsystem, so that a
// replay checkpoint can say which system diverged first. Hashes are of the bits (FNV-1a 64 of
// every float's bytes): two runs agree only when they are bit-identical, which the game keeps
// across runs, thread counts (fluid::par's deterministic loops) and windowed/headless runs.
//
// Hashed, per subsystem (a subsystem the scene does not list is left out):
//   rigid_bodies      every crate's transform and velocities as Bullet holds them, the pending
//                     external forces (the water's push for the next step), crates thrown
//   sph_fluid         particles in id order (id, position, velocity, density, pressure), time,
//                     step count, next id, the emitters' layer clocks, the colliders' poses and
//                     the forces they took from the water
// Left out: GPU-only state: the fluid surface's buffers and the sprite_particles effect (GPU
// state-preserving sprites: they never feed back into SPH or Bullet, and GPU float results differ
// between drivers, so a hash of them would tie a replay to one driver); the fluid surface
// mesh (derived from the particles and the camera every frame), the camera (an input, not state),
// and Bullet's internal caches (contact manifolds, sleep timers), which act on the state hashed.

#include "fluid/core/fnv1a.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace game {

struct World;

using Fnv1a64 = fluid::Fnv1a64;  // fluid/core/fnv1a.hpp

struct SubsystemHash {
  std::string_view name;  // "rigid_bodies", "sph_fluid"
  std::uint64_t value = 0;
};

struct StateHash {
  std::uint64_t combined = 0;        // over the step count and every subsystem hash, in order
  std::vector<SubsystemHash> parts;  // present subsystems only, fixed order
};

// Caller-owned scratch so hashing every checkpoint allocates nothing after the first.
struct StateHashScratch {
  std::vector<std::uint32_t> order;
};

void hashWorldState(const World& world, StateHashScratch& scratch, StateHash& out);

}  // namespace game
