// Marching slices against the dense oracle, watertightness, hard cases, determinism.
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/detail/testing.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>

using namespace surface_test;

namespace {

fluid::SurfaceMesh slices(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p) {
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}

fluid::SurfaceMesh oracle(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p) {
  fluid::BaselineExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(fluid::BaselineMethod::dense, in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}

void expectClosedAndEqualToOracleBy(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p,
                                    std::size_t minTriangles);

// Closed, consistently oriented outward, and the same triangles as dense MC on the lattice: with
// p's route (the default: the dense scan) and with §4 seeding and Alg. 1's walk (the §6 cache).
void expectClosedAndEqualToOracle(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p,
                                  std::size_t minTriangles = 1) {
  expectClosedAndEqualToOracleBy(in, p, minTriangles);
  if (p.fieldRoute != fluid::SurfaceFieldRoute::particleCache) {
    fluid::SurfaceParams walk = p;
    walk.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
    SCOPED_TRACE("the walk (particle cache route)");
    expectClosedAndEqualToOracleBy(in, walk, minTriangles);
  }
}

void expectClosedAndEqualToOracleBy(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p,
                                    std::size_t minTriangles) {
  const fluid::SurfaceMesh m = slices(in, p);
  const fluid::SurfaceMesh ref = oracle(in, p);
  const Topology t = checkTopology(m);
  EXPECT_GE(t.triangles, minTriangles);
  EXPECT_EQ(t.badEdges, 0u);
  EXPECT_EQ(t.degenerate, 0u);
  EXPECT_EQ(t.keyPositionMismatch, 0u);
  if (t.triangles) {
    EXPECT_GT(t.signedVolume, 0.0);
  }
  EXPECT_EQ(m.stats.triangles, ref.stats.triangles);
  EXPECT_TRUE(canonicalTriangles(m) == canonicalTriangles(ref)) << "triangle sets differ from the dense oracle";
  // Same vertex positions for the same lattice edges (bitwise: same field sums).
  std::unordered_map<std::uint64_t, glm::vec3> refPos;
  for (std::size_t v = 0; v < ref.positions.size(); ++v) refPos[ref.edgeKeys[v]] = ref.positions[v];
  std::size_t differ = 0;
  for (std::size_t v = 0; v < m.positions.size(); ++v) differ += refPos.at(m.edgeKeys[v]) != m.positions[v];
  EXPECT_EQ(differ, 0u);
}

double loneRadius(double rc, double t) { return std::sqrt(2.0 * (0.5 - std::sqrt(t))) * rc; }

}  // namespace

TEST(MarchingSlices, LoneParticleIsClosedSphereOfAnalyticRadius) {
  const std::vector<float> x = {0.37f}, y = {-0.21f}, z = {0.05f};
  fluid::SurfaceParams p;
  p.cube = 0.1f;
  const fluid::SurfaceMesh m = slices({fluid::pointView(packPoints(x, y, z))}, p);
  const Topology t = checkTopology(m);
  EXPECT_GT(t.triangles, 500u);
  EXPECT_EQ(t.badEdges, 0u);
  const double r = loneRadius(p.rc, p.threshold);
  EXPECT_NEAR(r, 0.975, 0.001);  // the bench-data README's figure
  double worst = 0;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const glm::dvec3 d = glm::dvec3(m.positions[v]) - glm::dvec3(x[0], y[0], z[0]);
    worst = std::max(worst, std::abs(glm::length(d) - r));
    // Normals point away from the particle.
    EXPECT_GT(glm::dot(glm::normalize(d), glm::dvec3(m.normals[v])), 0.99);
  }
  EXPECT_LT(worst, 0.005);
  const double sphere = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(t.signedVolume / sphere, 1.0, 0.02);
}

class DataSets : public ::testing::TestWithParam<std::tuple<const char*, float, std::size_t>> {};

