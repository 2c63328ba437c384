// The two exact field routes (SurfaceFieldRoute): the slice splat must give the §6 cache's mesh bit
// for bit (same terms, same (z, index) order, same float expressions), on the test sets, the
// hidden-style hard cases, random sets, every thread count, both kernel copies and rotated frames;
// and, on its own, the dense oracle's triangles.
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/marching_slices_policy.hpp"
#include "mesh_checks.hpp"
#include "random_sets.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

using namespace surface_test;

namespace {

int gScannedMeshes = 0;    // expectRoutesAgree calls whose dense-scan mesh was scanned (every block)
int gScansWithGhosts = 0;  // of those, scans that found components the walk's seeding cannot reach
int gSamePlanScans = 0;    // scans compared with the walk block by block (both planned the same blocks)

// The dense scan against the slice splat's walk: the walk's triangles with the same vertex bits
// (keys, positions, normals) and as many per slab; where both planned the same blocks (the scan
// halves a one-block set across z first, the walk across its longest axis), also block by block,
// with the same vertex counts and, with the exact slab order, the same slab runs. The scan looks at
// every interior cube, so it may find more than the walk: components where overlapping fields
// exceed T away from every particle's nearest corner, which §4 seeding cannot reach
// (random_sets.hpp's "ghosts"). Then the scan must be the dense oracle's triangles exactly.
// Otherwise only the order within a slab may differ.
std::map<std::int32_t, std::uint32_t> slabTotals(const fluid::SurfaceMesh& m, std::uint32_t firstRun,
                                                 std::uint32_t runs) {
  std::map<std::int32_t, std::uint32_t> out;
  for (std::uint32_t r = firstRun; r < firstRun + runs; ++r) out[m.slabRuns[r].slab] += m.slabRuns[r].indices.count;
  return out;
}

void expectScanIsTheWalkUpToOrder(const fluid::SurfaceInput& in, const fluid::SurfaceMesh& scan,
                                  const fluid::SurfaceMesh& walk, const fluid::SurfaceParams& p, const std::string& what) {
  const std::vector<TriangleBits> all = trianglesWithVertexBits(scan, 0, scan.indices.size());
  const std::vector<TriangleBits> allWalk = trianglesWithVertexBits(walk, 0, walk.indices.size());
  const bool ghosts = all != allWalk;
  if (ghosts) {
    EXPECT_TRUE(std::includes(all.begin(), all.end(), allWalk.begin(), allWalk.end()))
        << what << ": the walk has triangles the scan lacks";
  } else {
    EXPECT_TRUE(slabTotals(scan, 0, std::uint32_t(scan.slabRuns.size())) ==
                slabTotals(walk, 0, std::uint32_t(walk.slabRuns.size())))
        << what;
  }
  for (const fluid::SurfaceBlockRange& s : scan.blocks)
    for (std::uint32_t r = s.firstSlabRun; r < s.firstSlabRun + s.slabRunCount; ++r)
      EXPECT_TRUE(scan.slabRuns[r].indices.first >= s.indices.first &&
                  scan.slabRuns[r].indices.first + scan.slabRuns[r].indices.count <= s.indices.first + s.indices.count)
          << what;
  bool samePlan = scan.blocks.size() == walk.blocks.size();
  for (std::size_t b = 0; samePlan && b < scan.blocks.size(); ++b)
    samePlan = scan.blocks[b].bx == walk.blocks[b].bx && scan.blocks[b].by == walk.blocks[b].by &&
               scan.blocks[b].bz == walk.blocks[b].bz;
  for (std::size_t b = 0; samePlan && !ghosts && b < scan.blocks.size(); ++b) {
    const fluid::SurfaceBlockRange &s = scan.blocks[b], &w = walk.blocks[b];
    EXPECT_TRUE(trianglesWithVertexBits(scan, s.indices.first, s.indices.count) ==
                trianglesWithVertexBits(walk, w.indices.first, w.indices.count))
        << what << " block " << b;
    EXPECT_EQ(s.vertexCount, w.vertexCount) << what << " block " << b;
    EXPECT_TRUE(slabTotals(scan, s.firstSlabRun, s.slabRunCount) == slabTotals(walk, w.firstSlabRun, w.slabRunCount))
        << what << " block " << b;
    if (p.order != fluid::SurfaceOrder::none && p.exactSlabOrder) {
      EXPECT_EQ(s.slabRunCount, w.slabRunCount) << what << " block " << b;
    }
  }
  gSamePlanScans += samePlan;
  EXPECT_EQ(checkTopology(scan).badEdges, 0u) << what;
  if (ghosts) {  // the extra triangles: exactly what the dense oracle has beyond the walk
    fluid::SurfaceParams plain = p;
    plain.order = fluid::SurfaceOrder::none;
    plain.fieldRoute = fluid::SurfaceFieldRoute::denseScan;
    fluid::SurfaceExtractor ex;
    fluid::SurfaceMesh scanPlain, ref;
    ASSERT_TRUE(ex.extract(in, plain, scanPlain).ok());
    fluid::BaselineExtractor dense;
    ASSERT_TRUE(dense.extract(fluid::BaselineMethod::dense, in, plain, ref).ok());
    EXPECT_TRUE(canonicalTriangles(scanPlain) == canonicalTriangles(ref)) << what << ": not the dense oracle's triangles";
    ++gScansWithGhosts;
  }
}

// Both routes on `in`: the same mesh bit for bit (every array, block and slab ranges included),
// closed, and (unless `oracleToo` is off) the dense oracle's triangles; and the dense scan the
// splat's triangles and vertices up to their order. Returns the splat mesh.
fluid::SurfaceMesh expectRoutesAgree(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p,
                                     const std::string& what, std::size_t minTriangles = 1, bool oracleToo = true) {
  const fluid::SurfaceMesh cache = meshWith(in, p, fluid::SurfaceFieldRoute::particleCache);
  const fluid::SurfaceMesh splat = meshWith(in, p, fluid::SurfaceFieldRoute::sliceSplat);
  EXPECT_GE(splat.indices.size() / 3, minTriangles) << what;
  EXPECT_EQ(splat.stats.splatBlocks, splat.stats.blocks) << what;
  EXPECT_EQ(test_support::meshBitsDiffer(splat, cache), "") << what;
  EXPECT_EQ(splat.blocks.size(), cache.blocks.size()) << what;
  for (std::size_t b = 0; b < std::min(splat.blocks.size(), cache.blocks.size()); ++b)
    EXPECT_TRUE(splat.blocks[b].indices.first == cache.blocks[b].indices.first &&
                splat.blocks[b].indices.count == cache.blocks[b].indices.count &&
                splat.blocks[b].vertexCount == cache.blocks[b].vertexCount)
        << what << " block " << b;
  EXPECT_EQ(splat.slabRuns.size(), cache.slabRuns.size()) << what;
  EXPECT_EQ(splat.stats.cubesVisited, cache.stats.cubesVisited) << what;
  EXPECT_EQ(splat.stats.cornersEvaluated, cache.stats.cornersEvaluated) << what;
  EXPECT_GT(splat.stats.particlesLookedUp, 0u) << what;
  EXPECT_EQ(checkTopology(splat).badEdges, 0u) << what;
  const fluid::SurfaceMesh scan = meshWith(in, p, fluid::SurfaceFieldRoute::denseScan);
  EXPECT_TRUE(scan.stats.scannedBlocks == 0 || scan.stats.scannedBlocks == scan.stats.blocks) << what;
  gScannedMeshes += scan.stats.scannedBlocks > 0;
  expectScanIsTheWalkUpToOrder(in, scan, splat, p, what + " (dense scan)");
  if (oracleToo && p.order == fluid::SurfaceOrder::none) {
    fluid::BaselineExtractor dense;
    fluid::SurfaceMesh ref;
    EXPECT_TRUE(dense.extract(fluid::BaselineMethod::dense, in, p, ref).ok());
    EXPECT_TRUE(canonicalTriangles(splat) == canonicalTriangles(ref)) << what << ": not the dense oracle's triangles";
  }
  return splat;
}

TEST(FieldRoutes, SliceSplatIsTheCacheMeshBitForBitOnTheTestSets) {
  for (const auto& [name, cube] : kTestSets) {
    const fluid::ParticlePositions ps = loadSet(name);
    for (int variant = 0; variant < 3; ++variant) {
      fluid::SurfaceParams p;
      p.cube = cube;
      p.threads = 1;
      if (variant == 1) {  // a rotated sweep frame with the exact slab order
        p.order = fluid::SurfaceOrder::backToFront;
        p.eye = {40.0f, -25.0f, 10.0f};
        p.viewDir = {-0.8f, 0.5f, -0.2f};
        p.exactSlabOrder = true;
      }
      if (variant == 2) p.portableKernels = true;  // the SSE2 copy of the splat
      const int scannedBefore = gScannedMeshes;
      expectRoutesAgree(inputOf(ps), p, std::string(name) + " variant " + std::to_string(variant), 1000);
      EXPECT_EQ(gScannedMeshes, scannedBefore + 1) << name << " not scanned";
    }
  }
}

TEST(FieldRoutes, DenseScanRunsInEveryBlock) {
  // Forced, the dense scan takes every block of every set, the small dense ones (fountain,
  // explosion) and spray's large sparse ones alike, each summed a slice at a time.
  const std::tuple<const char*, float, bool> sets[] = {
      {"fountain.xyz", 1.0f, true}, {"explosion.xyz", 0.6f, true}, {"spray.xyz", 1.0f, true}};
  for (const auto& [name, cube, scanned] : sets) {
    const fluid::ParticlePositions ps = loadSet(name);
    fluid::SurfaceParams p;
    p.cube = cube;
    const fluid::SurfaceMesh scan = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::denseScan);
    EXPECT_EQ(scan.stats.splatBlocks, scan.stats.blocks) << name;
    EXPECT_EQ(scan.stats.scannedBlocks, scanned ? scan.stats.blocks : 0u) << name;
    if (scanned) {
      EXPECT_EQ(scan.stats.seedEvaluations, 0u) << name;
      EXPECT_EQ(scan.stats.slabReversals, 0u) << name;
    }
  }
}

