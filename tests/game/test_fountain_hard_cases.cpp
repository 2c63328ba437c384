// Hard cases of issue 18 on the fountain's real SPH and its baked depth-map colliders
// (game::initSphFluid: content/scenes/fountain.json, content/colliders): water thrown at 100 m/s
// against the basin wall and the statue's thin dish rim, and a crate dropped into the jet at
// 30 m/s. (The same cases on analytic walls: tests/sph/test_blast.cpp; the nozzle and ten charges
// in one step in the game: tests/game/test_explosives.cpp.) Each step checks no NaN, bounded speed,
// an accounted particle count, no particle left inside a level collider and none through a wall.
#include "fluid/collide/collide.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/blast.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <unordered_map>

namespace {

const std::filesystem::path kContent = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "content";

// The fountain's SPH world with its jet running for `seconds` (the basin and the dish hold water).
game::SphFluid runningFountain(double seconds) {
  game::SphFluid f;
  game::SceneConfig scene;
  game::SceneStatus st = game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene);
  EXPECT_TRUE(st.ok()) << st.error;
  const game::SectionConfig* section = scene.effect("sph_fluid");
  EXPECT_NE(section, nullptr);
  if (section == nullptr) return f;
  game::SphFluidParams params;
  std::shared_ptr<const game::LevelColliders> colliders;
  std::string error;
  EXPECT_TRUE(game::sphParamsFrom(*section, params, error) && game::ensureFountainColliders(kContent, colliders, error) &&
              game::initSphFluid(f, params, game::FountainGeometry{}, colliders, game::sceneGravity(scene), error))
      << error;
  for (int frame = 0; frame < static_cast<int>(seconds * 60.0); ++frame)
    EXPECT_TRUE(game::stepSphFluid(f, 1.0 / 60.0)) << f.error;
  return f;
}

struct Watch {
  std::size_t steps = 0, emitted = 0, removed = 0, nonfinite = 0;
  float top_speed = 0.0f;
  float deepest = 0.0f;            // deepest end-of-step position inside a level collider (m)
  std::size_t through_walls = 0;   // one-step crossings of the basin wall or the dish rim
  bool finite = true;
};

float radial(glm::vec3 p) { return std::sqrt(p.x * p.x + p.z * p.z); }

// Steps the world one SPH step at a time for `seconds`, watching every particle by id.
Watch stepAndWatch(game::SphFluid& f, double seconds, std::size_t level_parts) {
  fluid::SphWorld& w = f.world;
  const game::FountainGeometry g;
  const float reach = fluid::sphSpacing(w.params);  // at most ~cfl d per step: a one-step crossing stays below
  Watch watch;
  std::unordered_map<std::uint32_t, glm::vec3> before;
  const double end = w.time + seconds;
  while (w.time < end) {
    before.clear();
    for (std::size_t i = 0; i < w.particles.size(); ++i) before[w.particles.id[i]] = w.particles.position[i];
    const std::size_t count = w.particles.size();
    fluid::SphStepStats stats;
    const fluid::SphStatus st = fluid::stepSph(w, 0.0f, &stats);
    EXPECT_TRUE(st.ok()) << st.error;
    if (!st.ok()) break;
    ++watch.steps;
    watch.emitted += stats.emitted;
    watch.removed += stats.removed;
    watch.nonfinite += stats.nonfinite;
    EXPECT_EQ(w.particles.size(), count + stats.emitted - stats.removed);
    EXPECT_LE(w.particles.size(), w.params.max_particles);
    for (std::size_t i = 0; i < w.particles.size(); ++i) {
      const glm::vec3 p = w.particles.position[i], v = w.particles.velocity[i];
      if (!std::isfinite(p.x + p.y + p.z + v.x + v.y + v.z)) watch.finite = false;
      watch.top_speed = std::max(watch.top_speed, glm::length(v));
      for (std::size_t c = 0; c < level_parts; ++c) {
        fluid::ColliderSample s;
        w.colliders[c].shape->query({&p, 1}, {&s, 1});
        if (s.valid && s.distance < 0.0f) watch.deepest = std::max(watch.deepest, -s.distance);
      }
      const auto it = before.find(w.particles.id[i]);
      if (it == before.end()) continue;
      const glm::vec3 a = it->second;
      // Through the basin wall: from the cavity to beyond the outer radius, staying below the
      // wall top all the way (a particle going over it is legal).
      const bool low_basin = a.y < g.basin_wall_top - reach && p.y < g.basin_wall_top - reach;
      if (low_basin && radial(a) < g.basin_inner_radius && radial(p) > g.basin_outer_radius) ++watch.through_walls;
      // Through the dish rim: from the dish (above its floor) to beyond its radius below the rim top.
      const bool low_dish = a.y > g.dish_floor && a.y < g.dish_rim_top - reach && p.y > g.dish_bottom &&
                            p.y < g.dish_rim_top - reach;
      if (low_dish && radial(a) < g.dish_inner_radius && radial(p) > g.dish_radius) ++watch.through_walls;
    }
  }
  return watch;
}

