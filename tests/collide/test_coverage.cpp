// Near-surface coverage and the automatic concave-region cubes (issue 32; coverage.hpp, Kolb et al.
// 2004 §4.1): on models made here (torus, bowl, mug with a handle, pipe, thin dish) every point within
// reach of the surface answers a finite distance of the right sign once the default bake (the axis
// maps with a margin ring as wide as the reach, then the cubes) has chosen its maps.
#include "collide_meshes.hpp"
#include "fluid/collide/collider_cache.hpp"
#include "fluid/collide/coverage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using collide_test::Mesh;

constexpr float kReach = 0.16f;  // the game's SPH support, 4 × particle_radius 0.04

struct Baked {
  std::vector<fluid::MapSpec> specs;
  std::vector<fluid::DepthMap> maps;
};

// The axis maps of bake-collider's default (front-back16, margin = reach).
Baked bakeAxes(const Mesh& mesh, int res) {
  Baked b;
  fluid::BakeRecipe recipe;
  recipe.resolution = res;
  recipe.margin = kReach;
  std::string error;
  EXPECT_TRUE(fluid::recipeMapSpecs(recipe, fluid::meshBounds(mesh.view()), b.specs, error)) << error;
  fluid::DepthMapCollider c;
  const fluid::BakeStatus st = fluid::bakeDepthMaps(mesh.view(), b.specs, {256, 0}, c);
  EXPECT_TRUE(st.ok()) << st.error;
  b.maps = c.maps();
  return b;
}

struct AutoBake {
  fluid::DepthMapCollider collider;
  fluid::ConcaveCubesResult chosen;
  float tolerance = 0.0f;
};

AutoBake bakeAuto(const Mesh& mesh, int res = 256) {
  const Baked axes = bakeAxes(mesh, res);
  const fluid::MeshDistance exact(mesh.view());
  fluid::CoverageDesc cd;
  cd.reach = kReach;
  cd.max_points = 60000;
  const fluid::NearSurfaceSamples samples = fluid::nearSurfaceSamples(exact, fluid::meshBounds(mesh.view()), cd);
  AutoBake out;
  fluid::ConcaveCubesDesc desc;
  desc.resolution = res;
  out.chosen = fluid::chooseConcaveCubes(mesh.view(), exact, samples, axes.specs, axes.maps, desc);
  EXPECT_TRUE(out.chosen.status.ok()) << out.chosen.status.error;
  std::vector<fluid::DepthMap> all = axes.maps;
  all.insert(all.end(), out.chosen.maps.begin(), out.chosen.maps.end());
  out.collider = fluid::DepthMapCollider(std::move(all), 256);
  out.tolerance = fluid::coverageTolerance(axes.specs);
  return out;
}

// Independent of the lattice the bake chose on: seeded uniform points in the padded bounds, those
// within reach, each answering finite and of the right sign (either sign within a texel).
void expectEveryNearPointCovered(const Mesh& mesh, const fluid::DepthMapCollider& collider, float tolerance,
                                 const char* name) {
  const fluid::Bounds b = fluid::meshBounds(mesh.view());
  const fluid::MeshDistance exact(mesh.view());
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const glm::vec3 lo = b.lo - glm::vec3(kReach), size = b.hi - b.lo + glm::vec3(2.0f * kReach);
  std::size_t near = 0, bad = 0;
  for (int k = 0; k < 60000; ++k) {
    const glm::vec3 p = lo + size * glm::vec3(u(rng), u(rng), u(rng));
    const fluid::ColliderSample e = exact.sample(p);
    if (!(std::fabs(e.distance) < kReach)) continue;
    ++near;
    const fluid::ColliderSample got = collider.sample(p);
    if (fluid::coveredSample(got, e, tolerance)) continue;
    if (++bad <= 5) {
      ADD_FAILURE() << name << ": (" << p.x << ", " << p.y << ", " << p.z << ") exact " << e.distance << " answered "
                    << (got.valid ? std::to_string(got.distance) : std::string("inf"));
    }
  }
  EXPECT_GT(near, 1000u) << name;
  EXPECT_EQ(bad, 0u) << name << ": " << bad << " of " << near << " near points not covered";
}

