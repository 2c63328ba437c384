#pragma once
// fluid/sph: an explosion's push on the SPH fluid, by the one blast law every consumer shares
// (fluid/core/blast.hpp: specific impulse I(r) = impulse_at_1m / r^2, held at its core_radius
// value inside the fireball, tapered to zero at reach). Applied between steps as an
// instantaneous velocity change dv = I(r) A / m along the outward direction.
//
// Cross-section: A = d^2, the face of the cube of fluid a particle stands for (the lattice of
// spacing d tiles space, m = rho_0 d^3 up to sphParticleMass's calibration). So a layer of water
// facing the blast receives exactly the impulse its area would, without the gaps a disc of the
// particle radius (pi r^2 = 0.785 d^2) would leave. Shadowing (fluid behind
// fluid) is ignored: every particle sees the centre.
//
// Stability comes from the step, not from here: the step after a blast sees the new velocities,
// so its CFL bound (dt <= cfl d / v_max) shortens it and no particle moves more than about
// cfl d per step whatever the blast speed; the end-of-step collision check (Kolb et al. 2004
// §3.3.2, with its tunnelling test) keeps particles out of colliders, thin walls included.

#include "fluid/core/blast.hpp"
#include "fluid/sph/sph.hpp"

#include <cstddef>

namespace fluid {

struct SphBlastStats {
  std::size_t particles = 0;      // particles whose velocity changed
  float max_speed_change = 0.0f;  // m/s, the largest |dv| applied
  double momentum = 0.0;          // N s, sum of m |dv| over the particles
};

// Cross-section over mass (m^2/kg) of one particle of a world with these parameters: d^2 / m.
float sphBlastAreaOverMass(const SphParams& params);

// Adds the blast's velocity change (fluid::blastVelocityChange with sphBlastAreaOverMass, capped
// at max_speed_change m/s > 0) to every particle's velocity; each particle independent, so the
// result does not depend on the thread count. Refuses, leaving the world untouched, an invalid
// blast (validateBlast's message), a cap that is not finite and > 0, or parameters that do not
// validate. `stats` is optional.
SphStatus applyBlast(SphWorld& world, const Blast& blast, float max_speed_change, SphBlastStats* stats = nullptr);

}  // namespace fluid