// `route` on `set` with blocks of 16 cubes (many blocks): at 2 and 3 threads, cold and warm, the
// one-thread mesh bit for bit; with `exactToo` also in a rotated frame with the exact slab order.
void expectThreadCountInvariant(const char* set, fluid::SurfaceFieldRoute route, bool exactToo) {
  const fluid::ParticlePositions ps = loadSet(set);
  fluid::SurfaceParams p;
  p.blockCubes = 16;
  p.threads = 1;
  p.fieldRoute = route;
  for (bool exact : {false, true}) {
    if (exact && !exactToo) break;
    if (exact) {
      p.order = fluid::SurfaceOrder::backToFront;
      p.eye = {-30.0f, 20.0f, 45.0f};
      p.viewDir = {0.6f, -0.3f, -0.7f};
      p.exactSlabOrder = true;
    }
    fluid::SurfaceExtractor ex1;
    fluid::SurfaceMesh one;
    ASSERT_TRUE(ex1.extract(inputOf(ps), p, one).ok());
    ASSERT_GT(one.blocks.size(), 8u);
    if (route == fluid::SurfaceFieldRoute::denseScan) {
      ASSERT_EQ(one.stats.scannedBlocks, one.stats.blocks);
    }
    for (int threads : {2, 3}) {
      fluid::SurfaceParams pt = p;
      pt.threads = threads;
      fluid::SurfaceExtractor ex;
      fluid::SurfaceMesh m;
      for (int rep = 0; rep < 2; ++rep) {  // and again with warm scratch
        ASSERT_TRUE(ex.extract(inputOf(ps), pt, m).ok());
        EXPECT_EQ(test_support::meshBitsDiffer(m, one), "") << threads << " threads, rep " << rep << ", exact " << exact;
      }
    }
  }
}

