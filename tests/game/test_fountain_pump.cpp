
// Issue 33's hard cases on the game's pumped fountain (game::initSphFluid with content/scenes/
// fountain.json: the basin filled with 13,000 particles, the pump circulating them): ten blasts in
// one step in the pool, a blast on the intake, the pool thrown out by blasts and returning through
// the gutter and the pump, a crate on the intake, a crate on the nozzle. Every game step checks no
// NaN, the speed cap and the constant count of water (the store plus the pump); each case checks
// that the ids are the ones the pool was made with.
#include "archimedes_tank.hpp"
#include "engine/physics/physics_world.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/blast.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"
#include "game/world/rigid_bodies.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

const std::filesystem::path kContent = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "content";

game::SphFluid pumpedFountain() {
  game::SphFluid f;
  game::SceneConfig scene;
  EXPECT_TRUE(game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene).ok());
  game::SphFluidParams params;
  std::shared_ptr<const game::LevelColliders> colliders;
  std::string error;
  EXPECT_TRUE(game::sphParamsFrom(*scene.effect("sph_fluid"), params, error)) << error;
  EXPECT_TRUE(params.pump);
  EXPECT_TRUE(game::ensureFountainColliders(kContent, colliders, error) &&
              game::initSphFluid(f, params, game::FountainGeometry{}, colliders, game::sceneGravity(scene), error))
      << error;
  return f;
}

std::size_t water(const game::SphFluid& f) { return f.world.particles.size() + f.world.pump.size(); }

