// One particle layout (DESIGN.md habit 3): the surface mesher reads the SPH store's own vec3
// positions in place through a pointer + stride view (fluid::pointView), with no copy kept in step
// by the solver. After steps that emit, drain and re-sort particles the view covers exactly the
// stored positions, and meshing through it gives the same bits as meshing the same points held in
// another layout (a padded stride), so the layout never changes the surface.
#include "fluid/sph/sph_scenes.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <gtest/gtest.h>
#include <glm/vec4.hpp>

#include <cstring>
#include <vector>

namespace {

using namespace fluid;

// The mesh of the store's positions read in place, against the mesh of a stride-16 copy.
void expectInPlaceMeshMatchesCopy(const SphWorld& world, const char* when) {
  const std::vector<glm::vec3>& positions = world.particles.position;
  const PointView view = pointView(positions);
  ASSERT_EQ(view.count, positions.size()) << when;
  ASSERT_EQ(view.data, positions.empty() ? nullptr : &positions[0].x) << when;  // in place, no copy
  std::vector<glm::vec4> padded(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) padded[i] = glm::vec4(positions[i], -1.0f);
  const PointView paddedView{padded.empty() ? nullptr : &padded[0].x, padded.size(), sizeof(glm::vec4)};

  SurfaceParams p;  // the game's water field: Rc = 2 spacings, cube half a spacing
  p.rc = 2.0f * sphSpacing(world.params);
  p.cube = 0.5f * sphSpacing(world.params);
  p.threads = 1;
  SurfaceExtractor a, b;
  SurfaceMesh inPlace, copied;
  ASSERT_TRUE(a.extract({view}, p, inPlace).ok()) << when;
  ASSERT_TRUE(b.extract({paddedView}, p, copied).ok()) << when;
  ASSERT_GT(inPlace.indices.size(), 0u) << when;
  EXPECT_EQ(inPlace.indices, copied.indices) << when;
  ASSERT_EQ(inPlace.positions.size(), copied.positions.size()) << when;
  EXPECT_EQ(
      std::memcmp(inPlace.positions.data(), copied.positions.data(), inPlace.positions.size() * sizeof(glm::vec3)), 0)
      << when;
  EXPECT_EQ(std::memcmp(inPlace.normals.data(), copied.normals.data(), inPlace.normals.size() * sizeof(glm::vec3)), 0)
      << when;
}

TEST(SphParticleLayout, MesherReadsTheStoreInPlaceAfterStepsWithEmittersAndSinks) {
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    SphScene s;
    ASSERT_TRUE(makeSphScene("fountain", solver, {{"rate", "3000"}, {"budget", "600"}}, s).ok());
    addSphBlock(s.world, glm::vec3(-0.1f, 0.0f, -0.1f), glm::vec3(0.1f, 0.06f, 0.1f));
    // A few particles inside the drain (a floor corner): the first step removes them.
    addSphBlock(s.world, glm::vec3(-0.5f, 0.0f, -0.5f), glm::vec3(-0.42f, 0.02f, -0.42f));
    expectInPlaceMeshMatchesCopy(s.world, "after addSphBlock");
    std::size_t removed = 0, emitted = 0;
    for (int step = 0; step < 60; ++step) {
      SphStepStats stats;
      ASSERT_TRUE(stepSph(s.world, 0.0f, &stats).ok());
      removed += stats.removed;
      emitted += stats.emitted;
      if (step % 20 == 19) expectInPlaceMeshMatchesCopy(s.world, sphSolverName(solver));
    }
    EXPECT_GT(emitted, 0u) << sphSolverName(solver);  // the store grew and shrank during the run
    EXPECT_GT(removed, 0u) << sphSolverName(solver);
  }
}

}  // namespace