TEST(Coverage, TorusHoleGetsACubeAndEveryNearPointIsCovered) {
  const Mesh torus = collide_test::makeTorus(0.6f, 0.2f, 48, 16);
  const AutoBake a = bakeAuto(torus);
  ASSERT_GE(a.chosen.cubes.size(), 1u);
  // The first cube sits in the hole, near the axis (the middle of the cavity).
  const glm::vec3 c = a.chosen.cubes.front().cube.center;
  EXPECT_LT(glm::length(glm::vec2(c.x, c.y)), 0.1f);
  EXPECT_LT(a.chosen.after.unmeasured.size(), a.chosen.before.unmeasured.size());
  // The point: 1 cm from the inner wall, in the hole, within the support: about 0.01 now.
  const fluid::ColliderSample s = a.collider.sample({0.39f, 0.0f, 0.0f});
  ASSERT_TRUE(s.valid);
  EXPECT_NEAR(s.distance, 0.01f, 0.006f);
  EXPECT_NEAR(a.collider.sample({0.3f, 0.0f, 0.0f}).distance, 0.1f, 0.01f);
  expectEveryNearPointCovered(torus, a.collider, a.tolerance, "torus");
}

TEST(Coverage, AxisMapsWithoutMarginLeaveTheTorusHoleBeyondReach) {
  const Mesh torus = collide_test::makeTorus(0.6f, 0.2f, 48, 16);
  const fluid::DepthMapCollider c(
      [&] {
        fluid::DepthMapCollider out;
        fluid::bakeDepthMaps(torus.view(), fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 256), {256, 0}, out);
        return out.maps();
      }(),
      256);
  EXPECT_FALSE(c.sample({0.39f, 0.0f, 0.0f}).valid);  // the issue, as it was
  const fluid::MeshDistance exact(torus.view());
  fluid::CoverageDesc cd;
  cd.reach = kReach;
  cd.max_points = 20000;
  const fluid::NearSurfaceSamples samples = fluid::nearSurfaceSamples(exact, fluid::meshBounds(torus.view()), cd);
  const fluid::CoverageReport r = fluid::measureCoverage(c, samples, 0.01f);
  EXPECT_GT(r.beyond_reach, 0u);
  EXPECT_LT(r.coveredShare(), 1.0);
}

TEST(Coverage, BowlMugPipeAndDishCoverEveryNearPoint) {
  const struct {
    const char* name;
    Mesh mesh;
  } models[] = {{"bowl", collide_test::makeBowl(64)},
                {"mug", collide_test::makeMug(64)},
                {"pipe", collide_test::makePipe(64)},
                {"dish", collide_test::makeDish(64)}};
  for (const auto& m : models) {
    SCOPED_TRACE(m.name);
    const AutoBake a = bakeAuto(m.mesh);
    EXPECT_EQ(a.chosen.after.uncovered(), 0u) << m.name;
    EXPECT_GE(a.chosen.after.measuredShare(), a.chosen.before.measuredShare());
    expectEveryNearPointCovered(m.mesh, a.collider, a.tolerance, m.name);
  }
}

TEST(Coverage, BowlRimHidesItsCavityFromTheAxisMapsAndACubeSeesIt) {
  const Mesh bowl = collide_test::makeBowl(64);
  const AutoBake a = bakeAuto(bowl);
  EXPECT_GT(a.chosen.before.wrong_sign, 0u);  // cavity points under the rim read inside
  EXPECT_EQ(a.chosen.after.wrong_sign, 0u);
  ASSERT_GE(a.chosen.cubes.size(), 1u);
  EXPECT_EQ(a.chosen.cubes.front().compare, fluid::DepthCompare::less);
}

TEST(Coverage, ChosenCubesAreRecipeItemsThatBakeTheSameMaps) {
  const Mesh torus = collide_test::makeTorus(0.6f, 0.2f, 48, 16);
  const AutoBake a = bakeAuto(torus, 128);
  ASSERT_FALSE(a.chosen.items.empty());
  fluid::BakeRecipe recipe;
  recipe.maps = "axes," + a.chosen.items;
  recipe.resolution = 128;
  recipe.margin = kReach;
  std::vector<fluid::MapSpec> specs;
  std::string error;
  ASSERT_TRUE(fluid::recipeMapSpecs(recipe, fluid::meshBounds(torus.view()), specs, error)) << error;
  fluid::DepthMapCollider again;
  ASSERT_TRUE(fluid::bakeDepthMaps(torus.view(), specs, {256, 0}, again).ok());
  ASSERT_EQ(again.maps().size(), a.collider.maps().size());
  for (std::size_t m = 0; m < again.maps().size(); ++m) {
    EXPECT_EQ(again.maps()[m].resolution, a.collider.maps()[m].resolution) << m;
    EXPECT_TRUE(again.maps()[m].texels == a.collider.maps()[m].texels) << "map " << m;
  }
}