TEST(FieldRoutes, DenseScanIsThreadCountInvariant) {
  expectThreadCountInvariant("fountain.xyz", fluid::SurfaceFieldRoute::denseScan, true);
}

TEST(FieldRoutes, OneExtractorSwitchingRoutesAndSetsMeshesAsFreshOnes) {
  // The game switches the route live: each worker's scratch (the dense scan's two slices and the
  // value scan's four, which they only clear where their last splat wrote; the walk's slices and
  // volume) must not leak from one route or set into the next.
  const std::tuple<const char*, float> sets[] = {{"fountain.xyz", 1.0f}, {"spray.xyz", 1.0f}, {"blob.xyz", 0.3f}};
  const fluid::SurfaceFieldRoute routes[] = {fluid::SurfaceFieldRoute::denseScan, fluid::SurfaceFieldRoute::sliceSplat,
                                             fluid::SurfaceFieldRoute::valueScan, fluid::SurfaceFieldRoute::denseScan,
                                             fluid::SurfaceFieldRoute::particleCache, fluid::SurfaceFieldRoute::valueScan};
  std::vector<fluid::ParticlePositions> data;
  for (const auto& [name, cube] : sets) data.push_back(loadSet(name));
  fluid::SurfaceExtractor reused;
  fluid::SurfaceMesh m;
  for (int round = 0; round < 2; ++round)
    for (std::size_t i = 0; i < data.size(); ++i)
      for (const fluid::SurfaceFieldRoute route : routes) {
        fluid::SurfaceParams p;
        p.cube = std::get<1>(sets[i]);
        p.threads = 2;
        p.fieldRoute = route;
        ASSERT_TRUE(reused.extract(inputOf(data[i]), p, m).ok());
        EXPECT_EQ(test_support::meshBitsDiffer(m, meshWith(inputOf(data[i]), p, route)), "")
            << std::get<0>(sets[i]) << " route " << int(route) << " round " << round;
      }
}

