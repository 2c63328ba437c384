// The fountain level's baked colliders (content/colliders, issue 18 item 2) on the real models:
// the shipped files match their models, the basin's map set covers its cavity, and every point
// within the SPH support of a surface gets a finite distance, and the SPH's double check never
// throws a particle farther than its step on them.
#include "fluid/collide/collider_cache.hpp"
#include "fluid/core/collider.hpp"
#include "game/world/collider_model.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sph_fluid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

namespace {

namespace fs = std::filesystem;
const fs::path kContent = fs::path(FLUIDDEMO_SOURCE_DIR) / "content";

// SPH support H = 4 r (fluid::SphParams) with the fountain scene's particle radius.
float fountainSupport() {
  game::SceneConfig scene;
  const game::SceneStatus st = game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene);
  EXPECT_TRUE(st.ok()) << st.error;
  const game::SectionConfig* sph = scene.effect("sph_fluid");
  return sph ? 4.0f * static_cast<float>(sph->number("particle_radius")) : 0.0f;
}

struct Part {
  fluid::LevelColliderEntry entry;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  fluid::MeshView view() const { return {positions, indices}; }
};

std::vector<Part> fountainModels() {
  std::vector<fluid::LevelColliderEntry> entries;
  const fluid::CacheStatus st = fluid::readLevelColliders(kContent / "colliders" / "fountain.colliders", entries);
  EXPECT_TRUE(st.ok()) << st.error;
  std::vector<Part> parts;
  for (const auto& e : entries) {
    Part p{e, {}, {}};
    std::string error;
    EXPECT_TRUE(game::colliderModelLoader()(kContent / e.model, p.positions, p.indices, error)) << error;
    parts.push_back(std::move(p));
  }
  return parts;
}

// Seeded points in the part's bounds padded by 0.3 m (the ground: the courtyard around the fountain).
std::vector<glm::vec3> pointsAround(const Part& part, std::size_t count) {
  fluid::Bounds b = fluid::meshBounds(part.view());
  if (part.entry.name == "ground") b = {{-4.0f, -1.2f, -4.0f}, {4.0f, 0.5f, 4.0f}};
  b.lo -= glm::vec3(0.3f);
  b.hi += glm::vec3(0.3f);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> points(count);
  for (glm::vec3& p : points) p = b.lo + (b.hi - b.lo) * glm::vec3(u(rng), u(rng), u(rng));
  return points;
}

fluid::DepthMapCollider bake(const Part& part, const fluid::BakeRecipe& recipe) {
  std::vector<fluid::MapSpec> specs;
  std::string error;
  EXPECT_TRUE(fluid::recipeMapSpecs(recipe, fluid::meshBounds(part.view()), specs, error)) << error;
  fluid::DepthMapCollider c;
  const fluid::BakeStatus st = fluid::bakeDepthMaps(part.view(), specs, {recipe.normal_resolution, 0}, c);
  EXPECT_TRUE(st.ok()) << st.error;
  return c;
}

TEST(FountainColliders, ShippedFilesMatchTheirModels) {
  std::vector<fluid::CachedCollider> parts;
  const fluid::CacheStatus st = fluid::loadLevelColliders(kContent, "fountain", game::colliderModelLoader(),
                                                          fluid::CachePolicy::load_only, parts);
  ASSERT_TRUE(st.ok()) << st.error << " (run: fluiddemo bake-collider --level fountain)";
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(parts[0].name, "ground");
  EXPECT_EQ(parts[1].name, "basin");
  EXPECT_EQ(parts[2].name, "statue");
  for (const auto& p : parts) EXPECT_FALSE(p.rebaked);
}

