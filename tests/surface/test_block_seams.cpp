// Block membership at seams (issue 15): a particle whose reach ends exactly on a block's first
// lattice plane. The set captured from the game (tests/data/fountain_mesher_abort*.xyz) broke the
// particle cache's anchor invariant (block_mesher.inl: 0 <= anchor - g0 <= n) and aborted.
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

using namespace surface_test;

namespace {

// The dense oracle's triangles and positions, and closed output, at 1, 2 and 3 threads.
void expectOracleAtOneTwoThreeThreads(const fluid::SurfaceInput& in, fluid::SurfaceParams p, std::size_t minTriangles,
                                      const std::string& what) {
  fluid::BaselineExtractor dense;
  fluid::SurfaceMesh ref;
  ASSERT_TRUE(dense.extract(fluid::BaselineMethod::dense, in, p, ref).ok());
  std::unordered_map<std::uint64_t, glm::vec3> refPos;
  for (std::size_t v = 0; v < ref.positions.size(); ++v) refPos[ref.edgeKeys[v]] = ref.positions[v];
  fluid::SurfaceMesh one;
  for (int threads : {1, 2, 3}) {
    p.threads = threads;
    fluid::SurfaceExtractor ex;
    fluid::SurfaceMesh m;
    const fluid::SurfaceStatus st = ex.extract(in, p, m);
    ASSERT_TRUE(st.ok()) << what << ": " << st.error;
    const Topology t = checkTopology(m);
    EXPECT_GE(t.triangles, minTriangles) << what;
    EXPECT_EQ(t.badEdges, 0u) << what << ", " << threads << " threads";
    EXPECT_TRUE(canonicalTriangles(m) == canonicalTriangles(ref)) << what << ", " << threads << " threads";
    std::size_t differ = 0;
    for (std::size_t v = 0; v < m.positions.size(); ++v) differ += refPos.at(m.edgeKeys[v]) != m.positions[v];
    EXPECT_EQ(differ, 0u) << what << ", " << threads << " threads";
    if (threads == 1)
      one = m;
    else
      EXPECT_TRUE(m.positions == one.positions && m.indices == one.indices) << what << ", " << threads << " threads";
  }
}

fluid::SurfaceParams fountainParams() {
  // The game's fountain: particle spacing 0.08, smoothing 2 and cube 0.5 spacings, so Rc = 4 S.
  fluid::SurfaceParams p;
  p.rc = 0.159999996f;
  p.cube = 0.0399999991f;
  p.threshold = 0.200000003f;
  p.order = fluid::SurfaceOrder::backToFront;
  p.eye = {0.5f, 2.5999999f, 9.5f};
  p.viewDir = {-0.0513743795f, -0.190808997f, -0.98028183f};
  return p;
}

}  // namespace

TEST(BlockSeams, FountainSetCapturedFromTheGameEqualsOracle) {
  for (const char* name : {"fountain_mesher_abort.xyz", "fountain_mesher_abort_min.xyz"}) {
    const fluid::ParticlePositions ps = loadSet(name);
    fluid::SurfaceParams p = fountainParams();
    expectOracleAtOneTwoThreeThreads(inputOf(ps), p, 24, name);
    p.order = fluid::SurfaceOrder::none;
    expectOracleAtOneTwoThreeThreads(inputOf(ps), p, 24, std::string(name) + " unordered");
  }
}

// One particle a hair below a lattice plane k S with Rc = m S exactly: (p + Rc) / S rounds to
// k + m, a block's first plane, though the particle's anchor is k - 1 and it reaches no corner
// beyond k + m - 1. Blocks of 10 cubes put a seam there for k = 0 (lattice0 = -6, seam at 4).
TEST(BlockSeams, ParticleJustBelowALatticePlaneWithRcAWholeNumberOfCubes) {
  const float s = 0.04f;
  for (int m : {1, 2, 4}) {
    for (float x : {-2.87305838e-20f, -1e-30f, -std::numeric_limits<float>::denorm_min(), std::nextafter(0.0f, -1.0f),
                    -1e-9f, 0.0f}) {
      for (int blockCubes : {4, 5, 6, 10}) {
        const std::vector<glm::vec3> ps = {{x, 0.0f, 0.0f}, {x, 0.5f, 0.1f}, {3.0f * s, 0.25f, 0.3f}};
        fluid::SurfaceParams p;
        p.cube = s;
        p.rc = s * float(m);
        p.blockCubes = blockCubes;
        expectOracleAtOneTwoThreeThreads(
            {fluid::pointView(ps)}, p, 8,
            "x " + std::to_string(x) + ", Rc/S " + std::to_string(m) + ", blockCubes " + std::to_string(blockCubes));
      }
    }
  }
}