std::vector<std::uint32_t> sortedIds(const game::SphFluid& f) {
  std::vector<std::uint32_t> ids = f.world.particles.id;
  for (std::size_t k = f.world.pump.head; k < f.world.pump.held.size(); ++k) ids.push_back(f.world.pump.held[k].id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

struct Watch {
  float top_speed = 0.0f;
  bool finite = true;
  std::size_t fewest_in_pool = SIZE_MAX, most_in_pump = 0;
};

// Steps `seconds` of game steps, checking the count, finiteness and the speed cap after each.
void stepAndWatch(game::SphFluid& f, double seconds, Watch& watch) {
  const std::size_t count = water(f);
  const game::FountainGeometry g;
  for (int frame = 0; frame < static_cast<int>(std::lround(seconds * 60.0)); ++frame) {
    ASSERT_TRUE(game::stepSphFluid(f, 1.0 / 60.0)) << f.error;
    ASSERT_EQ(water(f), count) << "game step " << frame;
    for (std::size_t i = 0; i < f.world.particles.size(); ++i) {
      const glm::vec3 p = f.world.particles.position[i], v = f.world.particles.velocity[i];
      if (!std::isfinite(p.x + p.y + p.z + v.x + v.y + v.z)) watch.finite = false;
      watch.top_speed = std::max(watch.top_speed, glm::length(v));
    }
    const game::WaterWhereabouts where = game::waterWhereabouts(f, g);
    watch.fewest_in_pool = std::min(watch.fewest_in_pool, where.pool);
    watch.most_in_pump = std::max(watch.most_in_pump, where.pump);
  }
  EXPECT_TRUE(watch.finite);
  EXPECT_LE(watch.top_speed, f.world.params.max_speed * 1.0001f);
}

void blast(game::SphFluid& f, glm::vec3 centre, float impulse_at_1m) {
  fluid::Blast b;
  b.centre = centre;
  b.impulse_at_1m = impulse_at_1m;
  ASSERT_TRUE(fluid::applyBlast(f.world, b, f.world.params.max_speed).ok());
}

// A 0.6 m crate resting at `centre`: a still box collider of the SPH (the water's side of a crate).
void addStillCrate(game::SphFluid& f, glm::vec3 centre) {
  fluid::SphCollider crate;
  crate.shape = std::make_shared<fluid::BoxShape>(glm::vec3(0.3f));
  crate.pose.translation = centre;
  crate.integrate_pose = false;
  crate.material.resilience = 0.0f;
  f.world.colliders.push_back(crate);
}

TEST(FountainPump, ThePoolIsFilledAtLoad) {
  game::SphFluid f = pumpedFountain();
  const game::WaterWhereabouts where = game::waterWhereabouts(f, game::FountainGeometry{});
  std::printf("[ metric ] at load: pool %zu (level %.3f m), air %zu, ground %zu, pump %zu\n", where.pool,
              where.pool_level, where.jet_and_air, where.ground, where.pump);
  EXPECT_EQ(water(f), 13000u);
  EXPECT_EQ(where.pool + where.pump, 13000u);  // all of it in the basin or already in the pump
  EXPECT_GE(where.pool_level, 0.15f);          // issue 33: at least 15 cm above the basin floor
  // Not at rest: the basin's floor-wall corner (its baked maps' concave corner, issue 33 item 6)
  // keeps kicking particles; v_rms 0.2 m/s measured. Bounded so that a blow-up fails.
  double v2 = 0.0;
  for (const glm::vec3& v : f.world.particles.velocity) v2 += glm::dot(v, v);
  const double v_rms = std::sqrt(v2 / static_cast<double>(f.world.particles.size()));
  std::printf("[ metric ] pool v_rms at load %.3f m/s\n", v_rms);
  EXPECT_LT(v_rms, 0.5);
}

TEST(FountainPump, TenBlastsInOneStepInThePool) {
  game::SphFluid f = pumpedFountain();
  const auto ids = sortedIds(f);
  const game::FountainGeometry g;
  for (int k = 0; k < 10; ++k) {
    const float angle = 0.628f * static_cast<float>(k);
    blast(f, glm::vec3(2.0f * std::cos(angle), g.basin_floor + 0.1f, 2.0f * std::sin(angle)), 60.0f);
  }
  Watch watch;
  stepAndWatch(f, 3.0, watch);
  EXPECT_EQ(sortedIds(f), ids);
  std::printf("[ metric ] ten blasts: top speed %.1f m/s, fewest in the pool %zu, most in the pump %zu\n",
              watch.top_speed, watch.fewest_in_pool, watch.most_in_pump);
}

TEST(FountainPump, ABlastOnTheIntake) {
  game::SphFluid f = pumpedFountain();
  const auto ids = sortedIds(f);
  const game::FountainGeometry g;
  blast(f, glm::vec3(g.basin_inner_radius - 0.4f, g.basin_floor + 0.05f, 0.0f), 120.0f);
  Watch watch;
  stepAndWatch(f, 3.0, watch);
  EXPECT_EQ(sortedIds(f), ids);
}

// Issue 33 item 3: a blast costs about what calm water costs. The fountain runs 4 s (the jet up, the
// dish full), then 2 s calm, then an explosive's blast and 2 s after it; the
// SPH steps per game step are compared (a count, so the comparison is exact on any machine; the
// wall time is printed beside it). Without spray the drops the blast throws set every step.
struct BlastCost {
  double calm_steps = 0.0, blast_steps = 0.0, calm_ms = 0.0, blast_ms = 0.0;
  std::size_t most_spray = 0;
};
BlastCost blastCost(float spray_speed, glm::vec3 centre, float impulse) {
  game::SphFluid f = pumpedFountain();
  f.params.spray_speed = spray_speed;
  game::applySolverKnobs(f.params, f.world.params);
  const game::FountainGeometry g;
  BlastCost cost;
  std::size_t steps = 0;
  double ms = 0.0;
  const auto run = [&](double seconds) {
    steps = 0;
    ms = 0.0;
    const int frames = static_cast<int>(std::lround(seconds * 60.0));
    for (int frame = 0; frame < frames; ++frame) {
      EXPECT_TRUE(game::stepSphFluid(f, 1.0 / 60.0, [&](const fluid::SphStepStats& s) {
        ++steps;
        ms += s.step_ms;
        cost.most_spray = std::max(cost.most_spray, s.spray);
      })) << f.error;
    }
    return frames;
  };
  run(4.0);
  const int calm_frames = run(2.0);
  cost.calm_steps = static_cast<double>(steps) / calm_frames;
  cost.calm_ms = ms / calm_frames;
  blast(f, centre, impulse);
  const int blast_frames = run(2.0);
  cost.blast_steps = static_cast<double>(steps) / blast_frames;
  cost.blast_ms = ms / blast_frames;
  return cost;
}

TEST(FountainSpray, ABlastInTheDishCostsAboutWhatCalmWaterCosts) {
  // An explosive going off on the water in the statue's dish (content/scenes/fountain.json's impulse).
  const glm::vec3 dish(0.7f, 1.7f, 0.0f);
  const BlastCost on = blastCost(6.0f, dish, 60.0f), off = blastCost(0.0f, dish, 60.0f);
  std::printf(
      "[ metric ] SPH steps per game step, calm / 2 s after a blast: spray %.2f / %.2f (%.1f / %.1f ms), "
      "without spray %.2f / %.2f (%.1f / %.1f ms); most spray %zu\n",
      on.calm_steps, on.blast_steps, on.calm_ms, on.blast_ms, off.calm_steps, off.blast_steps, off.calm_ms,
      off.blast_ms, on.most_spray);
  EXPECT_GT(on.most_spray, 20u);
  EXPECT_LE(on.blast_steps, 1.5 * on.calm_steps);
  EXPECT_LT(on.blast_steps, off.blast_steps);
}

// Strong blasts round the basin throw much of the pool over the wall: the gutter takes it into the
// pump, and the nozzle brings it back into the basin.
TEST(FountainPump, ThePoolThrownOutReturnsThroughTheGutterAndThePump) {
  game::SphFluid f = pumpedFountain();
  const auto ids = sortedIds(f);
  const game::FountainGeometry g;
  const std::size_t pool0 = game::waterWhereabouts(f, g).pool;
  for (int k = 0; k < 6; ++k) {
    const float angle = 1.047f * static_cast<float>(k);
    blast(f, glm::vec3(1.8f * std::cos(angle), g.basin_floor, 1.8f * std::sin(angle)), 600.0f);
  }
  Watch thrown;
  stepAndWatch(f, 2.0, thrown);
  const game::WaterWhereabouts after = game::waterWhereabouts(f, g);
  Watch back;
  stepAndWatch(f, 6.0, back);
  const game::WaterWhereabouts later = game::waterWhereabouts(f, g);
  std::printf(
      "[ metric ] pool %zu at load, %zu after the blasts (pump %zu, jet and air %zu, ground %zu), %zu six seconds "
      "later (pump %zu, jet and air %zu, ground %zu, spray %zu)\n",
      pool0, after.pool, after.pump, after.jet_and_air, after.ground, later.pool, later.pump, later.jet_and_air,
      later.ground, later.spray);
  EXPECT_LT(after.pool + 1000, pool0);           // the blasts threw a good part of it out
  EXPECT_GT(after.pump, f.world.pump.capacity);  // the gutter took it past the intake's share
  EXPECT_GT(later.pool, after.pool + 500);       // and the jet brought it back (a few hundred a second)
  EXPECT_LT(later.pump, after.pump);
  EXPECT_EQ(sortedIds(f), ids);
}

// A crate (a box collider) resting on the intake's grate: the intake takes what still reaches it,
// the jet runs on what the pump holds.
TEST(FountainPump, ACrateOnTheIntake) {
  game::SphFluid f = pumpedFountain();
  const auto ids = sortedIds(f);
  const game::FountainGeometry g;
  addStillCrate(f, glm::vec3(g.basin_inner_radius - 0.4f, g.basin_floor + 0.3f, 0.0f));
  Watch watch;
  stepAndWatch(f, 3.0, watch);
  EXPECT_EQ(sortedIds(f), ids);
}

// A crate on the nozzle: the emitter places no particle inside or against it, so the pump keeps
// what the intake takes (up to its capacity) and the count stays.
TEST(FountainPump, ACrateOnTheNozzle) {
  game::SphFluid f = pumpedFountain();
  const auto ids = sortedIds(f);
  const game::FountainGeometry g;
  addStillCrate(f, g.nozzle + glm::vec3(0.0f, 0.3f, 0.0f));
  Watch watch;
  stepAndWatch(f, 3.0, watch);
  EXPECT_EQ(sortedIds(f), ids);
  EXPECT_GE(f.world.pump.size(), f.world.pump.capacity);  // the jet cannot give it back
}

}  // namespace

namespace {

// Issue 33 item 5: crates in the game's own pool (rigid_bodies + sph_fluid, coupled two-way as the
// game builds them). A 0.3 m crate of `density` dropped from 0.6 m above the basin floor (0.36 m
// above the water, spinning as the game throws it) at 2 m from the centre, stepped for `seconds`;
// from `settle_from` on, every 0.25 s: its submerged share below the pool's volume level and
// below its visible level, its centre and lowest corner above the basin floor. The means over
// those samples.
//  - volume level: the level the pool's particles fill at their rest volume d^3 over the basin's
//    floor area (game::waterWhereabouts' pool_level), raised by the crate's own part below it; as
//    in the tank test (tests/game/archimedes_tank.hpp volumeLevel), which says why a crate floats
//    against this level: SPH water settles slightly denser than rho_0 by volume, and a crate
//    feels the pressure of the water's mass.
//  - visible level: around the crate (columns 0.4-1.0 m from its centre) the highest particle
//    plus r, the median over columns.
struct Floating {
  float submerged = 0.0f;                    // share of the crate's volume below the volume level
  float submerged_visible = 0.0f;            // below the visible level
  float bottom_above_floor = 0.0f;           // m, the crate's lowest corner above the basin floor
  float centre_above_floor = 0.0f;           // m
  float level = 0.0f, visible_level = 0.0f;  // m above the basin floor
  // What holds the crate up (N, means over the samples): the SPH's coupling force on it, and the
  // film closure's push on its face points in the film (game::filmForce, as forcesToBodies adds it).
  float sph_force = 0.0f, film_force = 0.0f;
  int samples = 0;
};

// The dropped crate's edge (m): its scene's crate_size, its half extent and its volume.
constexpr float kCrateSize = 0.3f, kCrateHalf = 0.5f * kCrateSize, kCrateVolume = kCrateSize * kCrateSize * kCrateSize;

// Share of the dropped crate's volume below the plane y = level (16^3 cell centres).
float shareBelow(const engine::BodyState& crate, float level) {
  return archimedes_tank::submergedFraction(crate, level, kCrateHalf, 16);
}

float poolLevelAround(const fluid::SphWorld& sph, glm::vec3 centre, float basin_wall_top) {
  const float d = fluid::sphSpacing(sph.params), r = sph.params.particle_radius;
  std::map<std::pair<int, int>, float> tops;
  for (const glm::vec3& x : sph.particles.position) {
    const float dist = glm::length(glm::vec2(x.x - centre.x, x.z - centre.z));
    if (dist < 0.4f || dist > 1.0f || x.y > basin_wall_top) continue;
    const std::pair<int, int> cell{static_cast<int>(std::floor(x.x / d)), static_cast<int>(std::floor(x.z / d))};
    auto [it, fresh] = tops.emplace(cell, x.y);
    if (!fresh) it->second = std::max(it->second, x.y);
  }
  std::vector<float> levels;
  for (const auto& [cell, top] : tops) levels.push_back(top + r);
  if (levels.empty()) return NAN;
  std::nth_element(levels.begin(), levels.begin() + static_cast<std::ptrdiff_t>(levels.size() / 2), levels.end());
  return levels[levels.size() / 2];
}

// The crate is dropped at (x, z), 0.6 m above the floor. The water is `sph_fluid: {}` (the game's
// defaults), or `water` (a scene's own sph_fluid section) where given.
Floating crateInThePool(float density, double seconds, double settle_from, float x = 2.0f, float z = 0.0f,
                        const game::SectionConfig* water = nullptr) {
  Floating out;
  game::SceneConfig scene;
  const std::string text =
      R"({"effects": {"rigid_bodies": {"crates": 0, "throw_speed": 0.5, "crate_size": )" + std::to_string(kCrateSize) +
      R"(, "density": )" + std::to_string(density) + R"(}, "sph_fluid": {}}})";
  EXPECT_TRUE(game::parseSceneText(text, "float.json", scene).ok());
  if (water != nullptr)
    for (game::SectionConfig& effect : scene.effects)
      if (effect.name == "sph_fluid") effect = *water;
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, kContent, world, error)) << error;
  game::RigidBodies& bodies = *game::findState<game::RigidBodies>(world);
  const game::FountainGeometry g;
  // throwCrate places the crate 0.6 m + its size along the direction from the origin: 0.6 m above the floor.
  game::throwCrate(bodies, glm::vec3(x, g.basin_floor + 0.6f + 0.9f, z), glm::vec3(0.0f, -1.0f, 0.0f));
  const fluid::SphWorld& sph = game::findState<game::SphFluid>(world)->world;
  const int frames = static_cast<int>(seconds * 60.0), first = static_cast<int>(settle_from * 60.0);
  int force_frames = 0;
  for (int frame = 1; frame <= frames; ++frame) {
    game::stepWorld(world, nullptr);
    if (frame < first) continue;
    // Every frame's push on the crate (the last SPH collider, when it takes part in the coupling).
    const game::SphFluid& fluid = *game::findState<game::SphFluid>(world);
    if (fluid.coupling && !fluid.coupling->coupled.empty()) {
      out.sph_force += sph.colliders.back().force.y;
      out.film_force +=
          game::filmForce(*fluid.coupling, sph, sph.colliders.back().pose, fluid.coupling->film_scratch).force.y;
      ++force_frames;
    }
    if (frame % 15 != 0) continue;
    const engine::BodyState crate = engine::bodyState(*bodies.physics, bodies.crates.back());
    const float visible = poolLevelAround(sph, crate.position, g.basin_wall_top);
    EXPECT_TRUE(std::isfinite(visible)) << "water around the crate";
    if (!std::isfinite(visible)) return out;
    const float area = game::basinFloorArea(g);
    const float water_level = game::waterWhereabouts(*game::findState<game::SphFluid>(world), g).pool_level;
    float level = g.basin_floor + water_level;
    for (int it = 0; it < 20; ++it)
      level = g.basin_floor + water_level + kCrateVolume * shareBelow(crate, level) / area;
    float lowest = 1e30f;
    for (int k = 0; k < 8; ++k)
      lowest = std::min(
          lowest,
          (crate.rotation * (kCrateHalf * glm::vec3(k & 1 ? 1.0f : -1.0f, k & 2 ? 1.0f : -1.0f, k & 4 ? 1.0f : -1.0f)) +
           crate.position)
              .y);
    out.submerged += shareBelow(crate, level);
    out.submerged_visible += shareBelow(crate, visible);
    out.bottom_above_floor += lowest - g.basin_floor;
    out.centre_above_floor += crate.position.y - g.basin_floor;
    out.level += level - g.basin_floor;
    out.visible_level += visible - g.basin_floor;
    ++out.samples;
  }
  EXPECT_EQ(world.nonfinite_state, "");
  EXPECT_GT(out.samples, 0);
  if (out.samples == 0) return out;
  const float n = static_cast<float>(out.samples);
  out.submerged /= n;
  out.sph_force /= static_cast<float>(std::max(force_frames, 1));
  out.film_force /= static_cast<float>(std::max(force_frames, 1));
  out.submerged_visible /= n;
  out.visible_level /= n;
  out.bottom_above_floor /= n;
  out.centre_above_floor /= n;
  out.level /= n;
  return out;
}