TEST(FountainColliders, BasinMapSetCoversItsCavity) {
  // Points just inside the basin's cavity, beside its inner wall, fall in y-map texels that the
  // conservative cover fills from the rim, and the x and z maps see them between the walls: the
  // six axis maps call them inside. The cavity cube of the shipped recipe (Kolb §4.1) sees them.
  for (const Part& part : fountainModels()) {
    if (part.entry.name != "basin") continue;
    const std::vector<glm::vec3> points = pointsAround(part, 40000);
    std::vector<fluid::ColliderSample> exact(points.size()), got(points.size());
    fluid::queryParallel(fluid::MeshDistance(part.view()), points, exact);
    // Percentage misclassified, and the largest exact |distance| among them.
    auto misclassified = [&](const fluid::DepthMapCollider& c, float& deepest) {
      fluid::queryParallel(c, points, got);
      std::size_t wrong = 0;
      deepest = 0.0f;
      for (std::size_t k = 0; k < points.size(); ++k)
        if ((exact[k].distance < 0.0f) != (got[k].valid && got[k].distance < 0.0f)) {
          ++wrong;
          deepest = std::max(deepest, std::fabs(exact[k].distance));
        }
      return 100.0 * static_cast<double>(wrong) / static_cast<double>(points.size());
    };
    fluid::BakeRecipe axes = part.entry.recipe;
    axes.maps = "axes";
    float deepest_shipped = 0.0f, deepest_six = 0.0f;
    const double shipped = misclassified(bake(part, part.entry.recipe), deepest_shipped);
    const double six = misclassified(bake(part, axes), deepest_six);
    EXPECT_LT(shipped, 0.6 * six) << shipped << " % against " << six << " % with the six axis maps";
    // What stays wrong is texel quantisation at the surface: within half a texel (6.4 m / 256 / 2).
    const float half_texel = 0.5f * 6.4f / static_cast<float>(part.entry.recipe.resolution);
    EXPECT_LT(deepest_shipped, half_texel) << "six axis maps: up to " << deepest_six << " m deep";
    EXPECT_GT(deepest_six, 2.0f * half_texel);  // the cavity points the cube fixes
    return;
  }
  FAIL() << "no basin in content/colliders/fountain.colliders";
}

TEST(FountainColliders, EveryPointWithinTheSphSupportGetsAFiniteDistance) {
  const float support = fountainSupport();
  ASSERT_GT(support, 0.0f);
  for (const Part& part : fountainModels()) {
    EXPECT_GE(part.entry.recipe.margin, support) << part.entry.name << ": MARGIN below the SPH support";
    const std::vector<glm::vec3> points = pointsAround(part, 30000);
    std::vector<fluid::ColliderSample> exact(points.size()), got(points.size());
    fluid::queryParallel(fluid::MeshDistance(part.view()), points, exact);
    fluid::BakeRecipe no_margin = part.entry.recipe;
    no_margin.margin = 0.0f;
    std::size_t beyond_without = 0;
    for (const fluid::BakeRecipe& recipe : {part.entry.recipe, no_margin}) {
      fluid::queryParallel(bake(part, recipe), points, got);
      std::size_t near = 0, beyond = 0;
      for (std::size_t k = 0; k < points.size(); ++k) {
        if (!(std::fabs(exact[k].distance) < support)) continue;
        ++near;
        beyond += !(got[k].valid && std::isfinite(got[k].distance));
      }
      ASSERT_GT(near, 1000u) << part.entry.name;
      if (recipe.margin > 0.0f) {
        EXPECT_EQ(beyond, 0u) << part.entry.name << ": " << beyond << " of " << near << " points beyond reach";
      } else {
        beyond_without = beyond;
      }
    }
    // The check can fail: without the margin the basin's and the statue's convex edges leave
    // points within the support beyond reach (the ground's slab is seen whole by its y pair).
    if (part.entry.name != "ground") {
      EXPECT_GT(beyond_without, 0u) << part.entry.name;
    }
  }
}

// Seeded points in the ring (radius r0..r1 about the y axis, height y0..y1) round a concave corner.
std::vector<glm::vec3> ringPoints(float r0, float r1, float y0, float y1, std::size_t count) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> points(count);
  for (glm::vec3& p : points) {
    const float angle = 6.2831853f * u(rng), r = r0 + (r1 - r0) * u(rng);
    p = {r * std::cos(angle), y0 + (y1 - y0) * u(rng), r * std::sin(angle)};
  }
  return points;
}

