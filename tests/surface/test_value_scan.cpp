// SurfaceFieldRoute::valueScan: the dense scan over a value-only float splat, normals from central
// differences. Not bit-equal to the exact routes, so it is held to what it promises instead: the
// dense oracle's triangles on the test sets and the random sets (where no corner sits within float
// rounding of T), normals within a few degrees of the analytic ones, closed and oriented meshes,
// and the same bits whatever the block plan (its margins and the corner ring around each
// interior are complete), thread count, kernel copy or reused scratch.
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"
#include "random_sets.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

using namespace surface_test;

namespace {

constexpr fluid::SurfaceFieldRoute kValue = fluid::SurfaceFieldRoute::valueScan;

fluid::SurfaceMesh denseOracle(const fluid::SurfaceInput& in, fluid::SurfaceParams p) {
  p.order = fluid::SurfaceOrder::none;
  fluid::BaselineExtractor dense;
  fluid::SurfaceMesh ref;
  const fluid::SurfaceStatus st = dense.extract(fluid::BaselineMethod::dense, in, p, ref);
  EXPECT_TRUE(st.ok()) << st.error;
  return ref;
}

// Angles (degrees) between the value route's normals and the exact route's at the same edge keys,
// and the largest position difference there, over the vertices both meshes have.
struct NormalAgreement {
  double meanDegrees = 0, maxDegrees = 0, p99Degrees = 0, maxPositionGap = 0;
  std::size_t matched = 0;
};
NormalAgreement compareVertices(const fluid::SurfaceMesh& value, const fluid::SurfaceMesh& exact) {
  std::unordered_map<std::uint64_t, std::uint32_t> byKey;
  for (std::uint32_t v = 0; v < exact.positions.size(); ++v) byKey.emplace(exact.edgeKeys[v], v);
  NormalAgreement a;
  std::vector<double> angles;
  for (std::uint32_t v = 0; v < value.positions.size(); ++v) {
    const auto it = byKey.find(value.edgeKeys[v]);
    if (it == byKey.end()) continue;
    const glm::dvec3 n0 = value.normals[v], n1 = exact.normals[it->second];
    const double c = std::clamp(glm::dot(n0, n1) / (glm::length(n0) * glm::length(n1)), -1.0, 1.0);
    angles.push_back(std::acos(c) * 180.0 / 3.14159265358979323846);
    a.maxPositionGap =
        std::max(a.maxPositionGap, double(glm::length(value.positions[v] - exact.positions[it->second])));
  }
  a.matched = angles.size();
  if (angles.empty()) return a;
  for (double d : angles) a.meanDegrees += d / double(angles.size());
  std::sort(angles.begin(), angles.end());
  a.maxDegrees = angles.back();
  a.p99Degrees = angles[angles.size() * 99 / 100];
  return a;
}

TEST(ValueScan, DenseOracleTrianglesAndCloseNormalsOnTheTestSets) {
  // Bounds on the angle between central-difference and analytic normals, per test set (mean,
  // 99th percentile, degrees), about 1.3x what was measured (the test prints it): a sign or axis
  // slip in cornerCentral gives tens of degrees on average. The sets' small droplets are a cube or
  // two across (isolated particle: radius 0.975 S at Rc = 3 S), where a difference over two
  // cubes cannot follow the curvature: fountain's spray and spray's slivers have the tails.
  const double bounds[][2] = {{7.0, 50.0}, {1.0, 3.0}, {3.5, 12.0}, {5.0, 30.0}};
  for (std::size_t set = 0; set < std::size(kTestSets); ++set) {
    const auto& [name, cube] = kTestSets[set];
    const double* bound = bounds[set];
    const fluid::ParticlePositions ps = loadSet(name);
    fluid::SurfaceParams p;
    p.cube = cube;
    p.threads = 1;
    const fluid::SurfaceMesh value = meshWith(inputOf(ps), p, kValue);
    const fluid::SurfaceMesh exact = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::denseScan);
    ASSERT_GT(value.indices.size() / 3, 1000u) << name;
    EXPECT_EQ(value.stats.scannedBlocks, value.stats.blocks) << name;
    EXPECT_GT(value.stats.particlesLookedUp, 0u) << name;
    EXPECT_TRUE(canonicalTriangles(value) == canonicalTriangles(denseOracle(inputOf(ps), p)))
        << name << ": not the dense oracle's triangles";
    const Topology topo = checkTopology(value);
    EXPECT_EQ(topo.badEdges, 0u) << name;
    EXPECT_EQ(topo.keyPositionMismatch, 0u) << name;
    EXPECT_GT(topo.signedVolume, 0.0) << name;
    const NormalAgreement a = compareVertices(value, exact);
    EXPECT_EQ(a.matched, value.positions.size()) << name;
    std::printf("%s: normals %.2f mean, %.2f p99, %.2f max degrees from the analytic ones; positions within %.2g\n",
                name, a.meanDegrees, a.p99Degrees, a.maxDegrees, a.maxPositionGap);
    EXPECT_LT(a.meanDegrees, bound[0]) << name;
    EXPECT_LT(a.p99Degrees, bound[1]) << name;
    EXPECT_LT(a.maxPositionGap, 1e-3 * cube) << name;
    // Vertex normals facing away from a triangle they belong to: no more than the analytic ones have.
    EXPECT_LE(topo.normalsAgainstFaces, checkTopology(exact).normalsAgainstFaces) << name;
  }
}