TEST(Coverage, ChoiceIsIndependentOfTheThreadCount) {
  const Mesh bowl = collide_test::makeBowl(48);
  const Baked axes = bakeAxes(bowl, 128);
  const fluid::MeshDistance exact(bowl.view());
  std::string items[2];
  for (int t = 0; t < 2; ++t) {
    fluid::CoverageDesc cd;
    cd.reach = kReach;
    cd.max_points = 20000;
    cd.threads = t + 1;
    const fluid::NearSurfaceSamples s = fluid::nearSurfaceSamples(exact, fluid::meshBounds(bowl.view()), cd);
    fluid::ConcaveCubesDesc desc;
    desc.resolution = 128;
    desc.threads = t + 1;
    items[t] = fluid::chooseConcaveCubes(bowl.view(), exact, s, axes.specs, axes.maps, desc).items;
  }
  EXPECT_EQ(items[0], items[1]);
  EXPECT_FALSE(items[0].empty());
}

TEST(Coverage, CubeItemWithItsOwnResolutionParsesAndBadOnesAreRefused) {
  const fluid::Bounds b{glm::vec3(-1.0f), glm::vec3(1.0f)};
  std::vector<fluid::MapSpec> specs;
  std::string error;
  ASSERT_TRUE(
      fluid::parseMapSpec("cube@0:0.5:-1e-3:0.25:64", b, 256, fluid::DepthMapFormat::front_back16, specs, error))
      << error;
  ASSERT_EQ(specs.size(), 1u);
  EXPECT_EQ(specs[0].resolution, 64);
  EXPECT_EQ(specs[0].cube.center, glm::vec3(0.0f, 0.5f, -1e-3f));
  ASSERT_TRUE(fluid::parseMapSpec("cube@1:2:3:4", b, 32, fluid::DepthMapFormat::front_back16, specs, error));
  EXPECT_EQ(specs[0].resolution, 32);
  for (const char* bad :
       {"cube@1:2:3:4x", "cube@1:2:3:4:3", "cube@1:2:3:4:5000", "cube@1:2:3:4:64:1", "cube@1:2:3", "cube@1:2:3:0",
        "cube@1:2:3:-1", "cube@1::3:4", "cube@nan:0:0:1", "cube@1:2:3:4:6.5", "auto"}) {
    EXPECT_FALSE(fluid::parseMapSpec(bad, b, 32, fluid::DepthMapFormat::front_back16, specs, error)) << bad;
    EXPECT_NE(error.find(bad), std::string::npos) << error;
  }
  EXPECT_EQ(fluid::cubeItemText({0.1f, -2.0f, 3e-5f}, 0.7f, 128), "cube@0.1:-2:3e-05:0.7:128");
}

TEST(Coverage, FirstHitIsTheNearestCrossingAlongTheRay) {
  const Mesh box = collide_test::makeBox(glm::vec3(-0.5f), glm::vec3(0.5f));
  const fluid::MeshDistance exact(box.view());
  EXPECT_NEAR(exact.firstHit({-2.0f, 0.1f, 0.2f}, {1.0f, 0.0f, 0.0f}), 1.5f, 1e-5f);
  EXPECT_NEAR(exact.firstHit({0.0f, 0.1f, 0.2f}, {0.0f, 0.0f, 2.0f}), 0.15f, 1e-5f);  // from inside, |dir| = 2
  EXPECT_TRUE(std::isinf(exact.firstHit({-2.0f, 0.1f, 0.2f}, {-1.0f, 0.0f, 0.0f})));
  EXPECT_NEAR(exact.unsignedDistance({2.0f, 0.0f, 0.0f}), 1.5f, 1e-5f);
  EXPECT_EQ(exact.unsignedDistance({2.0f, 0.0f, 0.0f}, 0.5f), 0.5f);
}

}  // namespace