void printFloating(float density, const Floating& f) {
  std::printf(
      "[ metric ] %.0f kg/m^3 crate in the pool (means over %d samples): %.3f submerged below the volume level "
      "%.3f m (%.3f below the visible %.3f m; Archimedes %.3f), centre %.3f m and lowest corner %.3f m above "
      "the floor; held up by the SPH %.1f N and the film %.1f N (weight %.1f N)\n",
      density, f.samples, f.submerged, f.level, f.submerged_visible, f.visible_level, std::min(1.0f, density / 1000.0f),
      f.centre_above_floor, f.bottom_above_floor, f.sph_force, f.film_force, density * kCrateVolume * 9.81f);
}

// content/scenes/fountain.json's own water (its sph_fluid section: one 16.7 ms DFSPH step a frame at
// cfl 0.9, tolerance 0.005, spray_speed 4): the water the game's fountain plays.
game::SectionConfig fountainSceneWater() {
  game::SceneConfig fountain;
  EXPECT_TRUE(game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), fountain).ok());
  const game::SectionConfig* water = fountain.effect("sph_fluid");
  EXPECT_NE(water, nullptr);
  return water != nullptr ? *water : game::SectionConfig{};
}

// The 500 kg/m^3 crate dropped at five spots chosen around the basin, each a mean over 4-8 s: where
// it lands moves its draft (it bobs and tilts in water three layers deep).
const glm::vec2 kDropSpots[] = {{2.0f, 0.0f}, {1.8f, 0.0f}, {2.2f, 0.0f}, {0.0f, 2.0f}, {-1.4f, -1.4f}};

