#pragma once
// Internal to fluid/sph: the pressure solvers, one tagged step each (the driver, sph_step.cpp,
// picks by SphParams::solver). Both run after the neighbour search and the boundary sampling and
// leave, for the shared advection, coupling and collision phases:
//  - particles.velocity: the end-of-step velocities; context.dt the step length;
//  - particles.density / pressure; scratch.kappa (boundary impulse per particle) and
//    scratch.old_position (step-start positions);
//  - context.advected / coupled when they already advected the particles or summed the coupling
//    forces in their last pass; the stats' density error, iteration counts and max_acceleration.
#include "fluid/sph/step_context.hpp"

namespace fluid::sph_step {

// Weakly compressible SPH, Becker & Teschner 2007 (wcsph.cpp).
void stepWcsph(StepContext& context);

// Divergence-free SPH, Bender & Koschier 2015 / 2017 (dfsph.cpp).
void stepDfsph(StepContext& context);

}  // namespace fluid::sph_step
