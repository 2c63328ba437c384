// FountainShape answers batches eight points at a time with AVX2 where the CPU has it, and with
// the scalar code otherwise (setPortable forces that). Both must give the same samples bit for bit:
// the SPH step's results are compared across machines and thread counts by hash.
#include "tests/support/fountain_shape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

// Random points around the fountain, points on and next to every primitive's boundary (where the
// deciding primitive changes), and non-finite ones; 8k + 5 of them, so the last batch is partial.
std::vector<glm::vec3> probePoints(const game::FountainGeometry& g) {
  std::vector<glm::vec3> pts;
  std::mt19937 rng(20261121);
  std::uniform_real_distribution<float> xz(-3.6f, 3.6f), y(-0.3f, 2.8f), unit(0.0f, 1.0f);
  for (int i = 0; i < 60000; ++i) pts.push_back({xz(rng), y(rng), xz(rng)});
  const float radii[] = {g.basin_outer_radius, g.basin_inner_radius, g.plinth_radius,    g.column_radius,
                         g.dish_radius,        g.dish_inner_radius,  g.spire_radius};
  const float heights[] = {0.0f,          g.basin_wall_top, g.basin_floor, g.plinth_top, g.column_top,
                           g.dish_bottom, g.dish_rim_top,   g.dish_floor,  g.spire_top};
  for (float r : radii)
    for (float h : heights)
      for (float dr : {-1e-3f, 0.0f, 1e-3f})
        for (float dh : {-1e-3f, 0.0f, 1e-3f}) {
          const float angle = 6.2831853f * unit(rng);
          pts.push_back({(r + dr) * std::cos(angle), h + dh, (r + dr) * std::sin(angle)});
        }
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  for (glm::vec3 p : {glm::vec3(nan, 1, 0), glm::vec3(0, inf, 0), glm::vec3(-inf, 0, 0), glm::vec3(0, 0, nan)})
    pts.push_back(p);
  pts.push_back(g.nozzle);
  while (pts.size() % 8 != 5) pts.push_back({0.1f * float(pts.size() % 7), 1.0f, 0.0f});
  return pts;
}

TEST(FountainShape, EightWideAndScalarQueriesGiveTheSameSamples) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2 on this CPU: only the scalar path exists";
  fountainref::FountainShape wide, scalar;
  scalar.setPortable(true);
  const std::vector<glm::vec3> pts = probePoints(wide.geometry());
  std::vector<fluid::ColliderSample> a(pts.size()), b(pts.size());
  wide.query(pts, a);
  scalar.query(pts, b);
  std::size_t differing = 0, valid = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    valid += a[i].valid;
    const bool same = a[i].valid == b[i].valid &&
                      std::memcmp(&a[i].distance, &b[i].distance, sizeof(float)) == 0 &&
                      std::memcmp(&a[i].normal, &b[i].normal, sizeof(glm::vec3)) == 0;
    if (!same && differing++ < 5)
      ADD_FAILURE() << "point " << i << " (" << pts[i].x << ", " << pts[i].y << ", " << pts[i].z
                    << "): 8-wide d = " << a[i].distance << " valid " << a[i].valid << ", scalar d = " << b[i].distance
                    << " valid " << b[i].valid;
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(valid, pts.size() - 10);  // only the non-finite points may come back invalid
}

TEST(FountainShape, BatchDistancesMatchThePointQuery) {
  // query() and distance() are two entry points to one field; they must agree on finite points.
  fountainref::FountainShape shape;
  const std::vector<glm::vec3> pts = probePoints(shape.geometry());
  std::vector<fluid::ColliderSample> s(pts.size());
  shape.query(pts, s);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!std::isfinite(pts[i].x + pts[i].y + pts[i].z)) {
      EXPECT_FALSE(s[i].valid && !std::isfinite(s[i].distance)) << "non-finite distance leaked at point " << i;
      continue;
    }
    ASSERT_TRUE(s[i].valid) << i;
    EXPECT_NEAR(s[i].distance, shape.distance(pts[i]), 1e-5f) << i;
    EXPECT_NEAR(glm::length(s[i].normal), 1.0f, 1e-3f) << i;
  }
}

}  // namespace