TEST(ValueScan, SameBitsWhateverTheBlocksThreadsOrKernelCopy) {
  // Blocks of 8 and 16 cubes put many seams through the fountain: a vertex next to one reads
  // corners of the ring around its block's interior, which must hold every particle's term.
  const fluid::ParticlePositions ps = loadSet("fountain.xyz");
  fluid::SurfaceParams p;
  p.threads = 1;
  p.fieldRoute = kValue;
  const auto reference = trianglesWithVertexBits(meshWith(inputOf(ps), p, kValue));
  for (int blockCubes : {8, 16}) {
    fluid::SurfaceParams pb = p;
    pb.blockCubes = blockCubes;
    const fluid::SurfaceMesh one = meshWith(inputOf(ps), pb, kValue);
    ASSERT_GT(one.blocks.size(), 8u);
    EXPECT_TRUE(trianglesWithVertexBits(one) == reference) << blockCubes << "-cube blocks";
    for (int threads : {2, 3}) {
      pb.threads = threads;
      fluid::SurfaceExtractor ex;
      fluid::SurfaceMesh m;
      for (int rep = 0; rep < 2; ++rep) {  // and again with warm scratch
        ASSERT_TRUE(ex.extract(inputOf(ps), pb, m).ok());
        EXPECT_EQ(test_support::meshBitsDiffer(m, one), "") << threads << " threads, rep " << rep << ", " << blockCubes << "-cube blocks";
      }
    }
  }
  fluid::SurfaceParams portable = p;
  portable.portableKernels = true;
  EXPECT_TRUE(trianglesWithVertexBits(meshWith(inputOf(ps), portable, kValue)) == reference);
  // A rotated sweep frame with the exact slab order: the same triangles (keys in that frame).
  fluid::SurfaceParams rotated = p;
  rotated.order = fluid::SurfaceOrder::backToFront;
  rotated.eye = {40.0f, -25.0f, 10.0f};
  rotated.viewDir = {-0.8f, 0.5f, -0.2f};
  rotated.exactSlabOrder = true;
  const fluid::SurfaceMesh r1 = meshWith(inputOf(ps), rotated, kValue);
  rotated.threads = 2;
  EXPECT_EQ(test_support::meshBitsDiffer(meshWith(inputOf(ps), rotated, kValue), r1), "");
  EXPECT_EQ(checkTopology(r1).badEdges, 0u);
  EXPECT_EQ(r1.indices.size(), reference.size() * 3);
}

TEST(ValueScan, RandomSetsAreClosedAndMostlyTheOraclesTriangles) {
  // The property sweep's random sets (clusters, sheets, lines, lattices, duplicates, exact-T
  // values, mixed radii; random S, Rc, blocks, views). Exact-T sets put corners on T itself, where
  // the float predicate and sum may fall on the other side: there the triangle sets may differ,
  // so this asserts closed, oriented meshes everywhere and the oracle's triangles on the sets
  // without such corners (at least 40 of 48).
  int equalToOracle = 0;
  for (int seed = 1; seed <= 48; ++seed) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    fluid::SurfaceParams p = r.params;
    const fluid::SurfaceMesh value = meshWith(r.input(), p, kValue);
    const Topology topo = checkTopology(value);
    EXPECT_EQ(topo.badEdges, 0u) << "seed " << seed;
    EXPECT_EQ(topo.degenerate, 0u) << "seed " << seed;
    equalToOracle += canonicalTriangles(meshWith(r.input(), [&] {
                       fluid::SurfaceParams plain = p;
                       plain.order = fluid::SurfaceOrder::none;
                       return plain;
                     }(), kValue)) == canonicalTriangles(denseOracle(r.input(), p));
    p.threads = 3;
    fluid::SurfaceParams one = r.params;
    one.threads = 1;
    EXPECT_EQ(test_support::meshBitsDiffer(meshWith(r.input(), p, kValue), meshWith(r.input(), one, kValue)), "")
        << "seed " << seed << ": thread count changed the mesh";
  }
  std::printf("value scan: %d of 48 random sets have the dense oracle's triangles\n", equalToOracle);
  EXPECT_GE(equalToOracle, 40);
}

}  // namespace
