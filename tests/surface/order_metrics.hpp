#pragma once
// Out-of-order measure for back-to-front output (paper §5), shared by the test and the docs tool.

#include "fluid/surface/marching_slices.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <random>

namespace surface_test {

// Fraction of sampled triangle pairs (a emitted before b) where a is nearer to the eye than b
// by more than `slack` (depth = distance of the centroid along the view direction). 0 = perfect
// back-to-front, about 0.5 = unordered. Deterministic (seeded).
inline double outOfOrderFraction(const fluid::SurfaceMesh& m, glm::vec3 eye, glm::vec3 dir, float slack,
                                 std::size_t samples = 200000, std::uint32_t seed = 7) {
  const std::size_t n = m.indices.size() / 3;
  if (n < 2) return 0.0;
  const glm::vec3 d = glm::normalize(dir);
  auto depth = [&](std::size_t t) {
    const glm::vec3 c =
        (m.positions[m.indices[3 * t]] + m.positions[m.indices[3 * t + 1]] + m.positions[m.indices[3 * t + 2]]) / 3.0f;
    return glm::dot(c - eye, d);
  };
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  std::size_t bad = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    std::size_t a = pick(rng), b = pick(rng);
    if (a == b) continue;
    if (a > b) std::swap(a, b);
    bad += depth(a) < depth(b) - slack;
  }
  return double(bad) / double(samples);
}

}  // namespace surface_test
