#pragma once
// Internal to fluid/collide: the two small steps every depth-map lookup makes, shared by the
// sampler (depth_map.cpp) and the reach grid's bake (reach_grid.cpp) so both read a texel the same way.
#include "fluid/collide/collide.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <cstring>

namespace fluid::collide_detail {

inline glm::vec3 transformPoint(const glm::mat4& m, glm::vec3 p) {
  return glm::vec3(m[0]) * p.x + glm::vec3(m[1]) * p.y + glm::vec3(m[2]) * p.z + glm::vec3(m[3]);
}

// binary16 -> float for the depths the maps hold (normal numbers, zero, −1): one shift and
// add; anything else (subnormal, inf, NaN) takes the exact general path.
inline float depthHalf(std::uint16_t bits) {
  const std::uint32_t exponent = (bits >> 10) & 0x1Fu;
  if (exponent == 0u || exponent == 31u) return halfToFloat(bits);
  const std::uint32_t f = ((static_cast<std::uint32_t>(bits) & 0x8000u) << 16) |
                          (((static_cast<std::uint32_t>(bits) & 0x7FFFu) << 13) + (112u << 23));
  float out;
  std::memcpy(&out, &f, 4);
  return out;
}

}  // namespace fluid::collide_detail
