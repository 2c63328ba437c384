// Baselines against the oracle, back-to-front order, user attributes, exact slab order.
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"
#include "order_metrics.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>

using namespace surface_test;

namespace {
fluid::SurfaceMesh run(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p) {
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}
fluid::SurfaceMesh baseline(fluid::BaselineMethod method, const fluid::SurfaceInput& in,
                            const fluid::SurfaceParams& p) {
  fluid::BaselineExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(method, in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}
}  // namespace

class Baselines : public ::testing::TestWithParam<std::tuple<const char*, float>> {};

TEST_P(Baselines, Approaches2And3GiveTheOracleTriangles) {
  const auto [name, cube] = GetParam();
  const fluid::ParticlePositions ps = loadSet(name);
  fluid::SurfaceParams p;
  p.cube = cube;
  const auto ref = canonicalTriangles(baseline(fluid::BaselineMethod::dense, inputOf(ps), p));
  for (auto method : {fluid::BaselineMethod::blocked, fluid::BaselineMethod::hashed}) {
    p.blockCubes = 24;
    const fluid::SurfaceMesh m = baseline(method, inputOf(ps), p);
    EXPECT_EQ(m.stats.triangles, ref.size()) << int(method);
    EXPECT_TRUE(canonicalTriangles(m) == ref) << int(method);
    const Topology t = checkTopology(m);
    EXPECT_EQ(t.badEdges, 0u);
    EXPECT_GT(t.signedVolume, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(BenchData, Baselines,
                         ::testing::Values(std::make_tuple("fountain.xyz", 1.0f), std::make_tuple("blob.xyz", 0.3f),
                                           std::make_tuple("explosion.xyz", 0.6f)));

TEST(SurfaceOrder, BackToFrontForRandomViewsAndExactSlabOrder) {
  const fluid::ParticlePositions ps = loadSet("explosion.xyz");
  std::mt19937 rng(99);
  std::normal_distribution<float> g;
  fluid::SurfaceParams p;
  p.cube = 0.6f;
  p.blockCubes = 24;
  const fluid::SurfaceMesh plain = run(inputOf(ps), p);
  const auto reference = canonicalTriangles(plain);
  double worstOrdered = 0, sumOrdered = 0, sumReverse = 0, sumExact = 0;
  const int views = 6;
  for (int v = 0; v < views; ++v) {
    const glm::vec3 dir = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    const glm::vec3 eye = -60.0f * dir;  // looking at the explosion's centre from outside
    p.order = fluid::SurfaceOrder::backToFront;
    p.eye = eye;
    p.viewDir = dir;
    p.exactSlabOrder = false;
    const fluid::SurfaceMesh m = run(inputOf(ps), p);
    // Same surface (rotating the sweep changes the summation order, so compare counts and
    // closedness rather than bits).
    EXPECT_NEAR(double(m.stats.triangles), double(plain.stats.triangles), 0.001 * plain.stats.triangles);
    const Topology t = checkTopology(m);
    EXPECT_EQ(t.badEdges, 0u);
    EXPECT_GT(t.signedVolume, 0.0);
    const double ordered = outOfOrderFraction(m, eye, dir, 0.0f, 50000);
    p.order = fluid::SurfaceOrder::frontToBack;
    const double reverse = outOfOrderFraction(run(inputOf(ps), p), eye, dir, 0.0f, 50000);
    worstOrdered = std::max(worstOrdered, ordered);
    sumOrdered += ordered;
    sumReverse += reverse;
    // Exact mode: within each block, runs are one per slab, in strictly increasing sweep order,
    // and the same triangles.
    p.order = fluid::SurfaceOrder::backToFront;
    p.exactSlabOrder = true;
    const fluid::SurfaceMesh ex = run(inputOf(ps), p);
    EXPECT_EQ(ex.stats.triangles, m.stats.triangles);
    for (const fluid::SurfaceBlockRange& b : ex.blocks)
      for (std::uint32_t r = 1; r < b.slabRunCount; ++r)
        EXPECT_LT(ex.slabRuns[b.firstSlabRun + r - 1].slab, ex.slabRuns[b.firstSlabRun + r].slab);
    EXPECT_TRUE(canonicalTriangles(ex) == canonicalTriangles(m));
    const double exact = outOfOrderFraction(ex, eye, dir, 0.0f, 50000);
    EXPECT_LE(exact, ordered + 0.005);
    sumExact += exact;
  }
  std::printf(
      "out-of-order fraction over %d random views: back-to-front mean %.4f (worst %.4f), "
      "exact slab order mean %.4f, front-to-back mean %.4f\n",
      views, sumOrdered / views, worstOrdered, sumExact / views, sumReverse / views);
  EXPECT_LT(sumExact, sumOrdered);
  EXPECT_LT(worstOrdered, 0.15);
  EXPECT_GT(sumReverse / views, 0.8);
}

TEST(SurfaceAttributes, PerParticleVec4IsInterpolatedOntoVertices) {
  // Two far-apart particles with different colours: every vertex carries its particle's colour.
  const std::vector<glm::vec3> points = {{0, 0, 0}, {10, 0, 0}};
  const std::vector<glm::vec4> user = {{1, 0, 0, 1}, {0, 0, 1, 0.5f}};
  fluid::SurfaceParams p;
  p.cube = 0.25f;
  const fluid::SurfaceMesh m = run({fluid::pointView(points), {}, {}, user}, p);
  ASSERT_EQ(m.attributes.size(), m.positions.size());
  ASSERT_GT(m.positions.size(), 100u);
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const glm::vec4 expect = m.positions[v].x < 5 ? user[0] : user[1];
    EXPECT_NEAR(glm::length(m.attributes[v] - expect), 0.0f, 1e-5f);
  }
  // Overlapping particles blend: attributes stay within the convex hull of the inputs.
  const std::vector<glm::vec3> points2 = {{0, 0, 0}, {1.2f, 0, 0}};
  const fluid::SurfaceMesh b = run({fluid::pointView(points2), {}, {}, user}, p);
  bool blended = false;
  for (const glm::vec4& a : b.attributes) {
    EXPECT_NEAR(a.x + a.z, 1.0f, 1e-4f);
    EXPECT_GE(a.x, -1e-5f);
    blended = blended || (a.x > 0.3f && a.x < 0.7f);
  }
  EXPECT_TRUE(blended);
  // Same geometry as without attributes (per-corner data takes the §6 cache's walk: compared with
  // that route, the same triangle order too).
  fluid::SurfaceParams walk = p;
  walk.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
  const fluid::SurfaceMesh plain = run({fluid::pointView(points2)}, walk);
  EXPECT_TRUE(plain.positions == b.positions);
  EXPECT_TRUE(plain.indices == b.indices);
}

// With several blocks, one thread has the blocks append to the mesh's arrays directly while
// more threads concatenate per-block outputs: attributes, like positions, must not differ.
TEST(SurfaceAttributes, SameForOneAndTwoThreadsOverSeveralBlocks) {
  const fluid::ParticlePositions ps = loadSet("explosion.xyz");
  std::vector<glm::vec4> user(ps.size());
  for (std::size_t i = 0; i < user.size(); ++i) user[i] = {float(i % 7), float(i % 3), 1.0f, float(i) * 1e-3f};
  fluid::SurfaceParams p;
  p.cube = 0.6f;
  p.blockCubes = 24;
  p.threads = 1;
  const fluid::SurfaceInput in{fluid::pointView(ps), {}, {}, user};
  const fluid::SurfaceMesh one = run(in, p);
  p.threads = 2;
  const fluid::SurfaceMesh two = run(in, p);
  ASSERT_GT(one.blocks.size(), 1u);
  ASSERT_EQ(one.attributes.size(), one.positions.size());
  EXPECT_TRUE(one.attributes == two.attributes);
  EXPECT_TRUE(one.positions == two.positions);
  EXPECT_TRUE(one.indices == two.indices);
}

TEST(SurfaceStrength, StrengthAndRadiusScaleChangeTheLoneRadius) {
  const std::vector<glm::vec3> points = {{0, 0, 0}};
  const std::vector<float> scale = {0.5f}, strength = {2.0f};
  fluid::SurfaceParams p;
  p.cube = 0.05f;
  auto meanRadius = [](const fluid::SurfaceMesh& m) {
    double r = 0;
    for (const glm::vec3& v : m.positions) r += glm::length(v);
    return r / double(m.positions.size());
  };
  // f = s ((r/(sqrt2 Rc_i))^2 - 1/2)^2 = T  ->  r = Rc_i sqrt(2 (1/2 - sqrt(T / s)))
  const double rScaled = 1.5 * std::sqrt(2.0 * (0.5 - std::sqrt(0.2)));
  EXPECT_NEAR(meanRadius(run({fluid::pointView(points), {}, scale, {}}, p)), rScaled, 0.003);
  const double rStrong = 3.0 * std::sqrt(2.0 * (0.5 - std::sqrt(0.1)));
  EXPECT_NEAR(meanRadius(run({fluid::pointView(points), strength, {}, {}}, p)), rStrong, 0.003);
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const std::vector<float> bad = {-1.0f};
  EXPECT_NE(ex.extract({fluid::pointView(points), bad, {}, {}}, p, m).error.find("strength[0]"), std::string::npos);
}

#include "fluid/surface/marching_slices_policy.hpp"

namespace {
// A caller's own compile-time policy: the field-weighted mean of a per-particle scalar (here the
// particle's own input index), and a count of contributions, carried to the vertices.
struct IndexMeanPolicy {
  struct CornerData {
    float sum = 0, weight = 0, count = 0;
  };
  static constexpr bool kHasUser = true;
  void add(CornerData& c, std::uint32_t particle, float w) const {
    c.sum += w * float(particle);
    c.weight += w;
    c.count += 1;
  }
  glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const {
    const float ma = a.weight > 0 ? a.sum / a.weight : 0, mb = b.weight > 0 ? b.sum / b.weight : 0;
    return {ma + t * (mb - ma), a.count, b.count, t};
  }
};
}  // namespace

TEST(SurfacePolicy, CallerPolicyIsInterpolatedAndGeometryUnchanged) {
  const std::vector<glm::vec3> points = {{0, 0, 0}, {0, 0, 0.1f}, {20, 0, 0}};
  fluid::SurfaceParams p;
  p.cube = 0.25f;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m, plain;
  ASSERT_TRUE(fluid::extractWithPolicy(ex, {fluid::pointView(points)}, p, IndexMeanPolicy{}, m).ok());
  fluid::SurfaceParams walk = p;  // a policy with corner data takes the §6 cache's walk; so does this
  walk.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
  ASSERT_TRUE(ex.extract({fluid::pointView(points)}, walk, plain).ok());
  EXPECT_TRUE(m.positions == plain.positions);
  EXPECT_TRUE(m.indices == plain.indices);
  ASSERT_EQ(m.attributes.size(), m.positions.size());
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const glm::vec4 a = m.attributes[v];
    if (m.positions[v].x > 10) {
      EXPECT_FLOAT_EQ(a.x, 2.0f);  // only particle 2 out there
    } else {
      EXPECT_GT(a.x, 0.0f);  // a blend of particles 0 and 1
      EXPECT_LT(a.x, 1.0f);
    }
    EXPECT_GE(a.w, 0.0f);
    EXPECT_LE(a.w, 1.0f);
    EXPECT_LE(a.y, 2.0f);  // never more particles than exist there
  }
}

// SurfaceStats' phase clocks: every phase of a one-thread extraction is measured (the particle
// cache, seeding and march of a non-empty block take time), and the phases fit inside the call as
// timed by the caller, since on one thread they do not overlap.
TEST(SurfaceStats, PhaseTimesAreMeasuredAndFitInTheCall) {
  const fluid::ParticlePositions ps = loadSet("explosion.xyz");
  fluid::SurfaceParams p;
  p.cube = 0.6f;
  p.threads = 1;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  for (int round = 0; round < 3; ++round) {
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(ex.extract(inputOf(ps), p, m).ok());
    const double callMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const fluid::SurfaceStats& s = m.stats;
    for (double v : {s.prepareMs, s.cacheBuildMs, s.seedMs, s.marchMs, s.gatherMs}) {
      EXPECT_TRUE(std::isfinite(v));
      EXPECT_GE(v, 0.0);
    }
    EXPECT_GT(s.prepareMs, 0.0);
    EXPECT_GT(s.cacheBuildMs, 0.0);
    EXPECT_GT(s.seedMs, 0.0);
    EXPECT_GT(s.marchMs, 0.0);
    EXPECT_LE(s.prepareMs + s.cacheBuildMs + s.seedMs + s.marchMs + s.gatherMs, callMs);
  }
  // An empty input has nothing to time.
  ASSERT_TRUE(ex.extract({}, p, m).ok());
  EXPECT_EQ(m.stats.cacheBuildMs, 0.0);
  EXPECT_EQ(m.stats.marchMs, 0.0);
}