struct DropMeans {
  float below_volume_level = 0.0f, below_visible_level = 0.0f;
};

DropMeans dropHalfDensityCrates(const game::SectionConfig* water, const char* label) {
  DropMeans means;
  const float share = 1.0f / static_cast<float>(std::size(kDropSpots));
  for (const glm::vec2 spot : kDropSpots) {
    const Floating f = crateInThePool(500.0f, 8.0, 4.0, spot.x, spot.y, water);
    std::printf("[ metric ] %s, dropped at x %.1f z %.1f: ", label, spot.x, spot.y);
    printFloating(500.0f, f);
    EXPECT_GT(f.centre_above_floor, 0.2f) << "lifted off the floor (lying on it, the centre is at 0.15 m), dropped at "
                                          << spot.x << ", " << spot.y;
    means.below_volume_level += f.submerged * share;
    means.below_visible_level += f.submerged_visible * share;
  }
  std::printf("[ metric ] %s, 500 kg/m^3 crate, mean of the drops: %.3f submerged below the volume level, %.3f below "
              "the visible level (Archimedes 0.5)\n",
              label, means.below_volume_level, means.below_visible_level);
  return means;
}

// The pool is about three particle layers deep (level ~0.24 m at d = 8 cm), so the dropped 500
// crate reaches the floor on landing, and at its Archimedes draft its bottom lies 8.6 cm, about
// one spacing, above the floor: the water under it is a film the SPH does not resolve (one layer
// at most, squeezed out at one step a frame). The film closure of game/world/body_fluid_coupling
// presses every face point within d of the floor, facing it, with the surrounding water's
// pressure, and the SPH leaves the squeezed particles' push out of the crate's force
// (SphCollider::film_gap), so the film is counted once. Issue 33's bar, half submerged within
// 15 % (0.425-0.575), is asserted on the mean of the drops, below the pool's volume level and
// below the visible level around the crate.
TEST(FountainFloating, AHalfDensityCrateFloatsHalfSubmerged) {
  const game::SectionConfig water = fountainSceneWater();
  const DropMeans means = dropHalfDensityCrates(&water, "fountain scene's water");
  EXPECT_GT(means.below_volume_level, 0.425f) << "half submerged, within 15 %";
  EXPECT_LT(means.below_volume_level, 0.575f);
  EXPECT_GT(means.below_visible_level, 0.425f);
  EXPECT_LT(means.below_visible_level, 0.575f);
}

