#pragma once
// Internal to fluid/sph: the step's neighbour search (grid, re-sort by cell, lists).
#include "fluid/sph/step_context.hpp"

namespace fluid::sph_step {

// Builds (or, for WCSPH's Verlet list, reuses) the neighbour lists, re-sorting the particle data
// by grid cell when it rebuilds; writes the 16-byte position and velocity copies the pair loops
// read (scratch.pos4 / vel4) and the context's list pointers. `store_changed`: sinks or emitters
// changed the particle set this step (a Verlet list is then rebuilt).
void updateNeighbours(StepContext& context, bool store_changed);

}  // namespace fluid::sph_step
