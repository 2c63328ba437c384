// An explosion's push on the SPH particles (blast.hpp).
#include "fluid/sph/blast.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fluid {

float sphBlastAreaOverMass(const SphParams& params) {
  const float d = sphSpacing(params);
  return d * d / sphParticleMass(params);
}

SphStatus applyBlast(SphWorld& world, const Blast& blast, float max_speed_change, SphBlastStats* stats) {
  if (std::string error = validateBlast(blast); !error.empty()) return {"sph blast: " + error};
  if (!(max_speed_change > 0.0f) || !std::isfinite(max_speed_change)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "sph blast: max_speed_change = %g (need a finite value > 0 m/s)",
                  static_cast<double>(max_speed_change));
    return {buf};
  }
  if (SphStatus status = validateSphParams(world.params); !status.ok()) return status;
  const float area_over_mass = sphBlastAreaOverMass(world.params);
  const double mass = sphParticleMass(world.params);
  const std::vector<glm::vec3>& positions = world.particles.position;
  std::vector<glm::vec3>& velocities = world.particles.velocity;
  struct Sums {
    std::size_t particles = 0;
    float max_dv = 0.0f;
    double momentum = 0.0;
  };
  const Sums sums = par::parallelDeterministicReduce(
      tbb::blocked_range<std::size_t>(0, positions.size(), 512), Sums{},
      [&](const tbb::blocked_range<std::size_t>& range, Sums acc) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const glm::vec3 dv = blastVelocityChange(blast, positions[i], area_over_mass, max_speed_change);
          if (dv == glm::vec3(0.0f)) continue;  // out of reach (or a non-finite position, which the step refuses)
          velocities[i] += dv;
          const float speed = glm::length(dv);
          ++acc.particles;
          acc.max_dv = std::max(acc.max_dv, speed);
          acc.momentum += mass * speed;
        }
        return acc;
      },
      [](Sums a, const Sums& b) {
        a.particles += b.particles;
        a.max_dv = std::max(a.max_dv, b.max_dv);
        a.momentum += b.momentum;
        return a;
      });
  if (stats) {
    stats->particles = sums.particles;
    stats->max_speed_change = sums.max_dv;
    stats->momentum = sums.momentum;
  }
  return {};
}

}  // namespace fluid
