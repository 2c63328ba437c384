// Kolb et al. 2004 §4.2 eq. (3): L1 (octahedral) normal parametrization and the §4.3 texel
// encodings (fixed-point depth, binary16) that the GPU decodes.
#include "fluid/collide/collide.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <random>

namespace {

// atan2 form: acos loses all precision for nearly parallel vectors.
float angleDeg(glm::vec3 a, glm::vec3 b) {
  const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
  return static_cast<float>(glm::degrees(std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y))));
}

// Worst-case texel error of the L1 index over the sphere is about 241°/R (docs/collide.md,
// table "L1 normal index"); 250°/R bounds it at every resolution.
float worstCaseDeg(int resolution) { return 250.0f / static_cast<float>(resolution); }

glm::vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  glm::vec3 v;
  do v = {g(rng), g(rng), g(rng)};
  while (glm::dot(v, v) < 1e-6f);
  return glm::normalize(v);
}

TEST(L1Normal, ContinuousRoundTripIsExactToFloatPrecision) {
  std::mt19937 rng(1);
  for (int k = 0; k < 20000; ++k) {
    const glm::vec3 n = randomUnit(rng);
    const glm::vec2 st = fluid::l1Encode(n);
    ASSERT_GE(st.x, 0.0f);
    ASSERT_LE(st.x, 1.0f);
    ASSERT_GE(st.y, 0.0f);
    ASSERT_LE(st.y, 1.0f);
    ASSERT_LT(angleDeg(fluid::l1Decode(st), n), 1e-4f) << n.x << " " << n.y << " " << n.z;
  }
}

TEST(L1Normal, MatchesEquation3OnBothBranches) {
  // Upper half: l1(s,t) = (s, t, 1 − |s| − |t|).
  const glm::vec3 up = fluid::l1Decode({0.5f + 0.5f * 0.25f, 0.5f - 0.5f * 0.5f});
  EXPECT_LT(angleDeg(up, {0.25f, -0.5f, 0.25f}), 1e-4f);
  // Lower half: (sgn(s)(1 − |t|), sgn(t)(1 − |s|), 1 − |s| − |t|) with s = 0.75, t = −0.5.
  const glm::vec3 down = fluid::l1Decode({0.5f + 0.5f * 0.75f, 0.5f - 0.5f * 0.5f});
  EXPECT_LT(angleDeg(down, {0.5f, -0.25f, -0.25f}), 1e-4f);
}

TEST(L1Normal, Poles) {
  EXPECT_EQ(fluid::l1Encode({0, 0, 1}), glm::vec2(0.5f, 0.5f));
  // −z maps to a corner; sgn(0) = +1 picks (1, 1), and every corner decodes to −z.
  EXPECT_EQ(fluid::l1Encode({0, 0, -1}), glm::vec2(1.0f, 1.0f));
  for (glm::vec2 corner : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(0, 1), glm::vec2(1, 1)}) {
    EXPECT_LT(angleDeg(fluid::l1Decode(corner), {0, 0, -1}), 1e-4f);
  }
  for (int r : {64, 256, 1024}) {
    // Both poles sit on texel corners (R even): the error is half a texel diagonal.
    EXPECT_LT(angleDeg(fluid::l1TexelNormal(fluid::l1Texel({0, 0, 1}, r), r), {0, 0, 1}), 0.6f * worstCaseDeg(r));
    EXPECT_LT(angleDeg(fluid::l1TexelNormal(fluid::l1Texel({0, 0, -1}, r), r), {0, 0, -1}), 0.6f * worstCaseDeg(r));
  }
}

TEST(L1Normal, FoldLinesAreContinuous) {
  // Equator (z = 0): both branches of eq. (3) meet on the diamond |s| + |t| = 1.
  for (int k = 0; k < 360; ++k) {
    const float a = glm::radians(static_cast<float>(k));
    const glm::vec3 eq{std::cos(a), std::sin(a), 0.0f};
    const glm::vec3 above = glm::normalize(eq + glm::vec3(0, 0, 1e-3f));
    const glm::vec3 below = glm::normalize(eq - glm::vec3(0, 0, 1e-3f));
    EXPECT_LT(glm::length(fluid::l1Encode(above) - fluid::l1Encode(below)), 2e-3f);
  }
  // Lower-half seams (x = 0 or y = 0, z < 0) lie on the square's edges, mirrored: the two
  // sides of a seam are far apart in (s,t) but both texels decode close to the vector.
  for (int k = 1; k < 90; ++k) {
    const float a = glm::radians(static_cast<float>(k));
    for (glm::vec3 seam : {glm::vec3(0.0f, std::cos(a), -std::sin(a)), glm::vec3(std::cos(a), 0.0f, -std::sin(a))}) {
      const glm::vec3 side = seam.x == 0.0f ? glm::vec3(1e-4f, 0, 0) : glm::vec3(0, 1e-4f, 0);
      for (glm::vec3 n : {glm::normalize(seam + side), glm::normalize(seam - side), seam}) {
        EXPECT_LT(angleDeg(fluid::l1TexelNormal(fluid::l1Texel(n, 256), 256), n), worstCaseDeg(256));
      }
    }
  }
}

