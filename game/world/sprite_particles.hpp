#pragma once
// The `sprite_particles` effect: a fountain jet of plain gravity particles that bounce on the
// ground, the basin and the statue (FountainShape) and are drawn as point sprites. Stands in
// for the SPH fluid until that lands. SoA storage sized once at construction (max_particles);
// stepping never allocates (outside TSan builds, whose fluid::par loops start std::threads).
// Deterministic: a seeded generator, one fixed dt per step, and the per-particle work split over
// fluid::par ranges (oneTBB) with no cross-particle dependency (results do not depend on the
// thread count).

#include "fluid/core/collider.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace game {

// Live-tunable parameters (schema: effect_schema.cpp, section "sprite_particles").
struct SpriteParticleParams {
  float rate = 1500.0f;         // particles per second
  float speed = 7.0f;           // m/s at the nozzle
  float spread_degrees = 6.0f;  // half-angle of the jet cone
  float lifetime = 4.0f;        // s
  float size = 0.06f;           // sprite radius, m
  float restitution = 0.3f;     // Kolb §3.3.2 resilience ε
  float friction = 0.15f;       // Kolb §3.3.2 friction ν
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};
  glm::vec3 nozzle{0.0f, 2.5f, 0.0f};
};

SpriteParticleParams spriteParamsFrom(const SectionConfig& section, glm::vec3 gravity, glm::vec3 nozzle);

struct SpriteParticles {
  SpriteParticleParams params;
  std::size_t capacity = 0;         // max_particles, fixed at construction
  std::size_t count = 0;            // alive particles are [0, count)
  std::vector<glm::vec3> position;  // m
  std::vector<glm::vec3> previous;  // position before the last step (render interpolation)
  std::vector<glm::vec3> velocity;  // m/s
  std::vector<float> age;           // s
  double emit_debt = 0.0;           // fractional particles owed to the next step
  std::mt19937 rng;
  std::uint64_t steps = 0;
  std::uint64_t bounces = 0;  // collision reactions so far (for tests/overlay)
  // Scratch reused every step.
  std::vector<glm::vec3> predicted;
  std::vector<fluid::ColliderSample> previous_samples;
  std::vector<fluid::ColliderSample> predicted_samples;
};

// Allocates every array for `capacity` particles (the only allocation this system makes).
void initSpriteParticles(SpriteParticles& particles, const SpriteParticleParams& params, std::size_t capacity,
                         std::uint32_t seed);

// One fixed step: emit, integrate (semi-implicit Euler), collide with `shape` using the double
// check and reaction of Kolb et al. 2004 §3.3.2 (fluid::resolveCollision), retire old ones.
void stepSpriteParticles(SpriteParticles& particles, const fluid::SignedDistanceShape& shape, float dt);

// Empty when every position/velocity is finite; otherwise names the first bad value.
std::string findNonFiniteParticle(const SpriteParticles& particles);

}  // namespace game