TEST_P(DataSets, WatertightAndEqualToDenseOracleWithReadmeTriangleCount) {
  const auto [name, cube, expected] = GetParam();
  const fluid::ParticlePositions ps = loadSet(name);
  fluid::SurfaceParams p;
  p.cube = cube;
  const fluid::SurfaceMesh m = slices(inputOf(ps), p);
  EXPECT_EQ(m.stats.triangles, expected) << name;
  expectClosedAndEqualToOracle(inputOf(ps), p);
}

INSTANTIATE_TEST_SUITE_P(BenchData, DataSets,
                         ::testing::Values(std::make_tuple("fountain.xyz", 1.0f, std::size_t(14164)),
                                           std::make_tuple("blob.xyz", 0.3f, std::size_t(8288)),
                                           std::make_tuple("explosion.xyz", 0.6f, std::size_t(32508)),
                                           std::make_tuple("spray.xyz", 1.0f, std::size_t(100848))));

TEST(MarchingSlices, FountainAtFinerCubesEqualsOracle) {
  const fluid::ParticlePositions ps = loadSet("fountain.xyz");
  for (float cube : {0.75f, 0.5f}) {
    fluid::SurfaceParams p;
    p.cube = cube;
    expectClosedAndEqualToOracle(inputOf(ps), p);
  }
}

TEST(MarchingSlices, SameTrianglesForEveryBlockSize) {
  const fluid::ParticlePositions ps = loadSet("explosion.xyz");
  fluid::SurfaceParams p;
  p.cube = 0.6f;
  p.blockCubes = 32;
  const auto reference = canonicalTriangles(slices(inputOf(ps), p));
  for (int b : {0, 4, 7, 16, 64, 200}) {
    p.blockCubes = b;
    const fluid::SurfaceMesh m = slices(inputOf(ps), p);
    EXPECT_TRUE(canonicalTriangles(m) == reference) << "blockCubes " << b;
    EXPECT_EQ(checkTopology(m).badEdges, 0u) << "blockCubes " << b;
  }
}

// threads = 0 takes the slots of the caller's oneTBB arena, as tbb::parallel_for would: inside a
// one-slot arena (as AsyncSurfaceExtractor's worker on 2 cores) one worker's scratch, as with threads = 1.
TEST(MarchingSlices, ThreadsZeroUsesTheCallersArenaSlots) {
  const fluid::ParticlePositions ps = loadSet("spray.xyz");
  fluid::SurfaceParams p;
  p.blockCubes = 16;
  p.threads = 1;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh one, in_arena;
  ASSERT_TRUE(ex.extract(inputOf(ps), p, one).ok());
  ASSERT_GT(one.stats.blocks, 8u) << "enough blocks for a second worker to take some";
  p.threads = 0;
  fluid::SurfaceExtractor arena_ex;
  tbb::task_arena(1).execute([&] { ASSERT_TRUE(arena_ex.extract(inputOf(ps), p, in_arena).ok()); });
  EXPECT_EQ(in_arena.stats.workingBytesAllWorkers, one.stats.workingBytesAllWorkers)
      << "one worker's peak, not the sum of one per core";
  EXPECT_TRUE(in_arena.indices == one.indices);
  // The same rule as a number, for callers that split the threads (fluiddemo mesh's sequence mode).
  int slots_zero = 0, slots_three = 0;
  tbb::task_arena(1).execute([&] {
    slots_zero = fluid::surfaceThreads(p);
    fluid::SurfaceParams three = p;
    three.threads = 3;
    slots_three = fluid::surfaceThreads(three);
  });
  EXPECT_EQ(slots_zero, 1);
  EXPECT_EQ(slots_three, 3) << "a positive count is taken as given";
  tbb::task_arena(2).execute([&] { slots_zero = fluid::surfaceThreads(p); });
  EXPECT_EQ(slots_zero, 2);
}