TEST(FieldRoutes, AutomaticIsTheDenseScan) {
  // The default route: the slice splat and the dense scan in every block of every set (dense and
  // sparse, small and large discs), the walk's vertex bits (the cache route's, checked above).
  for (const auto& [name, cube] : kTestSets) {
    const fluid::ParticlePositions ps = loadSet(name);
    fluid::SurfaceParams p;
    p.cube = cube;
    p.threads = 1;
    EXPECT_EQ(p.fieldRoute, fluid::SurfaceFieldRoute::automatic);
    const fluid::SurfaceMesh automatic = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::automatic);
    const fluid::SurfaceMesh scan = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::denseScan);
    const fluid::SurfaceMesh cache = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::particleCache);
    EXPECT_EQ(automatic.stats.splatBlocks, automatic.stats.blocks) << name;
    EXPECT_EQ(automatic.stats.scannedBlocks, automatic.stats.blocks) << name;
    EXPECT_EQ(cache.stats.splatBlocks, 0u) << name;
    EXPECT_EQ(cache.stats.scannedBlocks, 0u) << name;
    EXPECT_EQ(test_support::meshBitsDiffer(automatic, scan), "") << name;
    expectScanIsTheWalkUpToOrder(inputOf(ps), automatic, cache, p, name);
  }
}

TEST(FieldRoutes, SliceSplatIsThreadCountInvariant) {
  expectThreadCountInvariant("spray.xyz", fluid::SurfaceFieldRoute::sliceSplat, false);
}

