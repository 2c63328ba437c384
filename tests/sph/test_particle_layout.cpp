// The SoA position arrays the surface mesher reads (sphPositionArrays): after every step they
// hold exactly the stored positions, in storage order (the step re-sorts particles by cell), and
// they never expose arrays of another size.
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace {

using namespace fluid;

void expectArraysMatchPositions(const SphWorld& world, const char* when) {
  const SphPositionArrays arrays = sphPositionArrays(world);
  const auto& positions = world.particles.position;
  ASSERT_EQ(arrays.x.size(), positions.size()) << when;
  ASSERT_EQ(arrays.y.size(), positions.size()) << when;
  ASSERT_EQ(arrays.z.size(), positions.size()) << when;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    // Bitwise: the mesher must see the very floats the solver stored.
    ASSERT_EQ(std::memcmp(&arrays.x[i], &positions[i].x, sizeof(float)), 0) << when << ", particle " << i;
    ASSERT_EQ(std::memcmp(&arrays.y[i], &positions[i].y, sizeof(float)), 0) << when << ", particle " << i;
    ASSERT_EQ(std::memcmp(&arrays.z[i], &positions[i].z, sizeof(float)), 0) << when << ", particle " << i;
  }
}

TEST(SphPositionArrays, HoldTheStoredPositionsAfterEveryStepWithEmittersAndSinks) {
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    SphScene s;
    ASSERT_TRUE(makeSphScene("fountain", solver, {{"rate", "3000"}, {"budget", "600"}}, s).ok());
    addSphBlock(s.world, glm::vec3(-0.1f, 0.0f, -0.1f), glm::vec3(0.1f, 0.06f, 0.1f));
    // A few particles inside the drain (a floor corner): the first step removes them.
    addSphBlock(s.world, glm::vec3(-0.5f, 0.0f, -0.5f), glm::vec3(-0.42f, 0.02f, -0.42f));
    expectArraysMatchPositions(s.world, "after addSphBlock");
    std::size_t removed = 0, emitted = 0;
    for (int step = 0; step < 60; ++step) {
      SphStepStats stats;
      ASSERT_TRUE(stepSph(s.world, 0.0f, &stats).ok());
      removed += stats.removed;
      emitted += stats.emitted;
      expectArraysMatchPositions(s.world, sphSolverName(solver));
    }
    EXPECT_GT(emitted, 0u) << sphSolverName(solver);  // the store grew and shrank during the run
    EXPECT_GT(removed, 0u) << sphSolverName(solver);
  }
}

TEST(SphPositionArrays, AreEmptyWhenNotKeptCurrentAndRefreshOnRequest) {
  SphScene s;
  ASSERT_TRUE(makeSphScene("column", SphSolverKind::dfsph, {}, s).ok());
  ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
  // A caller that grows `position` itself bypasses the arrays: they must not be read as current.
  s.world.particles.position.push_back(glm::vec3(0.1f));
  EXPECT_EQ(sphPositionArrays(s.world).x.size(), 0u);
  refreshSphPositionArrays(s.world);
  expectArraysMatchPositions(s.world, "after refreshSphPositionArrays");
}

}  // namespace