TEST(MarchingSlices, BitIdenticalForOneTwoAndManyThreads) {
  const fluid::ParticlePositions ps = loadSet("spray.xyz");
  fluid::SurfaceParams p;
  p.blockCubes = 16;
  p.threads = 1;
  const fluid::SurfaceMesh one = slices(inputOf(ps), p);
  for (int threads : {2, 3, 8}) {
    p.threads = threads;
    fluid::SurfaceExtractor ex;
    fluid::SurfaceMesh m;
    for (int rep = 0; rep < 2; ++rep) {  // and again with warm scratch
      ASSERT_TRUE(ex.extract(inputOf(ps), p, m).ok());
      EXPECT_TRUE(m.positions == one.positions) << threads;
      EXPECT_TRUE(m.normals == one.normals) << threads;
      EXPECT_TRUE(m.indices == one.indices) << threads;
      EXPECT_TRUE(m.edgeKeys == one.edgeKeys) << threads;
      EXPECT_EQ(m.stats.cubesVisited, one.stats.cubesVisited);
      // Block and slab index ranges too (one thread appends the blocks to the mesh directly,
      // more threads concatenate per-block outputs).
      ASSERT_EQ(m.blocks.size(), one.blocks.size());
      for (std::size_t b = 0; b < m.blocks.size(); ++b) {
        const fluid::SurfaceBlockRange &x = m.blocks[b], &r = one.blocks[b];
        EXPECT_TRUE(x.bx == r.bx && x.by == r.by && x.bz == r.bz && x.indices.first == r.indices.first &&
                    x.indices.count == r.indices.count && x.firstVertex == r.firstVertex &&
                    x.vertexCount == r.vertexCount && x.firstSlabRun == r.firstSlabRun &&
                    x.slabRunCount == r.slabRunCount)
            << "block " << b << ", " << threads << " threads";
      }
      ASSERT_EQ(m.slabRuns.size(), one.slabRuns.size());
      for (std::size_t k = 0; k < m.slabRuns.size(); ++k)
        EXPECT_TRUE(m.slabRuns[k].slab == one.slabRuns[k].slab &&
                    m.slabRuns[k].indices.first == one.slabRuns[k].indices.first &&
                    m.slabRuns[k].indices.count == one.slabRuns[k].indices.count)
            << "run " << k << ", " << threads << " threads";
    }
  }
}

// The particle-cache fill has an AVX2 path (four columns at once) chosen at run time and a
// portable SSE2 one; they must give the same cache, hence the same mesh bit for bit.
TEST(MarchingSlices, ParticleOrderIsZThenIndexForRadixAndComparisonSorts) {
  // prepareParticles orders by (z, input index): a radix sort of the z bits for 256 or more
  // particles, a comparison sort below. Ties, -0 next to +0, negative z, and a rotated sweep
  // frame (z = -y) must give exactly the (z, index) order in both.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(-40, 40);
  for (std::size_t n : {std::size_t(37), std::size_t(255), std::size_t(256), std::size_t(3000)}) {
    std::vector<float> x(n), y(n), z(n);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = 0.25f * float(pick(rng));
      y[i] = i % 7 == 0 ? (i % 2 ? -0.0f : 0.0f) : 0.125f * float(pick(rng));  // many ties, signed zeros
      z[i] = i % 5 == 0 ? (i % 2 ? -0.0f : 0.0f) : 0.5f * float(pick(rng)) + 1e-3f * float(i % 3);
    }
    for (int frame = 0; frame < 2; ++frame) {
      fluid::detail::SweepFrame f;
      if (frame) {  // sweep along -y: z' = -y
        f.axis[0] = 2, f.axis[1] = 0, f.axis[2] = 1;
        f.sign[2] = -1;
      }
      const std::vector<float>& w = frame ? y : z;
      const double sign = frame ? -1.0 : 1.0;
      std::vector<std::uint32_t> expect(n);
      for (std::uint32_t i = 0; i < n; ++i) expect[i] = i;
      std::sort(expect.begin(), expect.end(), [&](std::uint32_t a, std::uint32_t b) {
        const double za = sign * double(w[a]), zb = sign * double(w[b]);
        return za < zb || (za == zb && a < b);
      });
      fluid::SurfaceParams params;
      std::vector<fluid::detail::Particle> ps;
      std::vector<fluid::detail::ParticleSortKey> scratch;
      double rcMax = 0;
      fluid::detail::prepareParticles({fluid::pointView(packPoints(x, y, z))}, params, f, ps, rcMax, &scratch);
      ASSERT_EQ(ps.size(), n);
      for (std::size_t r = 0; r < n; ++r) {
        ASSERT_EQ(ps[r].index, expect[r]) << "n " << n << " frame " << frame << " rank " << r;
        const double zr = sign * double(w[expect[r]]);
        ASSERT_EQ(std::memcmp(&ps[r].z, &zr, sizeof zr), 0) << "n " << n << " rank " << r;  // same bits
      }
    }
  }
}