// The statue's dish floor round its spire (the spire's knob covers the floor's texels in the y map)
// reads far deeper than it is: a particle stepping a few millimetres in would be projected half a
// metre (the paper's rule, no slack). The basin's floor beside its wall (the rim covers it) is read
// by the cavity cube alone, within a texel since the cube looks down on it steeply. With the SPH's
// slack (a particle radius, fluid/sph/collisions.cpp) the double check moves no particle farther than
// its step plus slack and twice the skin.
TEST(FountainColliders, DoubleCheckMovesNoParticleFartherThanItsStep) {
  const float support = fountainSupport();
  ASSERT_GT(support, 0.0f);
  const float radius = support / 4.0f, skin = 0.01f * radius, dt = 1.0f / 120.0f;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), length(0.0f, 0.5f * radius);
  for (const Part& part : fountainModels()) {
    if (part.entry.name == "ground") continue;
    const fluid::DepthMapCollider collider = bake(part, part.entry.recipe);
    std::size_t steps_in = 0, thrown_by_paper = 0, thrown = 0, held = 0;
    float worst_paper = 0.0f;
    // Points all round the part, and in the ring round its concave corner (the spire's foot on the
    // dish floor; the basin floor's edge at the wall).
    const game::FountainGeometry g;
    std::vector<glm::vec3> points = pointsAround(part, 300000), ring;
    if (part.entry.name == "statue")
      ring =
          ringPoints(g.spire_radius - 0.05f, g.spire_radius + 0.05f, g.dish_floor - 0.03f, g.dish_floor + 0.05f, 50000);
    else
      ring = ringPoints(g.basin_inner_radius - 0.05f, g.basin_inner_radius + 0.02f, g.basin_floor - 0.03f,
                        g.basin_floor + 0.05f, 50000);
    points.insert(points.end(), ring.begin(), ring.end());
    for (const glm::vec3& from : points) {
      const fluid::ColliderSample before = collider.sample(from);
      if (!before.valid || before.distance < 0.0f || before.distance > radius) continue;
      glm::vec3 direction{u(rng), u(rng), u(rng)};
      if (glm::length(direction) < 1e-3f) continue;
      const glm::vec3 to = from + glm::normalize(direction) * length(rng);
      const fluid::ColliderSample after = collider.sample(to);
      if (!after.valid || after.distance >= 0.0f) continue;
      ++steps_in;
      // A projection moves by skin - distance; a held-back particle returns its step.
      const float step = glm::length(to - from), bound = step + 2.0f * skin + radius + 1e-5f;
      const glm::vec3 velocity = (to - from) / dt;
      const fluid::CollisionResult paper = fluid::resolveCollision(from, before, to, velocity, after, {}, dt, skin, {});
      const float paper_move = glm::length(paper.position - to);
      worst_paper = std::max(worst_paper, paper_move);
      thrown_by_paper += paper_move > bound;
      const fluid::CollisionResult r =
          fluid::resolveCollision(from, before, to, velocity, after, {}, dt, skin, {}, radius);
      thrown += glm::length(r.position - to) > bound;
      held += r.held_back;
      EXPECT_TRUE(std::isfinite(r.velocity.x + r.velocity.y + r.velocity.z));
    }
    ASSERT_GT(steps_in, 1000u) << part.entry.name;
    EXPECT_EQ(thrown, 0u) << part.entry.name;
    if (part.entry.name == "statue") {
      // The check can fail: round the spire's foot the paper's rule alone throws some particles far.
      EXPECT_GT(thrown_by_paper, 0u) << part.entry.name << " (worst " << worst_paper << " m)";
    } else {
      // The basin's cavity cube sees its floor beside the wall steeply enough
      // (BasinFloorBesideItsWallReadsNearItsTrueDistance) that the paper's rule alone throws none.
      EXPECT_EQ(thrown_by_paper, 0u) << part.entry.name << " (worst " << worst_paper << " m)";
    }
    EXPECT_GE(held, thrown_by_paper) << part.entry.name;
    std::printf(
        "%s: %zu steps in, %zu thrown farther than step + %.3f m by the paper's rule (worst %.3f m), "
        "0 with the slack\n",
        part.entry.name.c_str(), steps_in, thrown_by_paper, skin + radius, worst_paper);
  }
}

