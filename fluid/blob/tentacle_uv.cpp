// u around the tentacles (see fluid/blob/tentacle_uv.hpp for why this is a pass after meshing).
#include "fluid/blob/tentacle_uv.hpp"

#include "fluid/core/parallel.hpp"

#include <cmath>

namespace fluid {

void blobTentacleU(SurfaceMesh& mesh, const BlobWorld& world, glm::vec3 origin, float min_share) {
  const BlobParticles& parts = world.particles;
  std::vector<std::uint32_t> chain_particles;
  for (const auto& chain : world.target.tentacle_particles)
    chain_particles.insert(chain_particles.end(), chain.begin(), chain.end());
  if (chain_particles.empty() || mesh.attributes.size() != mesh.positions.size()) return;
  constexpr float kTwoPi = 6.28318530717958f;
  // Per vertex, independent: the result does not depend on the thread count.
  par::parallelFor(par::Range<std::size_t>(0, mesh.positions.size(), 512), [&](const par::Range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      glm::vec4& attr = mesh.attributes[k];
      if (attr.z < min_share) continue;
      const glm::vec3 p = mesh.positions[k] + origin;
      std::uint32_t best = chain_particles[0];
      float best_d2 = INFINITY;
      for (std::uint32_t i : chain_particles) {
        const glm::vec3 d = p - parts.position[i];
        const float d2 = glm::dot(d, d);
        if (d2 < best_d2) best_d2 = d2, best = i;
      }
      const glm::vec3 t = parts.tangent[best];
      const glm::vec3 n = parts.normal[best];
      const glm::vec3 rel = p - parts.position[best];
      const float angle = std::atan2(glm::dot(rel, glm::cross(t, n)), glm::dot(rel, n));  // (-pi, pi]
      float u = angle / kTwoPi + 0.5f;
      if (u >= 1.0f) u = 0.0f;
      attr.x = u;
    }
  });
}

}  // namespace fluid