TEST(MarchingSlices, Avx2AndPortableCacheFillGiveTheSameMesh) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU has no AVX2: only the portable fill runs";
  for (const auto& [name, cube] : kTestSets) {
    const fluid::ParticlePositions ps = loadSet(name);
    for (int order = 0; order < 2; ++order) {
      fluid::SurfaceParams p;
      p.cube = cube;
      p.threads = 1;
      if (order) {  // a rotated sweep frame (other clamp and span cases)
        p.order = fluid::SurfaceOrder::backToFront;
        p.eye = {40.0f, -25.0f, 10.0f};
        p.viewDir = {-0.8f, 0.5f, -0.2f};
      }
      p.portableKernels = true;
      const fluid::SurfaceMesh portable = slices(inputOf(ps), p);
      p.portableKernels = false;
      const fluid::SurfaceMesh fast = slices(inputOf(ps), p);
      ASSERT_GT(portable.indices.size(), 0u) << name;
      EXPECT_TRUE(fast.positions == portable.positions) << name << " order " << order;
      EXPECT_TRUE(fast.normals == portable.normals) << name << " order " << order;
      EXPECT_TRUE(fast.indices == portable.indices) << name << " order " << order;
      EXPECT_EQ(fast.stats.particlesLookedUp, portable.stats.particlesLookedUp) << name << " order " << order;
      EXPECT_EQ(fast.stats.particleCacheBytesPeakBlock, portable.stats.particleCacheBytesPeakBlock) << name;
    }
  }
}

TEST(MarchingSlices, ParticlesOnCornersAndBlockBoundaries) {
  // Particles exactly on lattice corners (S = 0.5, coordinates multiples of 0.5); for each block
  // size, the test checks that some particle sits exactly on a block face, so seams are hit.
  std::vector<float> x, y, z;
  for (float a : {-4.0f, -2.5f, 0.0f, 1.5f, 4.0f, 4.5f, 8.0f})
    for (float b : {-4.0f, -1.0f, 0.0f, 4.0f})
      for (float c : {0.0f, 2.0f, 4.0f}) {
        x.push_back(a);
        y.push_back(b);
        z.push_back(c);
      }
  for (int blockCubes : {4, 5, 6, 8}) {
    fluid::SurfaceParams p;
    p.cube = 0.5f;
    p.blockCubes = blockCubes;
    const std::vector<glm::vec3> points = packPoints(x, y, z);
    const fluid::SurfaceInput in{fluid::pointView(points)};
    const fluid::SurfaceMesh m = slices(in, p);
    std::size_t onFace = 0;
    for (const fluid::SurfaceBlockRange& b : m.blocks)
      for (std::size_t i = 0; i < x.size(); ++i) {
        const float pc[3] = {x[i], y[i], z[i]};
        for (int a = 0; a < 3; ++a) onFace += pc[a] == b.boundsMin[a] || pc[a] == b.boundsMax[a];
      }
    EXPECT_GT(onFace, 0u) << "no particle on a block face for blockCubes " << blockCubes;
    EXPECT_GT(m.blocks.size(), 8u);
    expectClosedAndEqualToOracle(in, p, 100);
  }
}