// The basin floor within a texel of its wall (issue 18): the rim covers those floor texels in the y
// maps and the x and z maps see them between the walls, so the cavity cube alone decides there, and
// a cube measures along its rays (Kolb §4.3): a texel's footprint on a surface its rays graze is long,
// and the distance along the ray errs by up to half of it, about half a texel / tan(grazing angle).
// From a centre 0.25 m above the floor (the first recipe) the rays meet the floor at the wall at 5
// degrees; from 2.8 m above it (the shipped recipe) at 44 degrees.
TEST(FountainColliders, BasinFloorBesideItsWallReadsNearItsTrueDistance) {
  for (const Part& part : fountainModels()) {
    if (part.entry.name != "basin") continue;
    const game::FountainGeometry g;
    const float texel = 6.4f / static_cast<float>(part.entry.recipe.resolution);
    // Where a particle resting on the floor beside the wall moves within a step.
    const std::vector<glm::vec3> points = ringPoints(g.basin_inner_radius - texel, g.basin_inner_radius,
                                                     g.basin_floor - 0.01f, g.basin_floor + 0.01f, 20000);
    std::vector<fluid::ColliderSample> exact(points.size()), got(points.size());
    fluid::queryParallel(fluid::MeshDistance(part.view()), points, exact);
    auto worst = [&](const fluid::BakeRecipe& recipe) {
      fluid::queryParallel(bake(part, recipe), points, got);
      float e = 0.0f;
      for (std::size_t k = 0; k < points.size(); ++k)
        if (got[k].valid) e = std::max(e, std::fabs(got[k].distance - exact[k].distance));
      return e;
    };
    fluid::BakeRecipe low_cube = part.entry.recipe;
    low_cube.maps = "axes,cube@0:0.45:0:3.1";
    const float shipped = worst(part.entry.recipe), low = worst(low_cube);
    std::printf("basin floor beside the wall: largest |error| %.4f m (cube 0.25 m above the floor: %.4f m)\n", shipped,
                low);
    EXPECT_LT(shipped, texel);
    EXPECT_GT(low, 4.0f * texel);  // the check can fail: the grazing cube's error
    return;
  }
  FAIL() << "no basin in content/colliders/fountain.colliders";
}

// The statue's dish (issue 33 item 6): its floor meets the spire's steep foot and the rim's sloped
// inner face in two concave corners. The y maps see both faces at a grazing angle (the spire's foot
// is 76 degrees from level, so a vertical distance into it is about 4x its depth) or not at all (the
// rim's top covers the floor's texels beside it), and the x and z maps see the points between the
// rim's outer walls: just inside either corner every axis vote is several times the true depth, the
// depth the water was pushed out by. The shipped recipe adds LESS depth cubes round the dish above
// its floor (Kolb §4.1: views placed for a concavity), whose rays meet the floor and both faces
// steeply. Within each corner's ring, every point inside the statue within a particle radius of its
// surface must read no more than half a particle radius deeper than it is, and the cubes must not give
// any point of the rings the wrong sign beyond a texel of the surface (a texel's ray passing beside
// the spire's silhouette reads the floor behind it: points within a texel inside the spire's foot
// may read outside, as the conservative ortho maps' points within a texel outside may read inside).
TEST(FountainColliders, DishCornersReadNearTheirTrueDepth) {
  const float radius = fountainSupport() / 4.0f;
  ASSERT_GT(radius, 0.0f);
  for (const Part& part : fountainModels()) {
    if (part.entry.name != "statue") continue;
    const game::FountainGeometry g;
    std::vector<glm::vec3> points =
        ringPoints(g.spire_radius - 0.06f, g.spire_radius + 0.04f, g.dish_floor - 0.04f, g.dish_floor + 0.06f, 30000);
    const std::vector<glm::vec3> rim = ringPoints(g.dish_inner_radius - 0.04f, g.dish_inner_radius + 0.06f,
                                                  g.dish_floor - 0.04f, g.dish_floor + 0.06f, 30000);
    points.insert(points.end(), rim.begin(), rim.end());
    std::vector<fluid::ColliderSample> exact(points.size()), got(points.size());
    fluid::queryParallel(fluid::MeshDistance(part.view()), points, exact);
    struct Reading {
      std::size_t inside = 0, wrong_sign = 0;
      float deepest_over = 0.0f;  // how much deeper than it is a point inside within a radius reads, at most
    };
    auto read = [&](const fluid::BakeRecipe& recipe) {
      fluid::queryParallel(bake(part, recipe), points, got);
      Reading r;
      const float texel = 2.1f * 1.1f / static_cast<float>(recipe.resolution);  // the statue's y maps
      for (std::size_t k = 0; k < points.size(); ++k) {
        const float d = exact[k].distance;
        const bool inside = got[k].valid && got[k].distance < 0.0f;
        if (std::fabs(d) > texel && inside != (d < 0.0f)) ++r.wrong_sign;
        if (!(d < 0.0f && d > -radius)) continue;
        ++r.inside;
        if (got[k].valid) r.deepest_over = std::max(r.deepest_over, d - got[k].distance);
      }
      return r;
    };
    fluid::BakeRecipe axes = part.entry.recipe;
    axes.maps = "axes";
    const Reading shipped = read(part.entry.recipe), six = read(axes);
    std::printf("dish corners: %zu points inside within %.3f m read at most %.4f m deeper than they are "
                "(six axis maps: %.4f m); wrong sign beyond a texel: %zu (%zu)\n",
                shipped.inside, radius, shipped.deepest_over, six.deepest_over, shipped.wrong_sign, six.wrong_sign);
    ASSERT_GT(shipped.inside, 5000u);
    EXPECT_LT(shipped.deepest_over, 0.5f * radius);
    EXPECT_EQ(shipped.wrong_sign, 0u);
    EXPECT_GT(six.deepest_over, radius);  // the check can fail: the axis maps alone
    return;
  }
  FAIL() << "no statue in content/colliders/fountain.colliders";
}

