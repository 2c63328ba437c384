#pragma once
// Internal to fluid/sph: the step's first phase. Sinks remove particles (SphSink), emitters add
// layers of them (SphEmitter, sph.hpp says when a lattice point is skipped), and the input check
// shares the sinks' pass over the particles.
#include "fluid/sph/sph.hpp"

#include <cstddef>

namespace fluid::sph_step {

// Validation and the sink test in one parallel pass. Returns the refusal naming the first
// particle with a non-finite position or velocity (the world is left untouched), otherwise
// marks scratch.keep[i] = 0 for the particles inside a sink box and returns their count in
// `in_sinks` (applySinks removes them). `nonfinite`: how many particles are non-finite.
SphStatus checkFiniteAndSinks(SphWorld& world, std::size_t& in_sinks, std::size_t& nonfinite);

// Removes the particles checkFiniteAndSinks marked (`in_sinks` of them), keeping the survivors'
// order: into the pump (`pumped` of them) or out of the world; returns the count removed.
std::size_t applySinks(SphWorld& world, std::size_t in_sinks, std::size_t& pumped);

// Emits the layers every emitter owes (its accumulator); returns the count of particles added.
std::size_t applyEmitters(SphWorld& world);

// Adds the part of [world.time, world.time + dt) during which each emitter is active to its
// accumulator.
void advanceEmitterClocks(SphWorld& world, float dt);

}  // namespace fluid::sph_step