TEST(MarchingSlices, FieldExactlyEqualToThresholdAtCorners) {
  // Rc = 2, S = 1: a particle on a corner gives u = r^2 / 8 = 1/8 at its 6 axis neighbours, so
  // f = (1/8 - 1/2)^2 = 0.140625 exactly, a float. With T = 0.140625 those corners sit exactly
  // on the threshold (outside, since inside is f > T) and vertices land on corners.
  const std::vector<glm::vec3> points = {{0, 0, 0}, {3, 0, 1}};
  fluid::SurfaceParams p;
  p.rc = 2.0f;
  p.cube = 1.0f;
  p.threshold = 0.140625f;
  const fluid::SurfaceInput in{fluid::pointView(points)};
  ASSERT_EQ(fluid::surfaceFieldAtCorner({fluid::pointView(std::span(points).first(1))}, p, 1, 0, 0), p.threshold);
  const fluid::SurfaceMesh m = slices(in, p);
  const Topology t = checkTopology(m);
  EXPECT_GT(t.triangles, 0u);
  EXPECT_EQ(t.badEdges, 0u);
  const fluid::SurfaceMesh ref = oracle(in, p);
  EXPECT_TRUE(canonicalTriangles(m) == canonicalTriangles(ref));
}

TEST(MarchingSlices, CoincidentParticles) {
  const std::vector<glm::vec3> points(7, glm::vec3(1.25f, -2.5f, 0.75f));
  fluid::SurfaceParams p;
  p.cube = 0.25f;
  expectClosedAndEqualToOracle({fluid::pointView(points)}, p, 100);
}

TEST(MarchingSlices, UprightBowlSeedingFailureCaseOfFigure4b) {
  // The bowl's inner minima (uprightBowl): the sweep must still reach them.
  const fluid::ParticlePositions bowl = uprightBowl();
  fluid::SurfaceParams p;
  p.cube = 0.5f;
  p.blockCubes = 64;
  p.fieldRoute = fluid::SurfaceFieldRoute::particleCache;  // the walk (the dense scan has no seeds)
  const fluid::SurfaceMesh m = slices(inputOf(bowl), p);
  EXPECT_GT(m.stats.slabReversals, 0u) << "the sweep never reversed; the bowl does not test reversal";
  expectClosedAndEqualToOracle(inputOf(bowl), p, 1000);
}

TEST(MarchingSlices, FarFromOriginOffsetBy1e5) {
  fluid::SurfaceParams p;
  const fluid::ParticlePositions ps = blobOffsetBy1e5(p);
  expectClosedAndEqualToOracle(inputOf(ps), p, 1000);
  // Local positions stay small and precise (float relative to the origin).
  const fluid::SurfaceMesh m = slices(inputOf(ps), p);
  for (const glm::vec3& v : m.positions) EXPECT_LT(glm::length(v), 10.0f);
}

TEST(MarchingSlices, ZeroAndOneParticle) {
  fluid::SurfaceParams p;
  const fluid::SurfaceMesh empty = slices({}, p);
  EXPECT_TRUE(empty.indices.empty());
  EXPECT_TRUE(empty.positions.empty());
  const std::vector<glm::vec3> points = {{5.5f, 5.5f, 5.5f}};
  expectClosedAndEqualToOracle({fluid::pointView(points)}, p, 8);
}

