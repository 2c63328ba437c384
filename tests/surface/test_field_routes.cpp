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

#include <cmath>
#include <string>
#include <vector>

using namespace surface_test;

namespace {

fluid::SurfaceMesh meshWith(const fluid::SurfaceInput& in, fluid::SurfaceParams p, fluid::SurfaceFieldRoute route) {
  p.fieldRoute = route;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}

// Both routes on `in`: the same mesh bit for bit (every array, block and slab ranges included),
// closed, and (unless `oracleToo` is off) the dense oracle's triangles. Returns the splat mesh.
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
      expectRoutesAgree(inputOf(ps), p, std::string(name) + " variant " + std::to_string(variant), 1000);
    }
  }
}

TEST(FieldRoutes, AutomaticPicksTheSplatForDenseSetsWithSmallDiscs) {
  // The default route: the splat on fountain and explosion (dense, ceil(Rc / S) <= 5, block fields
  // within the volume budget), the cache on blob (ceil(Rc / S) = 10) and spray (large sparse
  // blocks); the same bits either way.
  const std::tuple<const char*, float, bool> sets[] = {{"fountain.xyz", 1.0f, true},
                                                       {"blob.xyz", 0.3f, false},
                                                       {"explosion.xyz", 0.6f, true},
                                                       {"spray.xyz", 1.0f, false}};
  for (const auto& [name, cube, splat] : sets) {
    const fluid::ParticlePositions ps = loadSet(name);
    fluid::SurfaceParams p;
    p.cube = cube;
    p.threads = 1;
    EXPECT_EQ(p.fieldRoute, fluid::SurfaceFieldRoute::automatic);
    const fluid::SurfaceMesh automatic = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::automatic);
    const fluid::SurfaceMesh cache = meshWith(inputOf(ps), p, fluid::SurfaceFieldRoute::particleCache);
    EXPECT_EQ(automatic.stats.splatBlocks, splat ? automatic.stats.blocks : 0u) << name;
    EXPECT_EQ(cache.stats.splatBlocks, 0u) << name;
    EXPECT_EQ(test_support::meshBitsDiffer(automatic, cache), "") << name;
  }
}

TEST(FieldRoutes, SliceSplatIsThreadCountInvariant) {
  const fluid::ParticlePositions ps = loadSet("spray.xyz");
  fluid::SurfaceParams p;
  p.blockCubes = 16;
  p.threads = 1;
  p.fieldRoute = fluid::SurfaceFieldRoute::sliceSplat;
  fluid::SurfaceExtractor ex1;
  fluid::SurfaceMesh one;
  ASSERT_TRUE(ex1.extract(inputOf(ps), p, one).ok());
  ASSERT_GT(one.blocks.size(), 8u);
  for (int threads : {2, 3}) {
    p.threads = threads;
    fluid::SurfaceExtractor ex;
    fluid::SurfaceMesh m;
    for (int rep = 0; rep < 2; ++rep) {  // and again with warm scratch
      ASSERT_TRUE(ex.extract(inputOf(ps), p, m).ok());
      EXPECT_EQ(test_support::meshBitsDiffer(m, one), "") << threads << " threads, rep " << rep;
    }
  }
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
  // values, mixed radii; random S, Rc, blocks, views): both routes give the same bits.
  for (int seed = 1; seed <= 48; ++seed) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    expectRoutesAgree(r.input(), r.params, "seed " + std::to_string(seed), 0, false);
  }
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