TEST(L1Normal, TexelIndexLayoutAndRange) {
  std::mt19937 rng(2);
  for (int r : {1, 2, 7, 64, 256, 1000}) {
    for (int k = 0; k < 2000; ++k) {
      const glm::vec3 n = randomUnit(rng);
      const glm::ivec2 ij = fluid::l1Texel(n, r);
      ASSERT_GE(ij.x, 0);
      ASSERT_LT(ij.x, r);
      ASSERT_GE(ij.y, 0);
      ASSERT_LT(ij.y, r);
      ASSERT_EQ(fluid::l1TexelIndex(n, r), static_cast<std::uint32_t>(ij.y * r + ij.x));
    }
  }
  const std::vector<float> tex = fluid::l1NormalTexture(16);
  ASSERT_EQ(tex.size(), 16u * 16u * 3u);
  const glm::vec3 n37 = fluid::l1TexelNormal({3, 7}, 16);
  EXPECT_EQ(tex[(7 * 16 + 3) * 3 + 0], n37.x);
  EXPECT_EQ(tex[(7 * 16 + 3) * 3 + 2], n37.z);
}

TEST(L1Normal, AngularErrorAt256IsBounded) {
  std::mt19937 rng(3);
  float max_error = 0.0f;
  double sum = 0.0;
  const int count = 100000;
  for (int k = 0; k < count; ++k) {
    const glm::vec3 n = randomUnit(rng);
    const float e = angleDeg(fluid::l1TexelNormal(fluid::l1Texel(n, 256), 256), n);
    max_error = std::max(max_error, e);
    sum += e;
  }
  EXPECT_LT(max_error, worstCaseDeg(256));         // 0.98°
  EXPECT_GT(max_error, 0.5f * worstCaseDeg(256));  // and the bound is not vacuous
  EXPECT_LT(sum / count, 0.36);                    // measured 0.334° (table)
  // Every texel decodes to a unit vector that encodes back to the same texel.
  for (int j = 0; j < 256; ++j) {
    for (int i = 0; i < 256; ++i) {
      const glm::vec3 n = fluid::l1TexelNormal({i, j}, 256);
      ASSERT_NEAR(glm::length(n), 1.0f, 1e-6f);
      const glm::ivec2 back = fluid::l1Texel(n, 256);
      ASSERT_TRUE(back == glm::ivec2(i, j)) << i << "," << j << " -> " << back.x << "," << back.y;
    }
  }
}

TEST(L1Normal, ZeroAndNonFiniteVectorsDoNotPoison) {
  EXPECT_EQ(fluid::l1Encode({0, 0, 0}), glm::vec2(0.5f, 0.5f));
  EXPECT_EQ(fluid::l1Encode({NAN, 0, 1}), glm::vec2(0.5f, 0.5f));
  EXPECT_EQ(fluid::l1Encode({INFINITY, 0, 1}), glm::vec2(0.5f, 0.5f));
}

TEST(Encodings, FixedDepthRoundsToNearestAndReservesBackground) {
  EXPECT_EQ(fluid::encodeFixedDepth(0.0f), 0);
  EXPECT_EQ(fluid::encodeFixedDepth(1.0f), 65534);  // 65535 is the background code
  EXPECT_EQ(fluid::encodeFixedDepth(-0.5f), 0);
  EXPECT_EQ(std::bit_cast<std::uint32_t>(fluid::kFixedDepthStep), 0x37800080u);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.0f, 65534.0f / 65535.0f);
  for (int k = 0; k < 10000; ++k) {
    const float d = u(rng);
    EXPECT_LE(std::fabs(fluid::decodeFixedDepth(fluid::encodeFixedDepth(d)) - d), 0.5f / 65535.0f + 1e-7f);
  }
}

TEST(Encodings, HalfFloatRoundTripsEveryHalfAndRoundsToNearestEven) {
  for (std::uint32_t h = 0; h < 0x10000u; ++h) {
    const auto bits = static_cast<std::uint16_t>(h);
    const float f = fluid::halfToFloat(bits);
    if (std::isnan(f)) {
      EXPECT_TRUE(std::isnan(fluid::halfToFloat(fluid::floatToHalf(f))));
      continue;
    }
    ASSERT_EQ(fluid::floatToHalf(f), bits) << std::hex << h;
  }
  // Random floats in [−2, 2]: the result is one of the two neighbouring halves, the nearer.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  for (int k = 0; k < 20000; ++k) {
    const float f = u(rng);
    const std::uint16_t h = fluid::floatToHalf(f);
    const float got = fluid::halfToFloat(h);
    const float up = fluid::halfToFloat(static_cast<std::uint16_t>(h + 1));
    const float down = fluid::halfToFloat(static_cast<std::uint16_t>(h - 1));
    EXPECT_LE(std::fabs(got - f), std::fabs(up - f));
    EXPECT_LE(std::fabs(got - f), std::fabs(down - f));
  }
  EXPECT_EQ(fluid::floatToHalf(-1.0f), fluid::kHalfBackground);
  EXPECT_EQ(fluid::floatToHalf(1e6f), 0x7C00);
}

}  // namespace