TEST(MarchingSlices, RejectsNonFiniteInputWithClearError) {
  std::vector<glm::vec3> points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  points[3].x = std::numeric_limits<float>::quiet_NaN();
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  fluid::SurfaceStatus st = ex.extract({fluid::pointView(points)}, {}, m);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.error.find("positions[3].x"), std::string::npos) << st.error;
  EXPECT_NE(st.error.find("not finite"), std::string::npos) << st.error;
  points[3].x = 3;
  points[1].z = std::numeric_limits<float>::infinity();
  st = ex.extract({fluid::pointView(points)}, {}, m);
  EXPECT_NE(st.error.find("positions[1].z"), std::string::npos) << st.error;
  fluid::SurfaceParams bad;
  bad.cube = -1;
  points[1].z = 0;
  st = ex.extract({fluid::pointView(points)}, bad, m);
  EXPECT_NE(st.error.find("cube"), std::string::npos) << st.error;
  // Views the mesher cannot read: a stride shorter than a point or not a whole number of floats,
  // no data behind a count.
  for (std::size_t stride : {std::size_t(8), std::size_t(14)}) {
    st = ex.extract({fluid::PointView{&points[0].x, 2, stride}}, {}, m);
    EXPECT_NE(st.error.find("stride"), std::string::npos) << st.error;
  }
  st = ex.extract({fluid::PointView{nullptr, 2, 12}}, {}, m);
  EXPECT_NE(st.error.find("no data"), std::string::npos) << st.error;
  EXPECT_TRUE(m.indices.empty());
}

// Particles in the outermost margin cube along z (Rc / S not a whole number, so the block holds
// particles less than one cube inside its expanded top and bottom): columns near the rim of their
// discs have z ranges entirely beyond corner 1 (resp. n - 1), which the cache must leave empty
// rather than clamp onto that corner.
TEST(ParticleCache, ExactInTheOutermostMarginCubes) {
  std::mt19937 rng(77);
  fluid::SurfaceParams p;
  p.cube = 1.2f;  // Rc / S = 2.5, margin 3 cubes: block particles reach to half a cube from the top
  p.rc = 3.0f;
  p.blockCubes = 8;
  const double s = p.cube, bs = double(p.blockCubes) * s;
  std::uniform_real_distribution<float> u(0.0f, float(bs)), edge(0.0f, 0.5f * float(s));
  std::vector<float> x, y, z;
  for (int i = 0; i < 400; ++i) {
    x.push_back(u(rng)), y.push_back(u(rng));
    // Within Rc of the interior [0, bs] but in the last margin cube: below 0 - (m - 1) S or above
    // bs + (m - 1) S, at most Rc away.
    const float d = edge(rng);
    z.push_back(i % 2 ? float(bs + p.rc) - d : -p.rc + d);
  }
  const std::vector<glm::vec3> points = packPoints(x, y, z);
  const fluid::SurfaceInput in{fluid::pointView(points)};
  fluid::detail::BlockCacheProbe probe(in, p, 0, 0, 0);
  ASSERT_EQ(probe.margin, 3);
  std::vector<std::uint32_t> found, expect;
  std::size_t nonEmpty = 0;
  for (int cz = 0; cz <= probe.n; ++cz)
    for (int cy = 0; cy <= probe.n; ++cy)
      for (int cx = 0; cx <= probe.n; ++cx) {
        probe.lookup(cx, cy, cz, found);
        expect.clear();
        const bool boundary = cx == 0 || cy == 0 || cz == 0 || cx == probe.n || cy == probe.n || cz == probe.n;
        const double px = double(cx - probe.margin) * s, py = double(cy - probe.margin) * s,
                     pz = double(cz - probe.margin) * s;
        for (const auto& q : probe.particles)
          if (!boundary && fluid::detail::influences(q, px, py, pz)) expect.push_back(q.index);
        nonEmpty += !expect.empty();
        ASSERT_EQ(found, expect) << "corner " << cx << "," << cy << "," << cz;
      }
  EXPECT_GT(nonEmpty, 50u);
}