// Water resting on the basin floor beside the wall, stepped by the game's SPH with the game's
// colliders (issue 18): a floor read as deep inside there threw such particles up by that depth in one
// step, the energy the pool then spent jumping at its rim. No step may push a particle out deeper than
// the game's warning depth (a particle radius, game::sphDeepPush), nor lift a resting particle by as
// much: the boundary pressure and gravity move it millimetres per step.
TEST(FountainColliders, WaterRestingBesideTheBasinWallIsNotThrownUp) {
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene).ok());
  game::SphFluidParams params;
  std::string error;
  ASSERT_TRUE(game::sphParamsFrom(*scene.effect("sph_fluid"), params, error)) << error;
  params.pump = false;  // an empty basin: only the particles placed below
  std::shared_ptr<const game::LevelColliders> level;
  ASSERT_TRUE(game::ensureFountainColliders(kContent, level, error)) << error;
  game::SphFluid f;
  const game::FountainGeometry g;
  ASSERT_TRUE(game::initSphFluid(f, params, g, level, glm::vec3(0.0f, -9.81f, 0.0f), error)) << error;
  f.world.emitters.clear();  // only the resting particles below
  f.world.sinks.clear();
  ASSERT_EQ(level->parts[1].name, "basin");
  const fluid::DepthMapCollider& basin = level->parts[1].collider;
  // 107 particles round the wall (0.17 m apart, more than the SPH support, so each rests alone), a
  // skin above the floor and 2 to 26 mm from the wall (about a texel), sliding towards
  // the wall at 0.5 m/s as the pool's bottom layer does; where the collider itself calls the start
  // inside it is skipped (the end-of-step check never leaves a particle there).
  const float skin = 0.01f * params.particle_radius;
  for (int k = 0; k < 107; ++k) {
    const float angle = 6.2831853f * (static_cast<float>(k) + 0.37f) / 107.0f;
    const float r = g.basin_inner_radius - 0.002f - 0.002f * static_cast<float>(k % 13);
    const glm::vec3 p{r * std::cos(angle), g.basin_floor + skin, r * std::sin(angle)};
    if (basin.sample(p).distance < 0.0f) continue;
    fluid::addSphParticle(f.world, p, 0.5f * glm::normalize(glm::vec3(p.x, 0.0f, p.z)));
  }
  ASSERT_GT(f.world.particles.size(), 40u);
  float worst_rise = 0.0f, worst_push = 0.0f;
  std::vector<glm::vec3> before;
  for (int step = 0; step < 120; ++step) {  // 2 s of game steps
    before = f.world.particles.position;
    ASSERT_TRUE(game::stepSphFluid(
        f, 1.0 / 60.0, [&](const fluid::SphStepStats& s) { worst_push = std::max(worst_push, s.max_push_depth); }));
    ASSERT_EQ(f.world.particles.size(), before.size());
    for (std::size_t i = 0; i < before.size(); ++i)
      worst_rise = std::max(worst_rise, f.world.particles.position[i].y - before[i].y);
  }
  std::printf("%zu particles: largest rise in a game step %.4f m, deepest push %.4f m\n", before.size(), worst_rise,
              worst_push);
  EXPECT_LT(worst_push, game::sphDeepPush(f));
  EXPECT_LT(worst_rise, game::sphDeepPush(f));
}