TEST(FountainFloating, ADenseCrateSinksToTheBasinFloor) {
  const game::SectionConfig water = fountainSceneWater();
  const Floating f = crateInThePool(2000.0f, 6.0, 4.0, 2.0f, 0.0f, &water);
  printFloating(2000.0f, f);
  EXPECT_LT(f.bottom_above_floor, 0.03f);
  EXPECT_LT(f.centre_above_floor, 0.17f) << "lying on the floor";
}

// The same drops in the game's default water (`sph_fluid: {}`: DFSPH steps of at most 5 ms, cfl
// 0.4). That water stands looser at its top than the fountain's (the top layer about 5 % under
// the rest density), so near +x, where the jet's water comes down, its visible surface lies 2-3 cm
// above the volume level the particle count gives: the crate floats in the surface it meets. Issue
// 33's bar is asserted below the visible level; below the volume level the crates float higher
// than the bar allows (docs/engine.md's third pool table), and only a looser bound, within 25 %,
// is asserted there, to catch drift.
TEST(FountainFloating, InTheGameDefaultWaterAgainstItsVisibleSurface) {
  const DropMeans means = dropHalfDensityCrates(nullptr, "default water");
  EXPECT_GT(means.below_visible_level, 0.425f) << "half submerged, within 15 %";
  EXPECT_LT(means.below_visible_level, 0.575f);
  EXPECT_GT(means.below_volume_level, 0.375f) << "below the volume level, within 25 %";
  EXPECT_LT(means.below_volume_level, 0.625f);
}

// The figures of docs/engine.md's second pool table (about 15 s; run with --gtest_also_run_disabled_tests):
// crates of 250, 350, 500 and 700 kg/m^3 dropped into the pool, means over 4-8 s. Asserts only
// that a lighter crate floats higher.
TEST(FountainFloating, DISABLED_DensitySweep) {
  float previous = 0.0f;
  const game::SectionConfig water = fountainSceneWater();
  for (const float density : {250.0f, 350.0f, 500.0f, 700.0f}) {
    const Floating f = crateInThePool(density, 8.0, 4.0, 2.0f, 0.0f, &water);
    printFloating(density, f);
    EXPECT_GT(f.submerged, previous) << density << " kg/m^3 floats deeper than the lighter crate before it";
    previous = f.submerged;
  }
}

}  // namespace
