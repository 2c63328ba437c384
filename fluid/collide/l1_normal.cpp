// §4.2, eq. (3) of Kolb et al. 2004: the L1 parametrization of the unit sphere, and the
// §4.3 texel encodings. The bit-level contract is in collide.hpp.
#include "fluid/collide/collide.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>

namespace fluid {

namespace {
float signNonNegative(float x) { return x >= 0.0f ? 1.0f : -1.0f; }
}  // namespace

glm::vec2 l1Encode(glm::vec3 d) {
  const float l1 = std::fabs(d.x) + std::fabs(d.y) + std::fabs(d.z);
  if (!(l1 > 0.0f) || !std::isfinite(l1)) return {0.5f, 0.5f};
  const glm::vec3 p = d / l1;  // onto the L1 unit sphere (the octahedron)
  glm::vec2 ab{p.x, p.y};
  if (p.z < 0.0f) {
    // Lower half: invert the |s|+|t| > 1 branch of eq. (3): |s| = 1 − |y|, |t| = 1 − |x|.
    ab = {signNonNegative(p.x) * (1.0f - std::fabs(p.y)), signNonNegative(p.y) * (1.0f - std::fabs(p.x))};
  }
  return glm::clamp(ab * 0.5f + 0.5f, glm::vec2(0.0f), glm::vec2(1.0f));
}

glm::vec3 l1Decode(glm::vec2 st) {
  st = glm::clamp(st, glm::vec2(0.0f), glm::vec2(1.0f));
  const float s = st.x * 2.0f - 1.0f;
  const float t = st.y * 2.0f - 1.0f;
  const float as = std::fabs(s), at = std::fabs(t);
  glm::vec3 v;
  if (as + at <= 1.0f) {
    v = {s, t, 1.0f - as - at};
  } else {
    v = {signNonNegative(s) * (1.0f - at), signNonNegative(t) * (1.0f - as), 1.0f - as - at};
  }
  return glm::normalize(v);
}

glm::ivec2 l1Texel(glm::vec3 direction, int resolution) {
  assert(resolution >= 1);
  const glm::vec2 st = l1Encode(direction);
  const float r = static_cast<float>(resolution);
  const int i = std::min(static_cast<int>(std::floor(st.x * r)), resolution - 1);
  const int j = std::min(static_cast<int>(std::floor(st.y * r)), resolution - 1);
  return {i, j};
}

std::uint32_t l1TexelIndex(glm::vec3 direction, int resolution) {
  const glm::ivec2 ij = l1Texel(direction, resolution);
  return static_cast<std::uint32_t>(ij.y) * static_cast<std::uint32_t>(resolution) + static_cast<std::uint32_t>(ij.x);
}

glm::vec3 l1TexelNormal(glm::ivec2 texel, int resolution) {
  const double r = resolution;
  const glm::vec2 st{static_cast<float>((texel.x + 0.5) / r), static_cast<float>((texel.y + 0.5) / r)};
  return l1Decode(st);
}

std::vector<float> l1NormalTexture(int resolution) {
  assert(resolution >= 1);
  std::vector<float> rgb(static_cast<std::size_t>(resolution) * resolution * 3);
  for (int j = 0; j < resolution; ++j) {
    for (int i = 0; i < resolution; ++i) {
      const glm::vec3 n = l1TexelNormal({i, j}, resolution);
      const std::size_t k = (static_cast<std::size_t>(j) * resolution + i) * 3;
      rgb[k] = n.x;
      rgb[k + 1] = n.y;
      rgb[k + 2] = n.z;
    }
  }
  return rgb;
}

std::uint16_t encodeFixedDepth(float depth01) {
  if (!(depth01 > 0.0f)) return 0;  // also maps NaN to 0; callers never pass NaN
  const double q = std::floor(static_cast<double>(depth01) * 65535.0 + 0.5);
  return static_cast<std::uint16_t>(std::min(q, 65534.0));
}

float decodeFixedDepth(std::uint16_t q) { return static_cast<float>(q) * kFixedDepthStep; }

std::uint16_t floatToHalf(float value) {
  std::uint32_t f;
  std::memcpy(&f, &value, 4);
  const std::uint32_t sign = (f >> 16) & 0x8000u;
  const std::uint32_t abs = f & 0x7FFFFFFFu;
  if (abs >= 0x7F800000u) {  // inf / NaN
    return static_cast<std::uint16_t>(sign | 0x7C00u | (abs > 0x7F800000u ? 0x200u : 0u));
  }
  if (abs >= 0x477FF000u) return static_cast<std::uint16_t>(sign | 0x7C00u);  // rounds to >= 65520: inf
  if (abs < 0x38800000u) {  // below the smallest normal half (2^-14): subnormal or zero
    if (abs < 0x33000000u) return static_cast<std::uint16_t>(sign);  // < 2^-25: rounds to 0
    const std::uint32_t exponent = abs >> 23;
    const std::uint32_t mantissa = (abs & 0x7FFFFFu) | 0x800000u;
    const std::uint32_t shift = 126u - exponent;  // 14 + (127 - e) - 1 ... places bits at 2^-24 units
    const std::uint32_t shifted = mantissa >> shift;
    const std::uint32_t rest = mantissa & ((1u << shift) - 1u);
    const std::uint32_t half_way = 1u << (shift - 1u);
    std::uint32_t h = shifted;
    if (rest > half_way || (rest == half_way && (shifted & 1u))) ++h;
    return static_cast<std::uint16_t>(sign | h);
  }
  // Normal: rebias exponent (127 -> 15), keep 10 mantissa bits, round to nearest even.
  std::uint32_t h = ((abs - 0x38000000u) >> 13);
  const std::uint32_t rest = abs & 0x1FFFu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // may carry into the exponent: correct
  return static_cast<std::uint16_t>(sign | h);
}

float halfToFloat(std::uint16_t bits) {
  const std::uint32_t sign = (static_cast<std::uint32_t>(bits) & 0x8000u) << 16;
  const std::uint32_t exponent = (bits >> 10) & 0x1Fu;
  const std::uint32_t mantissa = bits & 0x3FFu;
  std::uint32_t f;
  if (exponent == 0) {
    if (mantissa == 0) {
      f = sign;
    } else {  // subnormal: value = mantissa · 2^-24, exact in float
      const float v = static_cast<float>(mantissa) * 5.9604644775390625e-08f;
      std::memcpy(&f, &v, 4);
      f |= sign;
    }
  } else if (exponent == 31) {
    f = sign | 0x7F800000u | (mantissa << 13);
  } else {
    f = sign | ((exponent + 112u) << 23) | (mantissa << 13);
  }
  float out;
  std::memcpy(&out, &f, 4);
  return out;
}

const char* formatName(DepthMapFormat format) {
  switch (format) {
    case DepthMapFormat::float32:
      return "float";
    case DepthMapFormat::fixed8:
      return "fixed8";
    case DepthMapFormat::front_back16:
      return "front-back16";
    case DepthMapFormat::cube8:
      return "cube8";
  }
  return "unknown";
}

bool parseFormat(const std::string& name, DepthMapFormat& out) {
  for (DepthMapFormat f :
       {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16, DepthMapFormat::cube8}) {
    if (name == formatName(f)) {
      out = f;
      return true;
    }
  }
  return false;
}

}  // namespace fluid