void expectSane(const Watch& w, float speed_bound, float max_depth) {
  EXPECT_TRUE(w.finite);
  EXPECT_EQ(w.nonfinite, 0u);
  EXPECT_LE(w.top_speed, speed_bound);
  EXPECT_LE(w.deepest, max_depth) << "a particle ended a step that deep inside a level collider";
  EXPECT_EQ(w.through_walls, 0u);
}

// End-of-step tolerance inside a baked collider: the §3.3.2 push-out leaves a particle skin
// outside the sampled texel's surface, and the neighbouring texel's surface can stand up to a
// quantisation step higher (a quarter particle radius covers both with margin).
float bakedTolerance(const fluid::SphWorld& w) { return 0.25f * w.params.particle_radius; }

TEST(FountainHardCases, WaterThrownAt100MetresPerSecondStaysOutOfTheBasinWallAndTheDishRim) {
  game::SphFluid f = runningFountain(2.0);
  fluid::SphWorld& w = f.world;
  const std::size_t parts = w.colliders.size();
  const game::FountainGeometry g;
  // The game clamps speeds at 3 jet_speed + 5 m/s (game/world/sph_fluid.cpp): off here, so the
  // 100 m/s water reaches the walls and the bound below is the solver's, not the clamp's.
  w.params.max_speed = 0.0f;
  // One charge in the basin water against the +x wall, one in the dish against its rim.
  std::size_t pushed = 0;
  for (const glm::vec3 centre : {glm::vec3(g.basin_inner_radius - 0.5f, g.basin_floor + 0.05f, 0.0f),
                                 glm::vec3(g.dish_inner_radius - 0.3f, g.dish_floor + 0.03f, 0.0f)}) {
    fluid::Blast blast;
    blast.centre = centre;
    blast.impulse_at_1m = 400.0f;
    blast.core_radius = 0.1f;
    blast.reach = 1.0f;
    fluid::SphBlastStats stats;
    ASSERT_TRUE(fluid::applyBlast(w, blast, 100.0f, &stats).ok());
    EXPECT_NEAR(stats.max_speed_change, 100.0f, 0.01f) << "the 100 m/s case is exercised";
    pushed += stats.particles;
  }
  EXPECT_GT(pushed, 100u);
  const Watch watch = stepAndWatch(f, 0.1, parts);
  std::printf("[ metric ] 100 m/s on the fountain: %zu steps in 0.1 s, top speed %.1f m/s, deepest %.2e m, %zu drained\n",
              watch.steps, static_cast<double>(watch.top_speed), static_cast<double>(watch.deepest), watch.removed);
  expectSane(watch, 110.0f, bakedTolerance(w));
}

TEST(FountainHardCases, ACrateDroppedIntoTheJetAt30MetresPerSecond) {
  game::SphFluid f = runningFountain(1.0);
  fluid::SphWorld& w = f.world;
  const std::size_t parts = w.colliders.size();
  const game::FountainGeometry g;
  // A 0.5 m crate 1.4 m above the nozzle falling at 30 m/s through the jet: in 0.04 s it reaches
  // the nozzle. The SPH world moves it by its velocity (no rigid body stops it here).
  fluid::SphCollider crate;
  crate.shape = std::make_shared<fluid::BoxShape>(glm::vec3(0.25f));
  crate.pose.translation = g.nozzle + glm::vec3(0.0f, 1.4f, 0.0f);
  crate.pose.linear_velocity = glm::vec3(0.0f, -30.0f, 0.0f);
  crate.integrate_pose = true;
  w.colliders.push_back(crate);
  std::size_t jet = 0;  // particles in the jet's column above the nozzle, in the crate's path
  for (const glm::vec3& p : w.particles.position) jet += radial(p) < 0.25f && p.y > g.nozzle.y && p.y < g.nozzle.y + 1.2f;
  EXPECT_GT(jet, 20u) << "the jet is in the crate's path";
  const Watch watch = stepAndWatch(f, 0.04, parts);
  std::printf("[ metric ] crate at 30 m/s into the jet: %zu steps in 0.04 s, top speed %.1f m/s, deepest %.2e m\n",
              watch.steps, static_cast<double>(watch.top_speed), static_cast<double>(watch.deepest));
  // The crate hits the water at 30 m/s: the reaction throws it at up to about twice that.
  expectSane(watch, 2.0f * 30.0f + f.params.jet_speed, bakedTolerance(w));
  EXPECT_GT(std::fabs(w.colliders.back().force.y), 0.0f) << "the water pushed back on the crate";
}

}  // namespace
