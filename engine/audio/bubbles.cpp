#include "engine/audio/bubbles.hpp"

#include <algorithm>
#include <cmath>

namespace engine::audio {

std::uint64_t nextRandom(Rng& rng) {
  std::uint64_t z = (rng.state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

float uniform01(Rng& rng) { return static_cast<float>(nextRandom(rng) >> 40) * (1.0f / 16777216.0f); }

float drawRadius(float lo, float hi, float exponent, float u) {
  if (!(hi > lo)) return lo;
  if (std::abs(exponent - 1.0f) < 1e-4f) return lo * std::pow(hi / lo, u);  // p ~ 1/r: log-uniform
  const float e = 1.0f - exponent;
  const float a = std::pow(lo, e), b = std::pow(hi, e);
  return std::clamp(std::pow(a + u * (b - a), 1.0f / e), lo, hi);
}

float topRadius(const BubbleParams& params, float drop_radius) {
  const float lo = 1.5f * params.radius_min;
  return std::clamp(params.size_ratio * drop_radius, lo, std::max(lo, params.radius_max));
}

int bubblesFromSplash(const Splash& splash, const BubbleParams& params, float step_seconds, Rng& rng,
                      std::vector<SoundEvent>& out) {
  if (!(splash.speed > 0.0f) || !(splash.particles > 0.0f) || !std::isfinite(splash.speed)) return 0;
  // The count follows the impact's kinetic energy (mass x speed^2), relative to one particle at the
  // reference speed; the fraction left over is a chance of one more, so small impacts make a sparse
  // patter and not a constant hiss.
  const float energy =
      splash.particles * (splash.speed / params.reference_speed) * (splash.speed / params.reference_speed);
  const float expected = params.rate_scale * params.per_particle * energy;
  const int count = std::min(params.max_per_impact, static_cast<int>(std::floor(expected + uniform01(rng))));
  const float top = topRadius(params, splash.drop_radius);
  const float lo = params.radius_min;
  const float level = splash.loudness * params.amplitude * std::min(3.0f, splash.speed / params.reference_speed);
  for (int i = 0; i < count; ++i) {
    SoundEvent e;
    e.kind = splash.kind;
    e.shape = VoiceShape::bubble;
    e.position = splash.position;
    e.radius = drawRadius(lo, top, params.exponent, uniform01(rng));
    // Bigger bubbles radiate more: amplitude ~ sqrt(r) about the 3 mm reference.
    e.amplitude = level * std::sqrt(e.radius / 0.003f);
    e.damping = params.damping;
    // Spread over the step, and a big splash's bubbles over a short cascade as its cavity breaks up.
    e.onset = uniform01(rng) * step_seconds + static_cast<float>(i) * 0.002f * uniform01(rng);
    out.push_back(e);
  }
  return count;
}

}  // namespace engine::audio