// Water on the dish floor running into its two concave corners (issue 33 item 6), stepped by the
// game's SPH with the game's colliders: beside the spire's foot and beside the rim, moving towards
// them at 0.5 m/s, as the jet's water spreading over the dish does. A corner read several times
// deeper than it is pushed such particles out by up to 55 mm in the tour (a particle radius is the
// warning depth, game::sphDeepPush); none may be pushed out that deep, nor reach the speed cap.
TEST(FountainColliders, WaterRunningIntoTheDishCornersIsNotThrown) {
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene).ok());
  game::SphFluidParams params;
  std::string error;
  ASSERT_TRUE(game::sphParamsFrom(*scene.effect("sph_fluid"), params, error)) << error;
  params.pump = false;  // only the particles placed below
  std::shared_ptr<const game::LevelColliders> level;
  ASSERT_TRUE(game::ensureFountainColliders(kContent, level, error)) << error;
  game::SphFluid f;
  const game::FountainGeometry g;
  ASSERT_TRUE(game::initSphFluid(f, params, g, level, glm::vec3(0.0f, -9.81f, 0.0f), error)) << error;
  f.world.emitters.clear();
  f.world.sinks.clear();
  ASSERT_EQ(level->parts[2].name, "statue");
  const fluid::DepthMapCollider& statue = level->parts[2].collider;
  // More than the SPH support apart round each corner, so each runs in alone: 8 round the spire, 2 to
  // 16 mm from its foot, heading in; 34 round the rim, 2 to 16 mm from it, heading out. Starts the
  // collider itself calls inside are skipped (the end-of-step check never leaves a particle there).
  const float skin = 0.01f * params.particle_radius;
  auto ring = [&](int count, float corner_radius, float towards) {
    for (int k = 0; k < count; ++k) {
      const float angle = 6.2831853f * (static_cast<float>(k) + 0.37f) / static_cast<float>(count);
      const float r = corner_radius - towards * (0.002f + 0.002f * static_cast<float>(k % 8));
      const glm::vec3 p{r * std::cos(angle), g.dish_floor + skin, r * std::sin(angle)};
      if (statue.sample(p).distance < 0.0f) continue;
      fluid::addSphParticle(f.world, p, towards * 0.5f * glm::normalize(glm::vec3(p.x, 0.0f, p.z)));
    }
  };
  ring(8, g.spire_radius, -1.0f);
  ring(34, g.dish_inner_radius, 1.0f);
  ASSERT_GT(f.world.particles.size(), 25u);
  float worst_push = 0.0f;
  std::size_t clamps = 0;
  for (int step = 0; step < 60; ++step) {  // 1 s of game steps
    const std::size_t count = f.world.particles.size();
    ASSERT_TRUE(game::stepSphFluid(f, 1.0 / 60.0, [&](const fluid::SphStepStats& s) {
      worst_push = std::max(worst_push, s.max_push_depth);
      clamps += s.speed_clamps;
    }));
    ASSERT_EQ(f.world.particles.size(), count);
  }
  std::printf("%zu particles in the dish's corners: deepest push %.4f m, speed clamps %zu\n", f.world.particles.size(),
              worst_push, clamps);
  EXPECT_LT(worst_push, game::sphDeepPush(f));
  EXPECT_EQ(clamps, 0u);
}

}  // namespace
