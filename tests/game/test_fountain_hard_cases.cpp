// Hard cases of issue 18 on the fountain's real SPH and its baked depth-map colliders
// (game::initSphFluid: content/scenes/fountain.json, content/colliders): water thrown at 100 m/s
// against the basin wall and the statue's thin dish rim, a crate dropped into the jet at 30 m/s, and
// the basin full to the brim and overflowing for 60 s (a soak-length case: tests/game/CMakeLists.txt
// labels it `soak`). (The same cases on analytic walls: tests/sph/test_blast.cpp; the nozzle and ten
// charges in one step in the game: tests/game/test_explosives.cpp.) Each step checks no NaN, bounded
// speed, an accounted particle count, no particle left inside a level collider and none through a wall.
#include "fluid/collide/collide.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/blast.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

namespace {

const std::filesystem::path kContent = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "content";

// The fountain's SPH world as the game builds it, with `tune` (when given) applied to the scene's
// parameters first.
game::SphFluid fountain(const std::function<void(game::SphFluidParams&)>& tune = {}) {
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
  EXPECT_TRUE(game::sphParamsFrom(*section, params, error)) << error;
  // These cases follow particles by id from the nozzle through sinks (ids made in order, never
  // reused) in the jet-fed fountain of 2,500: the pump off. The pump's own cases (constant count,
  // ids kept, a gutter's return, thread-count invariance) are tests/sph/test_pump.cpp.
  params.pump = false;
  params.max_particles = 2500;
  if (tune) tune(params);
  EXPECT_TRUE(game::ensureFountainColliders(kContent, colliders, error) &&
              game::initSphFluid(f, params, game::FountainGeometry{}, colliders, game::sceneGravity(scene), error))
      << error;
  return f;
}

// The fountain's SPH world with its jet running for `seconds` (the basin and the dish hold water).
game::SphFluid runningFountain(double seconds) {
  game::SphFluid f = fountain();
  for (int frame = 0; frame < static_cast<int>(seconds * 60.0); ++frame)
    EXPECT_TRUE(game::stepSphFluid(f, 1.0 / 60.0)) << f.error;
  return f;
}

struct Watch {
  std::size_t steps = 0, emitted = 0, removed = 0, nonfinite = 0;
  float top_speed = 0.0f;
  float deepest = 0.0f;           // deepest end-of-step position inside a level collider (m)
  std::size_t through_walls = 0;  // one-step crossings of the basin wall or the dish rim
  // Removed by a sink in a step that began over the basin's cavity: through its floor, where the floor
  // drains are off (they are sinks in the floor).
  std::size_t leaked = 0;
  std::size_t fewest = SIZE_MAX, most = 0;  // particle count after a step
  bool finite = true;                       // every position, velocity and density after every step
};

float radial(glm::vec3 p) { return std::sqrt(p.x * p.x + p.z * p.z); }

constexpr float kGone = 1e30f;  // position slot of an id not in the world at a step's start

// Steps the world one SPH step at a time for `seconds`, watching every particle by id.
Watch stepAndWatch(game::SphFluid& f, double seconds, std::size_t level_parts) {
  fluid::SphWorld& w = f.world;
  const game::FountainGeometry g;
  const float reach = fluid::sphSpacing(w.params);  // at most ~cfl d per step: a one-step crossing stays below
  Watch watch;
  // Positions at the start of a step by particle id (ids are handed out in order and never reused,
  // so a particle with an id below the step's starting next_id was there before the step).
  std::vector<glm::vec3> before;
  std::vector<char> present;  // by id: there after the step
  std::vector<fluid::ColliderSample> samples;
  const double end = w.time + seconds;
  while (w.time < end) {
    before.assign(w.next_id, glm::vec3(kGone));
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
    EXPECT_EQ(w.particles.density.size(), w.particles.size());
    // The sinks lie outside the basin and under the ground (up to a spacing below the basin floor):
    // water over the cavity reaches them only over the wall, never within one step, unless a
    // collision threw it through the floor.
    present.assign(w.next_id, 0);
    for (std::size_t i = 0; i < w.particles.size(); ++i) present[w.particles.id[i]] = 1;
    for (std::size_t id = 0; id < before.size(); ++id)
      if (!present[id] && before[id] != glm::vec3(kGone) && radial(before[id]) < g.basin_inner_radius &&
          before[id].y > g.basin_floor - reach)
        ++watch.leaked;
    watch.fewest = std::min(watch.fewest, w.particles.size());
    watch.most = std::max(watch.most, w.particles.size());
    // The level's parts are static: collider space is world space. One batch query per part.
    samples.resize(w.particles.size());
    for (std::size_t c = 0; c < level_parts; ++c) {
      w.colliders[c].shape->query(w.particles.position, samples);
      for (const fluid::ColliderSample& s : samples)
        if (s.valid && s.distance < 0.0f) watch.deepest = std::max(watch.deepest, -s.distance);
    }
    for (std::size_t i = 0; i < w.particles.size(); ++i) {
      const glm::vec3 p = w.particles.position[i], v = w.particles.velocity[i];
      if (!std::isfinite(p.x + p.y + p.z + v.x + v.y + v.z + w.particles.density[i])) watch.finite = false;
      watch.top_speed = std::max(watch.top_speed, glm::length(v));
      if (w.particles.id[i] >= before.size()) continue;  // born in this step
      const glm::vec3 a = before[w.particles.id[i]];
      // Through the basin wall: from the cavity to beyond the outer radius, staying below the
      // wall top all the way (a particle going over it is legal).
      const bool low_basin = a.y < g.basin_wall_top - reach && p.y < g.basin_wall_top - reach;
      if (low_basin && radial(a) < g.basin_inner_radius && radial(p) > g.basin_outer_radius) ++watch.through_walls;
      // Through the dish rim: from the dish (above its floor) to beyond its radius below the rim top.
      const bool low_dish =
          a.y > g.dish_floor && a.y < g.dish_rim_top - reach && p.y > g.dish_bottom && p.y < g.dish_rim_top - reach;
      if (low_dish && radial(a) < g.dish_inner_radius && radial(p) > g.dish_radius) ++watch.through_walls;
    }
  }
  return watch;
}

// Two watched runs as one (b after a).
Watch merged(const Watch& a, const Watch& b) {
  Watch m;
  m.steps = a.steps + b.steps;
  m.emitted = a.emitted + b.emitted;
  m.removed = a.removed + b.removed;
  m.nonfinite = a.nonfinite + b.nonfinite;
  m.top_speed = std::max(a.top_speed, b.top_speed);
  m.deepest = std::max(a.deepest, b.deepest);
  m.through_walls = a.through_walls + b.through_walls;
  m.leaked = a.leaked + b.leaked;
  m.fewest = std::min(a.fewest, b.fewest);
  m.most = std::max(a.most, b.most);
  m.finite = a.finite && b.finite;
  return m;
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
  // The jet's drops fall into the dish (about a second aloft), and what overflows it spreads over the basin
  // floor: by 6 s water lies near both charges.
  game::SphFluid f = runningFountain(6.0);
  fluid::SphWorld& w = f.world;
  const std::size_t parts = w.colliders.size();
  const game::FountainGeometry g;
  // The game clamps speeds at 3 jet_speed + 5 m/s (game/world/sph_fluid.cpp): off here, so the
  // 100 m/s water reaches the walls and the bound below is the solver's, not the clamp's.
  w.params.max_speed = 0.0f;
  // One charge in the basin water against the +x wall, one in the dish against its rim.
  std::size_t pushed = 0;
  // Each charge goes off at the water particle nearest the aimed point, so its core holds water
  // (the film's particles move from run to run of the jet).
  for (const glm::vec3 aim : {glm::vec3(g.basin_inner_radius - 0.5f, g.basin_floor + 0.05f, 0.0f),
                              glm::vec3(g.dish_inner_radius - 0.3f, g.dish_floor + 0.03f, 0.0f)}) {
    glm::vec3 centre = aim;
    float nearest = 1e30f;
    for (const glm::vec3& x : w.particles.position)
      if (glm::length(x - aim) < nearest) {
        nearest = glm::length(x - aim);
        centre = x;
      }
    ASSERT_LT(nearest, 0.6f) << "no water near the charge at (" << aim.x << ", " << aim.y << ", " << aim.z << "): "
                             << w.particles.size() << " particles, " << w.particles.spray_count << " of them spray";
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
  std::printf(
      "[ metric ] 100 m/s on the fountain: %zu steps in 0.1 s, top speed %.1f m/s, deepest %.2e m, %zu drained\n",
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
  for (const glm::vec3& p : w.particles.position)
    jet += radial(p) < 0.25f && p.y > g.nozzle.y && p.y < g.nozzle.y + 1.2f;
  EXPECT_GT(jet, 20u) << "the jet is in the crate's path";
  const Watch watch = stepAndWatch(f, 0.04, parts);
  std::printf("[ metric ] crate at 30 m/s into the jet: %zu steps in 0.04 s, top speed %.1f m/s, deepest %.2e m\n",
              watch.steps, static_cast<double>(watch.top_speed), static_cast<double>(watch.deepest));
  // The crate hits the water at 30 m/s: the reaction throws it at up to about twice that.
  expectSane(watch, 2.0f * 30.0f + f.params.jet_speed, bakedTolerance(w));
  EXPECT_GT(std::fabs(w.colliders.back().force.y), 0.0f) << "the water pushed back on the crate";
}

// Fills the basin's cavity to the brim with water at rest: a cubic lattice of spacing d (as
// fluid::addSphBlock lays one) whose top layer sits a radius below the wall top, keeping every
// particle at least a radius from each level part (floor, wall, plinth, column: the distance the
// boundary holds resting water at). Returns the count added.
std::size_t fillBasinToTheBrim(fluid::SphWorld& w, std::size_t level_parts) {
  const game::FountainGeometry g;
  const float r = w.params.particle_radius, d = fluid::sphSpacing(w.params);
  const int layers = static_cast<int>((g.basin_wall_top - g.basin_floor - 2.0f * r) / d + 1e-3f) + 1;
  const int across = static_cast<int>(2.0f * (g.basin_inner_radius - r) / d + 1e-3f) + 1;
  std::vector<glm::vec3> lattice;
  for (int k = 0; k < layers; ++k)
    for (int i = 0; i < across; ++i)
      for (int j = 0; j < across; ++j) {
        const glm::vec3 p(-g.basin_inner_radius + r + static_cast<float>(i) * d,
                          g.basin_floor + r + static_cast<float>(k) * d,
                          -g.basin_inner_radius + r + static_cast<float>(j) * d);
        if (radial(p) <= g.basin_inner_radius - r) lattice.push_back(p);
      }
  std::vector<bool> clear(lattice.size(), true);
  std::vector<fluid::ColliderSample> samples(lattice.size());
  for (std::size_t c = 0; c < level_parts; ++c) {
    w.colliders[c].shape->query(lattice, samples);
    for (std::size_t i = 0; i < lattice.size(); ++i)
      if (samples[i].valid && samples[i].distance < r) clear[i] = false;
  }
  std::size_t added = 0;
  for (std::size_t i = 0; i < lattice.size(); ++i) added += clear[i] && fluid::addSphParticle(w, lattice[i]);
  return added;
}

// Volume (m^3) of the water in the basin: the particles over its cavity from the floor up to one
// spacing above the wall top (the sheet spilling over the brim), at rest volume m / rho_0 each.
double basinVolume(const fluid::SphWorld& w) {
  const game::FountainGeometry g;
  const float d = fluid::sphSpacing(w.params);
  std::size_t in = 0;
  for (const glm::vec3& p : w.particles.position)
    in += radial(p) < g.basin_inner_radius && p.y > g.basin_floor - d && p.y < g.basin_wall_top + d;
  return static_cast<double>(in) * fluid::sphParticleMass(w.params) / w.params.rest_density;
}

TEST(FountainHardCases, BasinFilledToTheBrimAndOverflowingFor60Seconds) {
  // The game's jet cannot fill the basin in any reachable time (its whole budget covers the basin
  // floor a few centimetres deep), so the basin starts full to the brim. The floor drains would
  // empty a brimful basin within seconds (the hydrostatic head pushes water into them far faster
  // than the nozzle, whose rate is clamped by its layer spacing, can emit), so they are off: the
  // basin stays full and overflows its wall, and the sink under the ground (game/world/sph_fluid.cpp,
  // "whatever escapes the basin") takes the overflow, as the box-basin case does with its drains
  // outside the walls (tests/sph/test_blast.cpp).
  game::SphFluid f = fountain([](game::SphFluidParams& p) {
    p.max_particles = 40000;  // room for the fill (asserted); the budget is set just above it below
  });
  fluid::SphWorld& w = f.world;
  const std::size_t parts = w.colliders.size();
  const game::FountainGeometry g;
  const std::size_t filled = fillBasinToTheBrim(w, parts);
  // The budget: the full basin plus room for the water the jet adds before the level stands a layer
  // above the wall top (the basin's area times a spacing, in particles) and for the dish and the jet
  // in flight, so the jet keeps running and the basin really overflows. (With room for the dish alone
  // the budget binds a centimetre below the spill, the jet stops and nothing leaves.)
  const double pi = 3.14159265358979;
  const double layer_volume = pi * g.basin_inner_radius * g.basin_inner_radius * fluid::sphSpacing(w.params);
  const double particle_volume = fluid::sphParticleMass(w.params) / w.params.rest_density;
  const std::size_t room = static_cast<std::size_t>(2.0 * layer_volume / particle_volume);
  ASSERT_GT(static_cast<float>(room), f.params.rate);
  w.params.max_particles = filled + room;
  fluid::reserveSph(w, w.params.max_particles);
  // The fill holds the cavity's volume (the cylinder up to the wall top less the plinth and the
  // column) within 15 %: the lattice keeps a radius off the floor, the wall and the statue.
  const double cavity = pi * (g.basin_inner_radius * g.basin_inner_radius * (g.basin_wall_top - g.basin_floor) -
                              g.plinth_radius * g.plinth_radius * (g.plinth_top - g.basin_floor) -
                              g.column_radius * g.column_radius * (g.basin_wall_top - g.plinth_top));
  const double brim = basinVolume(w);
  ASSERT_LT(filled, 40000u);
  ASSERT_NEAR(brim, cavity, 0.15 * cavity) << "the basin's cavity is not full";

  const Watch first = stepAndWatch(f, 1.0, parts);  // the jet's full flow, below the budget
  const double full_rate = static_cast<double>(first.emitted) / w.time;
  const Watch filling = stepAndWatch(f, 30.0 - w.time, parts);
  const double at_30 = basinVolume(w);
  const Watch overflowing = stepAndWatch(f, 60.0 - w.time, parts);
  const double at_60 = basinVolume(w);
  const Watch all = merged(merged(first, filling), overflowing);
  const std::size_t budget = w.params.max_particles;
  std::printf(
      "[ metric ] overflow 60 s on the fountain: %zu steps, %zu filled + %zu emitted - %zu drained (%zu in the "
      "last 30 s, %zu through the floor), count %zu..%zu over the last 30 s (budget %zu), jet %.0f/s at full flow; "
      "top speed %.1f m/s, "
      "deepest %.2e m; water in the basin %.3f m^3 at the brim, %.3f at 30 s, %.3f at 60 s (drift 30 -> 60 s "
      "%+.2f %%)\n",
      all.steps, filled, all.emitted, all.removed, overflowing.removed, all.leaked, overflowing.fewest,
      overflowing.most, budget, full_rate, static_cast<double>(all.top_speed), static_cast<double>(all.deepest), brim,
      at_30, at_60, 100.0 * (at_60 - at_30) / at_30);

  // No particle faster than the jet's water falling from the nozzle to the ground (energy: v^2 =
  // jet^2 + 2 g h), with half again for the pressure kicks where the jet lands; the game's speed
  // cap (3 jet + 5 m/s) is above this bound, so the cap is not what holds it.
  const float fall =
      std::sqrt(f.params.jet_speed * f.params.jet_speed + 2.0f * glm::length(w.params.gravity) * g.nozzle.y);
  ASSERT_LT(1.5f * fall, w.params.max_speed);
  expectSane(all, 1.5f * fall, bakedTolerance(w));
  EXPECT_EQ(w.particles.size(), filled + all.emitted - all.removed);
  EXPECT_LE(all.most, budget);
  // The overflow starts before 30 s and keeps running into the sink beside the basin: over the last
  // half minute at least a quarter of the jet's full flow leaves over the wall, none through the floor.
  EXPECT_EQ(all.leaked, 0u) << "particles thrown through the basin floor into the sink under it";
  EXPECT_GT(filling.removed, 0u) << "no overflow within 30 s";
  EXPECT_GT(static_cast<double>(overflowing.removed), 0.25 * full_rate * 30.0);
  // The overflow pins the level: it neither drains nor piles up over the last half minute (within
  // half a particle layer of the basin's area), and the head that carries the jet's flow over the
  // wall stays under two layers above the brim.
  EXPECT_LT(std::abs(at_60 - at_30), 0.5 * layer_volume);
  for (const double level : {at_30, at_60}) {
    EXPECT_GT(level, brim - 0.5 * layer_volume) << "the basin drained";
    EXPECT_LT(level, brim + 2.0 * layer_volume) << "the water piles up over the brim";
  }
}

}  // namespace