TEST(FieldRoutes, HiddenStyleCases) {
  {  // an upright bowl: the sweep reverses (paper Fig. 4b)
    const fluid::ParticlePositions bowl = uprightBowl();
    fluid::SurfaceParams p;
    p.cube = 0.5f;
    p.blockCubes = 64;
    const fluid::SurfaceMesh m = expectRoutesAgree(inputOf(bowl), p, "bowl", 1000);
    EXPECT_GT(m.stats.slabReversals, 0u);
  }
  {  // 1e5 from the origin
    fluid::SurfaceParams p;
    const fluid::ParticlePositions ps = blobOffsetBy1e5(p);
    expectRoutesAgree(inputOf(ps), p, "offset 1e5", 1000);
  }
  {  // field exactly T at corners (Rc = 2, S = 1, T = 1/8 - 1/2 squared)
    const std::vector<glm::vec3> ps = {{0, 0, 0}, {3, 0, 1}};
    fluid::SurfaceParams p;
    p.rc = 2.0f;
    p.threshold = 0.140625f;
    expectRoutesAgree({fluid::pointView(ps)}, p, "exactly T");
  }
  {  // coincident particles
    const std::vector<glm::vec3> ps(7, glm::vec3(1.25f, -2.5f, 0.75f));
    fluid::SurfaceParams p;
    p.cube = 0.25f;
    expectRoutesAgree({fluid::pointView(ps)}, p, "coincident", 100);
  }
  {  // particles on corners and block faces, tiny blocks (many seams, margins clamp every side)
    std::vector<glm::vec3> ps;
    for (float a : {-4.0f, -2.5f, 0.0f, 1.5f, 4.0f, 4.5f, 8.0f})
      for (float b : {-4.0f, -1.0f, 0.0f, 4.0f})
        for (float c : {0.0f, 2.0f, 4.0f}) ps.push_back({a, b, c});
    for (int blockCubes : {4, 5, 8}) {
      fluid::SurfaceParams p;
      p.cube = 0.5f;
      p.blockCubes = blockCubes;
      expectRoutesAgree({fluid::pointView(ps)}, p, "corners, blockCubes " + std::to_string(blockCubes), 100);
    }
  }
  {  // per-particle strength and radius scale (Rc_i differ: reach and disc per particle)
    const fluid::ParticlePositions ps = loadSet("fountain.xyz");
    std::vector<float> strength(ps.size()), scale(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) {
      strength[i] = 0.6f + 0.1f * float(i % 7);
      scale[i] = 0.5f + 0.15f * float(i % 5);
    }
    fluid::SurfaceParams p;
    p.cube = 0.75f;
    expectRoutesAgree({fluid::pointView(ps), strength, scale, {}}, p, "strength and radius scale", 1000);
  }
}

TEST(FieldRoutes, RandomSetsAgree) {
  // The property sweep's random sets (clusters, sheets, lines, lattices, duplicates, exact-T
  // values, mixed radii; random S, Rc, blocks, views): both routes give the same bits, and the
  // dense scan the walk's triangles, or the dense oracle's where seeding misses a component.
  const int scannedBefore = gScannedMeshes, ghostsBefore = gScansWithGhosts, samePlanBefore = gSamePlanScans;
  for (int seed = 1; seed <= 48; ++seed) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    expectRoutesAgree(r.input(), r.params, "seed " + std::to_string(seed), 0, false);
  }
  EXPECT_EQ(gScannedMeshes - scannedBefore, 48) << "the dense scan did not run on every set";
  EXPECT_GE(gScansWithGhosts - ghostsBefore, 1) << "no set exercised the oracle comparison";
  EXPECT_GE(gSamePlanScans - samePlanBefore, 24) << "too few sets compared block by block";
}

TEST(FieldRoutes, UserDataAndPoliciesKeepTheCacheRoute) {
  // Per-corner policy data is summed one particle at a time per corner, which the splat does not
  // do: asking for it there gives the cache route's mesh and attributes.
  const fluid::ParticlePositions ps = loadSet("blob.xyz");
  std::vector<glm::vec4> user(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) user[i] = glm::vec4(float(i), 1.0f, -2.0f, 0.5f);
  fluid::SurfaceParams p;
  p.cube = 0.3f;
  const fluid::SurfaceInput in{fluid::pointView(ps), {}, {}, user};
  const fluid::SurfaceMesh cache = meshWith(in, p, fluid::SurfaceFieldRoute::particleCache);
  const fluid::SurfaceMesh splat = meshWith(in, p, fluid::SurfaceFieldRoute::sliceSplat);
  ASSERT_FALSE(cache.attributes.empty());
  EXPECT_EQ(test_support::meshBitsDiffer(splat, cache), "");
}

}  // namespace