TEST(ParticleCache, EveryLookupIsExactlyTheBruteForceSet) {
  std::mt19937 rng(1234);
  for (int trial = 0; trial < 6; ++trial) {
    std::uniform_real_distribution<float> u(-6.0f, 6.0f);
    std::vector<float> x(300), y(300), z(300), scale(300);
    for (int i = 0; i < 300; ++i) {
      x[i] = u(rng), y[i] = u(rng), z[i] = u(rng);
      scale[i] = 0.3f + 0.7f * float(i % 7) / 6.0f;
    }
    // Some particles exactly on lattice corners and coincident, to hit boundary cases.
    for (int i = 0; i < 20; ++i) x[i] = std::round(x[i]), y[i] = std::round(y[i]), z[i] = std::round(z[i]);
    x[21] = x[20], y[21] = y[20], z[21] = z[20];
    fluid::SurfaceParams p;
    p.cube = trial % 2 ? 0.5f : 0.37f;
    p.rc = trial < 3 ? 3.0f : 1.3f;
    p.blockCubes = 12;
    const std::vector<glm::vec3> points = packPoints(x, y, z);
    const fluid::SurfaceInput in{
        fluid::pointView(points), {}, trial % 2 ? std::span<const float>(scale) : std::span<const float>(), {}};
    fluid::detail::SweepFrame frame;
    std::vector<fluid::detail::Particle> all;
    double rcMax = 0;
    fluid::detail::prepareParticles(in, p, frame, all, rcMax);
    const int bc[3] = {trial % 3 - 1, 0, -1};
    p.portableKernels = (trial / 2) % 2 == 1;  // the AVX2 fill (where the CPU has it) and the portable one
    fluid::detail::BlockCacheProbe probe(in, p, bc[0], bc[1], bc[2]);
    const std::int64_t g0[3] = {std::int64_t(bc[0]) * p.blockCubes - probe.margin,
                                std::int64_t(bc[1]) * p.blockCubes - probe.margin,
                                std::int64_t(bc[2]) * p.blockCubes - probe.margin};
    std::vector<std::uint32_t> found, expect;
    std::size_t nonEmpty = 0, lookups = 0;
    auto check = [&](int cx, int cy, int cz) {
      probe.lookup(cx, cy, cz, found);
      expect.clear();
      const bool boundary = cx == 0 || cy == 0 || cz == 0 || cx == probe.n || cy == probe.n || cz == probe.n;
      const double px = double(g0[0] + cx) * p.cube, py = double(g0[1] + cy) * p.cube, pz = double(g0[2] + cz) * p.cube;
      // Brute force. At interior corners: every particle (the block lists must miss none). In the
      // margins: the block's particles, those with an anchor within ceil(Rc_i / S) cubes of an
      // interior corner on every axis.
      const int lc[3] = {cx, cy, cz};
      bool interior = true;
      for (int a = 0; a < 3; ++a) interior = interior && lc[a] >= probe.margin && lc[a] <= probe.margin + p.blockCubes;
      for (const auto& q : all) {
        const std::int64_t reach = std::int64_t(std::ceil(std::sqrt(q.rc2) / double(p.cube)));
        bool inBlock = true;
        for (int a = 0; a < 3; ++a)
          inBlock = inBlock && q.anchor[a] - reach <= std::int64_t(bc[a] + 1) * p.blockCubes &&
                    q.anchor[a] + reach >= std::int64_t(bc[a]) * p.blockCubes;
        if ((inBlock || interior) && !boundary && fluid::detail::influences(q, px, py, pz)) expect.push_back(q.index);
      }
      ++lookups;
      nonEmpty += !expect.empty();
      ASSERT_EQ(found, expect) << "corner " << cx << "," << cy << "," << cz;  // same set, same (z, index) order
    };
    // Sweep order (as marching slices walks), then random order to stress the start pointer.
    for (int cz = 0; cz <= probe.n; ++cz)
      for (int cy = 0; cy <= probe.n; cy += 2)
        for (int cx = 0; cx <= probe.n; cx += 3) check(cx, cy, cz);
    std::uniform_int_distribution<int> c(0, probe.n);
    for (int i = 0; i < 3000; ++i) check(c(rng), c(rng), c(rng));
    EXPECT_GT(nonEmpty, 100u) << "test set too sparse to mean anything";
  }
}
