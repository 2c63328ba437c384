#pragma once
// One model of an explosive's push, shared by everything a blast reaches (SPH water, the blob
// monster's particles, Bullet bodies, GPU sprites), so a blast throws a crate and the water beside
// it consistently.
//
// The blast delivers a momentum per unit area (specific impulse, Pa s) that spreads over a sphere:
// I(r) = impulse_at_1m / r^2. A body of cross-section A facing the blast receives I(r) A, so a
// particle of mass m and cross-section A gains dv = I(r) A / m along the outward direction.
// Measured blast waves fall off between 1/r and 1/r^2 (Kinney & Graham, "Explosive Shocks in Air",
// 1985, ch. 7); the steeper law keeps the push local, which suits a hand grenade in a fountain.
// Inside core_radius (the fireball) the impulse is held at its core_radius value rather than
// growing without bound, and it tapers to zero over the outer fifth of `reach` so that nothing
// changes discontinuously when an object drifts across the edge.

#include <glm/glm.hpp>

#include <cmath>
#include <string>

namespace fluid {

struct Blast {
  glm::vec3 centre{0.0f};
  float impulse_at_1m = 60.0f;  // Pa s: specific impulse 1 m from the centre
  float core_radius = 0.25f;    // m: the impulse is capped at its value here
  float reach = 4.0f;           // m: no impulse beyond this distance
};

// Empty when usable; otherwise names the bad field and value.
inline std::string validateBlast(const Blast& blast) {
  const glm::vec3& c = blast.centre;
  if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return "blast.centre is not finite";
  if (!(blast.impulse_at_1m >= 0.0f) || !std::isfinite(blast.impulse_at_1m))
    return "blast.impulse_at_1m = " + std::to_string(blast.impulse_at_1m) + " (need a finite value >= 0)";
  if (!(blast.core_radius > 0.0f) || !std::isfinite(blast.core_radius))
    return "blast.core_radius = " + std::to_string(blast.core_radius) + " (need a finite value > 0)";
  if (!(blast.reach > blast.core_radius) || !std::isfinite(blast.reach))
    return "blast.reach = " + std::to_string(blast.reach) + " (need a finite value > core_radius)";
  return {};
}

// Specific impulse (Pa s) at `distance` from the centre.
inline float blastImpulsePerArea(const Blast& blast, float distance) {
  if (!(distance < blast.reach)) return 0.0f;
  const float r = std::max(distance, blast.core_radius);
  const float taper_start = 0.8f * blast.reach;
  float taper = 1.0f;
  if (distance > taper_start) {
    const float t = (blast.reach - distance) / (blast.reach - taper_start);  // 1 -> 0 across the band
    taper = t * t * (3.0f - 2.0f * t);                                      // smoothstep: C1 at both ends
  }
  return blast.impulse_at_1m / (r * r) * taper;
}

// Unit vector from the centre to `point`; straight up for a point at the centre itself, where the
// direction is undefined (an explosive resting on the ground throws upward).
inline glm::vec3 blastDirection(const Blast& blast, glm::vec3 point) {
  const glm::vec3 d = point - blast.centre;
  const float length = std::sqrt(glm::dot(d, d));
  if (!(length > 1e-6f)) return {0.0f, 1.0f, 0.0f};
  return d / length;
}

// Velocity change of a particle at `point` whose cross-section over mass is `area_over_mass`
// (m^2/kg); capped at `max_speed_change` (m/s) so a particle sitting in the fireball does not
// leave with an unbounded speed.
inline glm::vec3 blastVelocityChange(const Blast& blast, glm::vec3 point, float area_over_mass,
                                     float max_speed_change) {
  const float distance = glm::length(point - blast.centre);
  const float dv = std::min(blastImpulsePerArea(blast, distance) * area_over_mass, max_speed_change);
  if (!(dv > 0.0f)) return glm::vec3(0.0f);
  return dv * blastDirection(blast, point);
}

}  // namespace fluid
