// ReachCulledCollider (collide.hpp): the grid of cells the maps place beyond reach never culls a
// point the collider answers within reach, answers like the collider everywhere else, and does
// cull most of the far points (otherwise it would be correct and useless).
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"

#include <gtest/gtest.h>

#include <cfloat>
#include <cstring>
#include <random>

namespace {

using collide_test::Mesh;
using fluid::DepthMapFormat;

std::shared_ptr<const fluid::DepthMapCollider> bake(const Mesh& mesh, const std::vector<fluid::MapSpec>& specs) {
  auto collider = std::make_shared<fluid::DepthMapCollider>();
  const fluid::BakeStatus status = fluid::bakeDepthMaps(mesh.view(), specs, {256, 0}, *collider);
  EXPECT_TRUE(status.ok()) << status.error;
  return collider;
}

bool sameSample(const fluid::ColliderSample& a, const fluid::ColliderSample& b) {
  return a.valid == b.valid && std::memcmp(&a.distance, &b.distance, sizeof(float)) == 0 &&
         std::memcmp(&a.normal, &b.normal, sizeof(glm::vec3)) == 0;
}

// Uniform points over the box plus points jittered around the mesh's vertices (the band where a
// wrong cell would show).
std::vector<glm::vec3> testPoints(const Mesh& mesh, const fluid::Bounds& box, float reach, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), j(-1.5f, 1.5f);
  std::vector<glm::vec3> points(60000);
  for (glm::vec3& p : points) p = box.lo + (box.hi - box.lo) * glm::vec3(u(rng), u(rng), u(rng));
  for (int pass = 0; pass < 8; ++pass)
    for (const glm::vec3& v : mesh.positions) points.push_back(v + reach * glm::vec3(j(rng), j(rng), j(rng)));
  return points;
}

void checkGrid(const Mesh& mesh, const std::shared_ptr<const fluid::DepthMapCollider>& collider, float reach,
               double min_far_share) {
  fluid::Bounds box = fluid::meshBounds(mesh.view());
  box.lo -= glm::vec3(2.0f * reach);
  box.hi += glm::vec3(2.0f * reach);
  fluid::ReachGridDesc desc;
  desc.reach = reach;
  const fluid::ReachCulledCollider culled(collider, box, desc);
  std::size_t far_points = 0, far_culled = 0, wrong = 0;
  const std::vector<glm::vec3> points = testPoints(mesh, box, reach, 5);
  std::vector<fluid::ColliderSample> batch(points.size());
  culled.query(points, batch);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const glm::vec3 p = points[k];
    const fluid::ColliderSample full = collider->sample(p);
    const bool beyond = !full.valid || full.distance >= reach;
    if (culled.culled(p)) {
      // The one thing that must never happen: a culled point the collider answers within reach.
      if (!beyond) {
        ++wrong;
        ADD_FAILURE() << "culled within reach: " << p.x << " " << p.y << " " << p.z << " d " << full.distance;
      }
      EXPECT_FALSE(batch[k].valid);
      EXPECT_EQ(batch[k].distance, FLT_MAX);
    } else {
      EXPECT_TRUE(sameSample(batch[k], full)) << p.x << " " << p.y << " " << p.z;
    }
    // Far points inside the box, a cell diagonal or more past the reach: most must be culled.
    const bool in_box = glm::all(glm::greaterThanEqual(p, box.lo)) && glm::all(glm::lessThanEqual(p, box.hi));
    if (in_box && full.valid && full.distance >= reach + 2.0f * glm::length(culled.cell())) {
      ++far_points;
      far_culled += culled.culled(p);
    }
    if (wrong > 5) break;
  }
  ASSERT_GT(far_points, 1000u);
  EXPECT_GE(static_cast<double>(far_culled), min_far_share * static_cast<double>(far_points))
      << far_culled << " of " << far_points << " far points culled";
  EXPECT_GT(culled.farFraction(), 0.1);
}

TEST(ReachGrid, SphereInEveryFormat) {
  const Mesh sphere = collide_test::makeSphere(1.0f, 24, 48);
  const fluid::Bounds bounds = fluid::meshBounds(sphere.view());
  for (DepthMapFormat format : {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16}) {
    SCOPED_TRACE(fluid::formatName(format));
    checkGrid(sphere, bake(sphere, fluid::defaultMapSpecs(bounds, 128, format)), 0.16f, 0.9);
  }
  SCOPED_TRACE("cube8 alone (GREATER, centre inside)");
  const auto specs = fluid::defaultMapSpecs(bounds, 128, DepthMapFormat::front_back16, true);
  checkGrid(sphere, bake(sphere, {specs.back()}), 0.16f, 0.5);
}

TEST(ReachGrid, BasinWithCavityCubeAndMarginRings) {
  // The concave basin with a LESS cavity cube (centre outside the collider) and ortho maps with a
  // margin ring as wide as the reach, like the fountain's basin recipe.
  const Mesh basin = collide_test::makeBasin(64);
  const float reach = 0.12f;
  auto specs = fluid::defaultMapSpecs(fluid::meshBounds(basin.view()), 128, DepthMapFormat::front_back16);
  for (fluid::MapSpec& s : specs) s.margin = reach;
  specs.push_back(collide_test::basinCavityCube(128));
  // Lower share: near the cavity cube's centre a cell spans many of its texels (directions).
  checkGrid(basin, bake(basin, specs), reach, 0.65);
}

TEST(ReachGrid, TorusAndThinWall) {
  const Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 48, 24);
  checkGrid(torus,
            bake(torus, fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 128, DepthMapFormat::front_back16)),
            0.1f, 0.8);
  const Mesh wall = collide_test::makeBox({-0.03f, -1.0f, -1.0f}, {0.03f, 1.0f, 1.0f});
  checkGrid(wall, bake(wall, fluid::defaultMapSpecs(fluid::meshBounds(wall.view()), 64, DepthMapFormat::front_back16)),
            0.1f, 0.9);
}

TEST(ReachGrid, NonFiniteAndOutsideTheBoxAreBeyondReach) {
  const Mesh sphere = collide_test::makeSphere(1.0f, 12, 24);
  const auto collider =
      bake(sphere, fluid::defaultMapSpecs(fluid::meshBounds(sphere.view()), 64, DepthMapFormat::front_back16));
  fluid::ReachGridDesc desc;
  desc.reach = 0.2f;
  const fluid::ReachCulledCollider culled(collider, {glm::vec3(-1.4f), glm::vec3(1.4f)}, desc);
  for (const glm::vec3 p : {glm::vec3(NAN, 0.0f, 0.0f), glm::vec3(INFINITY), glm::vec3(3.0f, 0.0f, 0.0f)}) {
    const fluid::ColliderSample s = culled.sample(p);
    EXPECT_FALSE(s.valid);
    EXPECT_EQ(s.distance, FLT_MAX);
  }
  // Inside the collider: never culled (the surface is within reach of every inside point here).
  EXPECT_FALSE(culled.culled(glm::vec3(0.9f, 0.0f, 0.0f)));
  EXPECT_TRUE(culled.sample(glm::vec3(0.9f, 0.0f, 0.0f)).distance < 0.0f);
  // A grid too large for max_cells coarsens instead of allocating without bound.
  desc.max_cells = 1000;
  const fluid::ReachCulledCollider coarse(collider, {glm::vec3(-1.4f), glm::vec3(1.4f)}, desc);
  EXPECT_LE(static_cast<std::size_t>(coarse.cells().x) * coarse.cells().y * coarse.cells().z, 1000u);
}

}  // namespace
