#pragma once
// From an impact to its bubbles (Moss, Yeh, Hong, Lin & Manocha 2010, "Sounding Liquids", §4-5):
// a drop or a body hitting water entrains bubbles; their number grows with the impact's energy and
// their radii follow a power law p(r) ~ r^-exponent on [radius_min, r_top], whose top the impact
// sets: a bigger drop traps bigger bubbles (lower notes), so the pitch distribution follows the
// size of what fell. Each bubble becomes a SoundEvent for the mixer (engine/audio/synth.hpp), its
// onset spread over the step. Deterministic: every random number comes from the caller's Rng.

#include "engine/audio/synth.hpp"

#include <cstdint>
#include <vector>

namespace engine::audio {

// splitmix64 (Steele, Lea & Flood 2014): small, seedable, the same sequence everywhere.
struct Rng {
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
};
std::uint64_t nextRandom(Rng& rng);
float uniform01(Rng& rng);  // in [0, 1)

struct BubbleParams {
  float radius_min = 0.0012f;    // m (2.7 kHz)
  float radius_max = 0.015f;     // m (217 Hz)
  float exponent = 2.0f;         // p(r) ~ r^-exponent (0 = uniform in r)
  float size_ratio = 0.05f;      // the top radius as a fraction of the drop's radius
  float rate_scale = 1.0f;       // bubbles per impact, relative
  float per_particle = 0.35f;    // bubbles a one-particle impact at reference_speed makes, on average
  float reference_speed = 3.0f;  // m/s
  int max_per_impact = 24;
  float amplitude = 0.02f;  // one bubble of radius 3 mm at reference_speed, 1 m away
  float damping = 1.0f;     // multiplies the bubbles' decay (goo > 1)
};

struct Splash {
  SoundKind kind = SoundKind::drop;
  glm::vec3 position{0.0f};
  float speed = 0.0f;        // m/s at impact
  float drop_radius = 0.0f;  // m: the radius of a ball of what fell
  float particles = 1.0f;    // how much fell, in particles (the energy's volume factor)
  float loudness = 1.0f;     // extra gain (a crate, a blast's splash)
};

// Draws one radius from p(r) ~ r^-exponent on [lo, hi] by inverting its CDF.
float drawRadius(float lo, float hi, float exponent, float u);
// The top of the impact's radius range: size_ratio * drop_radius within [1.5 radius_min, radius_max].
float topRadius(const BubbleParams& params, float drop_radius);
// Appends the splash's bubbles (onsets within [0, step_seconds + a short cascade)). Returns how many.
int bubblesFromSplash(const Splash& splash, const BubbleParams& params, float step_seconds, Rng& rng,
                      std::vector<SoundEvent>& out);

}  // namespace engine::audio
