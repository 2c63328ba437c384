// Emitters: CPU-side initial particle data (§3.3.1: "the initial particle data is determined
// on the CPU and can use complex algorithms, e.g. probability distributions").
#include "engine/gpu_particles/gpu_particles.hpp"

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace engine {

void BirthBatch::clear() {
  positions.clear();
  velocities.clear();
  lifetimes.clear();
  types.clear();
  spins.clear();
}

void BirthBatch::push(glm::vec3 position, glm::vec3 velocity, float lifetime, std::uint32_t type, float spin) {
  positions.push_back(position);
  velocities.push_back(velocity);
  lifetimes.push_back(lifetime);
  types.push_back(type);
  spins.push_back(spin);
}

namespace {

// Orthonormal frame around `axis` (unit).
void basis(glm::vec3 axis, glm::vec3& u, glm::vec3& v) {
  const glm::vec3 helper = std::fabs(axis.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
  u = glm::normalize(glm::cross(helper, axis));
  v = glm::cross(axis, u);
}

glm::vec3 safeDirection(glm::vec3 d) {
  const float len = glm::length(d);
  return (std::isfinite(len) && len > 1e-12f) ? d / len : glm::vec3(0.0f, 1.0f, 0.0f);
}

}  // namespace

void emit(const EmitterDesc& desc, BirthBatch& batch) {
  std::mt19937_64 rng(desc.seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const glm::vec3 axis = safeDirection(desc.direction);
  glm::vec3 u, v;
  basis(axis, u, v);
  const float two_pi = glm::two_pi<float>();
  auto inBall = [&]() {
    // Uniform in the unit ball by rejection (bounded: the acceptance rate is π/6).
    for (;;) {
      const glm::vec3 p(2.0f * unit(rng) - 1.0f, 2.0f * unit(rng) - 1.0f, 2.0f * unit(rng) - 1.0f);
      if (glm::dot(p, p) <= 1.0f) return p;
    }
  };
  for (std::uint32_t k = 0; k < desc.count; ++k) {
    const float lifetime = std::max(1e-3f, desc.lifetime * (0.75f + 0.5f * unit(rng)));
    const float spin = (unit(rng) - 0.5f) * 2.0f * glm::pi<float>();
    glm::vec3 position = desc.position + desc.radius * inBall();
    glm::vec3 velocity(0.0f);
    switch (desc.kind) {
      case EmitterKind::spray: {  // fast droplets in a cone
        const float cos_max = std::cos(std::clamp(desc.spread, 0.0f, glm::pi<float>()));
        const float c = 1.0f - unit(rng) * (1.0f - cos_max);
        const float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
        const float phi = two_pi * unit(rng);
        const glm::vec3 dir = c * axis + s * (std::cos(phi) * u + std::sin(phi) * v);
        velocity = dir * desc.speed * (0.8f + 0.4f * unit(rng));
        break;
      }
      case EmitterKind::mist: {  // slow, isotropic drift
        velocity = inBall() * desc.speed * 0.2f + axis * desc.speed * 0.1f;
        break;
      }
      case EmitterKind::splash: {  // crown: a ring thrown outwards and up around the axis
        const float phi = two_pi * unit(rng);
        const glm::vec3 radial = std::cos(phi) * u + std::sin(phi) * v;
        position = desc.position + radial * desc.radius;
        const glm::vec3 dir = safeDirection(std::cos(desc.spread) * axis + std::sin(desc.spread) * radial);
        velocity = dir * desc.speed * (0.7f + 0.6f * unit(rng));
        break;
      }
      case EmitterKind::debris: {  // explosion: isotropic, wide speed range
        velocity = safeDirection(inBall()) * desc.speed * (0.3f + 1.4f * unit(rng));
        break;
      }
    }
    batch.push(position, velocity, lifetime, desc.type, spin);
  }
}

std::size_t emitSprayFromFluid(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                               float min_speed, float jitter, float lifetime, std::uint32_t type,
                               std::uint32_t max_count, std::uint64_t seed, BirthBatch& batch) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> sym(-1.0f, 1.0f);
  const std::size_t n = std::min(positions.size(), velocities.size());
  std::size_t added = 0;
  for (std::size_t k = 0; k < n && added < max_count; ++k) {
    const glm::vec3 vel = velocities[k];
    const float speed = glm::length(vel);
    if (!std::isfinite(speed) || speed <= min_speed) continue;
    const glm::vec3 p = positions[k];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    const glm::vec3 noise(sym(rng), sym(rng), sym(rng));
    batch.push(p, vel + jitter * noise, lifetime, type, sym(rng) * glm::pi<float>());
    ++added;
  }
  return added;
}

}  // namespace engine
