#include "game/world/sprite_particles.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

namespace game {
namespace {

// Uniform in [0, 1) from the generator's raw bits: the same sequence on every standard library
// (std::uniform_real_distribution is implementation-defined).
float uniform01(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

constexpr float kDeepPenetration = 0.02f;  // m

bool isInside(const fluid::SignedDistanceShape& shape, glm::vec3 point) {
  fluid::ColliderSample sample;
  shape.query(std::span(&point, 1), std::span(&sample, 1));
  return sample.valid && sample.distance < 0.0f;
}

// Collision of particle i after integration (Kolb et al. 2004 §3.3.2 double check); returns 1
// when it reacted or was pushed out. Touches only particle i's entries.
int collideParticle(SpriteParticles& s, const fluid::SignedDistanceShape& shape,
                    const fluid::CollisionMaterial& material, float dt, std::size_t i) {
  int bounced = 0;
  constexpr float skin = 1e-3f;
  s.previous[i] = s.position[i];
  // Shallow penetrations (a resting particle sinks g*dt^2, about 3 mm, per step) are left to
  // the plain projection; only a deep one can have crossed a thin part.
  if (s.previous_samples[i].distance >= 0.0f && s.predicted_samples[i].valid &&
      s.predicted_samples[i].distance < -kDeepPenetration) {
    // Outside before, inside after: move the predicted point back to where the path first
    // enters the shape (bisection on the segment), so a fast particle crossing a thin part
    // (the dish floor is 0.23 m, a jet particle moves up to ~0.15 m per step) is reflected
    // off the side it came from instead of being projected out of the far side.
    float outside = 0.0f, inside = 1.0f;
    const glm::vec3 start = s.position[i], path = s.predicted[i] - s.position[i];
    for (int k = 0; k < 8; ++k) {
      const float mid = 0.5f * (outside + inside);
      (isInside(shape, start + path * mid) ? inside : outside) = mid;
    }
    s.predicted[i] = start + path * inside;
    shape.query(std::span(&s.predicted[i], 1), std::span(&s.predicted_samples[i], 1));
  }
  const fluid::CollisionResult result =
      fluid::resolveCollision(s.position[i], s.previous_samples[i], s.predicted[i], s.velocity[i],
                              s.predicted_samples[i], glm::vec3(0.0f), dt, skin, material);
  s.position[i] = result.position;
  s.velocity[i] = result.velocity;
  if (result.outcome != fluid::CollisionOutcome::none) {
    bounced = 1;
    // Across the CSG joins of the shape the field underestimates the true distance, so one
    // projection can stop short of the surface; a few more finish the push-out.
    for (int k = 0; k < 4; ++k) {
      fluid::ColliderSample sample;
      shape.query(std::span(&s.position[i], 1), std::span(&sample, 1));
      if (!sample.valid || sample.distance >= 0.0f) break;
      s.position[i] += sample.normal * (skin - sample.distance);
    }
  }
  s.age[i] += dt;
  return bounced;
}

}  // namespace

SpriteParticleParams spriteParamsFrom(const SectionConfig& section, glm::vec3 gravity, glm::vec3 nozzle) {
  SpriteParticleParams p;
  p.rate = static_cast<float>(section.number("rate"));
  p.speed = static_cast<float>(section.number("speed"));
  p.spread_degrees = static_cast<float>(section.number("spread_degrees"));
  p.lifetime = static_cast<float>(section.number("lifetime"));
  p.size = static_cast<float>(section.number("size"));
  p.restitution = static_cast<float>(section.number("restitution"));
  p.gravity = gravity;
  p.nozzle = nozzle;
  return p;
}

void initSpriteParticles(SpriteParticles& particles, const SpriteParticleParams& params, std::size_t capacity,
                         std::uint32_t seed) {
  particles = SpriteParticles{};
  particles.params = params;
  particles.capacity = capacity;
  particles.rng.seed(seed);
  particles.position.resize(capacity);
  particles.previous.resize(capacity);
  particles.velocity.resize(capacity);
  particles.age.resize(capacity);
  particles.predicted.resize(capacity);
  particles.previous_samples.resize(capacity);
  particles.predicted_samples.resize(capacity);
}

void stepSpriteParticles(SpriteParticles& s, const fluid::SignedDistanceShape& shape, float dt) {
  const SpriteParticleParams& p = s.params;
  // Retire particles past their lifetime (swap with the last alive one; order is irrelevant).
  for (std::size_t i = 0; i < s.count;) {
    if (s.age[i] >= p.lifetime) {
      const std::size_t last = --s.count;
      s.position[i] = s.position[last];
      s.previous[i] = s.previous[last];
      s.velocity[i] = s.velocity[last];
      s.age[i] = s.age[last];
    } else {
      ++i;
    }
  }
  // Emit: the debt keeps the long-run rate exact for any rate * dt.
  s.emit_debt += static_cast<double>(std::max(p.rate, 0.0f)) * dt;
  const auto wanted = static_cast<std::size_t>(s.emit_debt);
  s.emit_debt -= static_cast<double>(wanted);
  const std::size_t emit = std::min(wanted, s.capacity - s.count);
  const float spread = glm::radians(std::clamp(p.spread_degrees, 0.0f, 90.0f));
  const float cos_spread = std::cos(spread);
  for (std::size_t k = 0; k < emit; ++k) {
    // Direction uniform over the spherical cap of half-angle `spread` around +y.
    const float cos_theta = 1.0f - uniform01(s.rng) * (1.0f - cos_spread);
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    const float phi = 2.0f * std::numbers::pi_v<float> * uniform01(s.rng);
    const float speed = p.speed * (0.92f + 0.16f * uniform01(s.rng));
    const glm::vec3 direction(sin_theta * std::cos(phi), cos_theta, sin_theta * std::sin(phi));
    // Spread the births over the step so the jet has no visible bands.
    const float fraction = (static_cast<float>(k) + 0.5f) / static_cast<float>(emit);
    const std::size_t i = s.count++;
    s.velocity[i] = direction * speed;
    s.position[i] = p.nozzle + s.velocity[i] * (dt * fraction);
    s.previous[i] = s.position[i];
    s.age[i] = dt * fraction;
  }
  const std::size_t n = s.count;
  fluid::CollisionMaterial material;
  material.resilience = p.restitution;
  material.friction = p.friction;
  // Every particle is independent from here on, so ranges run in parallel and the result does
  // not depend on the thread count; each range counts its own bounces. fluid::par rather than
  // oneTBB directly: same splitting, but TSan builds run it on std::threads that TSan can follow
  // (the system oneTBB is not instrumented; see fluid/core/parallel.hpp).
  std::atomic<std::uint64_t> bounces{0};
  fluid::par::parallel_for(
      fluid::par::Range<std::size_t>(0, n, 1024), [&](const fluid::par::Range<std::size_t>& range) {
        const std::size_t begin = range.begin(), count = range.size();
        // Integrate (semi-implicit Euler): v* = v + g dt, x* = x + v* dt; then the double check.
        for (std::size_t i = begin; i < range.end(); ++i) {
          s.velocity[i] += p.gravity * dt;
          s.predicted[i] = s.position[i] + s.velocity[i] * dt;
        }
        shape.query(std::span(s.position.data() + begin, count), std::span(s.previous_samples.data() + begin, count));
        shape.query(std::span(s.predicted.data() + begin, count), std::span(s.predicted_samples.data() + begin, count));
        std::uint64_t range_bounces = 0;
        for (std::size_t i = begin; i < range.end(); ++i) range_bounces += collideParticle(s, shape, material, dt, i);
        bounces += range_bounces;
      });
  s.bounces += bounces.load();
  ++s.steps;
}

std::string findNonFiniteParticle(const SpriteParticles& s) {
  static constexpr const char* kAxis[] = {"x", "y", "z"};
  for (std::size_t i = 0; i < s.count; ++i) {
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(s.position[i][a])) {
        return "sprite_particles: particle " + std::to_string(i) + " position." + kAxis[a] + " = " +
               std::to_string(s.position[i][a]);
      }
      if (!std::isfinite(s.velocity[i][a])) {
        return "sprite_particles: particle " + std::to_string(i) + " velocity." + kAxis[a] + " = " +
               std::to_string(s.velocity[i][a]);
      }
    }
  }
  return {};
}

}  // namespace game
