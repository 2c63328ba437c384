#pragma once
// One 64-bit hash over the CPU simulation state of a World, and one per subsystem, so that a
// replay checkpoint can say which system diverged first. Hashes are of the bits (FNV-1a 64 of
// every float's bytes): two runs agree only when they are bit-identical, which the game keeps
// across runs, thread counts (fluid::par's deterministic loops) and windowed/headless runs.
//
// Each listed effect hashes what it owns (Effect::hashState, in its own file), in registry order,
// as one subsystem named after the effect; an effect with no CPU state a replay gates on adds
// nothing. Today: rigid_bodies (the crates in Bullet, the pending water forces, crates thrown),
// explosives (the charges in flight: bodies, fuse times; the detonation counts), sph_fluid (the
// particles in id order, the solver's clocks, the pump, the colliders and their forces) and blob
// (the goo, the behaviour machine, the round). Left out: GPU-only state (the sprites: GPU float
// results differ between drivers, and they never feed back), what is derived every frame (the
// surface meshes), inputs (the camera) and Bullet's internal caches (contact manifolds, sleep
// timers), which act on the state hashed.

#include "game/effects/effect_report.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace game {

struct World;

struct SubsystemHash {
  std::string_view name;  // the effect's name: "rigid_bodies", "sph_fluid", ...
  std::uint64_t value = 0;
};

struct StateHash {
  std::uint64_t combined = 0;        // over the step count and every subsystem hash, in order
  std::vector<SubsystemHash> parts;  // present subsystems only, fixed order
};

void hashWorldState(const World& world, StateHashScratch& scratch, StateHash& out);

}  // namespace game
