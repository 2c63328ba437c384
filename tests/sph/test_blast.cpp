// Blasts on the fluid (fluid/sph/blast.hpp) in a fountain-like basin: a square basin with thin
// solid walls (6 mm, under a third of the particle spacing) standing on the floor of a closed
// box, drains on the floor around it. The hard cases of issue 18: a blast centred on the nozzle,
// ten blasts in one step, a blast throwing water at 100 m/s against the walls, and the basin
// overflowing for 60 s. Each checks no NaN, bounded speed and an accounted particle count; the
// wall cases also check that no particle ends a step inside a collider or crosses a wall below
// its rim.
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/blast.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <span>

namespace {

using namespace fluid;

struct Basin {
  SphScene scene;
  float inner = 0.15f;         // half width of the water inside the walls (m)
  float wall = 0.006f;         // wall thickness (m)
  float rim = 0.12f;           // wall height (m)
  std::size_t first_wall = 0;  // colliders [first_wall, first_wall + 4) are the basin walls
};

// The basin with water filled to `water_height`, particle radius r, on the floor of a closed box.
Basin makeBasin(float r, float water_height, float rim, float inner = 0.15f) {
  Basin b;
  b.rim = rim;
  b.inner = inner;
  SphScene& s = b.scene;
  SphParams& p = s.world.params;
  p.particle_radius = r;
  p.max_particles = 4000;
  const CollisionMaterial material;
  s.box_min = glm::vec3(-0.6f, 0.0f, -0.6f);
  s.box_max = glm::vec3(0.6f, 0.8f, 0.6f);
  p.domain_min = s.box_min - glm::vec3(0.1f);
  p.domain_max = s.box_max + glm::vec3(0.1f);
  addSphContainer(s, s.box_min, s.box_max, material);
  b.first_wall = s.world.colliders.size();
  for (int axis : {0, 2})
    for (float side : {-1.0f, 1.0f}) {
      glm::vec3 half(b.inner + b.wall, 0.5f * rim, b.inner + b.wall);
      half[axis] = 0.5f * b.wall;
      auto shape = std::make_shared<BoxShape>(half);
      s.shapes.push_back(shape);
      SphCollider c;
      c.shape = shape;
      c.material = material;
      c.integrate_pose = false;
      c.lipschitz_distance = true;
      c.pose.translation = glm::vec3(0.0f, 0.5f * rim, 0.0f);
      c.pose.translation[axis] = side * (b.inner + 0.5f * b.wall);
      s.world.colliders.push_back(c);
    }
  // Drains on the floor around the basin (a ring of four boxes, 4 cm clear of the walls).
  const float clear = b.inner + b.wall + 0.04f, far = 1.0f, low = 1.5f * sphSpacing(p);
  s.world.sinks.push_back({glm::vec3(-far, -1.0f, -far), glm::vec3(-clear, low, far)});
  s.world.sinks.push_back({glm::vec3(clear, -1.0f, -far), glm::vec3(far, low, far)});
  s.world.sinks.push_back({glm::vec3(-clear, -1.0f, -far), glm::vec3(clear, low, -clear)});
  s.world.sinks.push_back({glm::vec3(-clear, -1.0f, clear), glm::vec3(clear, low, far)});
  addSphBlock(s.world, glm::vec3(-b.inner, 0.0f, -b.inner), glm::vec3(b.inner, water_height, b.inner));
  return b;
}

// Smallest signed distance of any particle to any collider (m; < 0: inside one).
float worstDistance(const SphWorld& world) {
  float worst = 1e30f;
  std::vector<glm::vec3> local;
  std::vector<ColliderSample> samples;
  for (const SphCollider& c : world.colliders) {
    local.resize(world.particles.size());
    samples.resize(local.size());
    for (std::size_t i = 0; i < local.size(); ++i) local[i] = toColliderSpace(c.pose, world.particles.position[i]);
    c.shape->query(local, samples);
    for (const ColliderSample& s : samples)
      if (s.valid) worst = std::min(worst, s.distance);
  }
  return worst;
}

float maxSpeed(const SphWorld& world) {
  float v = 0.0f;
  for (const glm::vec3& u : world.particles.velocity) v = std::max(v, glm::length(u));
  return v;
}

bool allFinite(const SphWorld& world) {
  for (std::size_t i = 0; i < world.particles.size(); ++i) {
    const glm::vec3 x = world.particles.position[i], v = world.particles.velocity[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z)) return false;
  }
  return true;
}

// What a run of steps saw.
struct Watch {
  std::size_t steps = 0, emitted = 0, removed = 0, wall_crossings = 0;
  float worst_distance = 1e30f;  // over every step end
  float top_speed = 0.0f;        // over every step end
  float first_dt = 0.0f;
  float max_move = 0.0f;    // m, the largest distance a particle moved in one step
  double max_energy = 0.0;  // kinetic + potential, over every step end
  bool finite = true;
};

// Steps with the solver's own step until `seconds` have passed, checking after every step: finite
// state, collider distances, speed, energy, and (by particle id) that no particle went from inside
// the basin to outside it, or back, while below the rim less one step's travel (cfl d): that would
// be a crossing through a wall rather than over it.
Watch stepAndWatch(Basin& b, double seconds) {
  SphWorld& w = b.scene.world;
  Watch watch;
  const float d = sphSpacing(w.params);
  const float over = b.rim - w.params.cfl * d - 1e-4f;
  std::vector<glm::vec3> before;  // by id
  auto inside = [&](glm::vec3 x) { return std::abs(x.x) < b.inner && std::abs(x.z) < b.inner; };
  auto outside = [&](glm::vec3 x) { return std::abs(x.x) > b.inner + b.wall || std::abs(x.z) > b.inner + b.wall; };
  const double end = w.time + seconds;
  while (w.time < end) {
    before.assign(w.next_id + 1000, glm::vec3(std::nanf("")));
    for (std::size_t i = 0; i < w.particles.size(); ++i) before[w.particles.id[i]] = w.particles.position[i];
    SphStepStats stats;
    const SphStatus status = stepSph(w, 0.0f, &stats);
    EXPECT_TRUE(status.ok()) << status.error;
    if (!status.ok()) break;
    if (watch.steps == 0) watch.first_dt = stats.dt;
    ++watch.steps;
    watch.emitted += stats.emitted;
    watch.removed += stats.removed;
    watch.finite = watch.finite && allFinite(w);
    watch.worst_distance = std::min(watch.worst_distance, worstDistance(w));
    watch.top_speed = std::max(watch.top_speed, maxSpeed(w));
    watch.max_energy = std::max(watch.max_energy, sphKineticEnergy(w) + sphPotentialEnergy(w));
    for (std::size_t i = 0; i < w.particles.size(); ++i) {
      if (w.particles.id[i] >= before.size()) continue;  // emitted this step
      const glm::vec3 x0 = before[w.particles.id[i]], x1 = w.particles.position[i];
      if (std::isnan(x0.x)) continue;  // emitted this step
      watch.max_move = std::max(watch.max_move, glm::length(x1 - x0));
      const bool crossed = (inside(x0) && outside(x1)) || (outside(x0) && inside(x1));
      if (crossed && std::max(x0.y, x1.y) < over) ++watch.wall_crossings;
    }
  }
  return watch;
}

void expectSane(const Watch& watch, std::size_t count_before, const SphWorld& w, float speed_bound, const char* what) {
  EXPECT_TRUE(watch.finite) << what;
  EXPECT_EQ(w.particles.size(), count_before + watch.emitted - watch.removed) << what;
  EXPECT_LE(w.particles.size(), w.params.max_particles) << what;
  EXPECT_LE(watch.top_speed, speed_bound) << what;
  // The collision pass leaves particles skin (0.01 r) outside; allow float rounding only.
  EXPECT_GE(watch.worst_distance, -1e-5f) << what;
  EXPECT_EQ(watch.wall_crossings, 0u) << what;
  // The adaptive step kept up with the speeds: no particle moved more than the CFL distance
  // cfl d per step, up to the pressure solve's velocity change after the bound was taken.
  EXPECT_LE(watch.max_move, 1.5f * w.params.cfl * sphSpacing(w.params)) << what;
}

TEST(SphBlast, EachParticleGetsTheSharedLawWithItsFaceAsCrossSection) {
  SphScene s;
  ASSERT_TRUE(makeSphScene("column", SphSolverKind::dfsph, {}, s).ok());
  SphWorld& w = s.world;
  w.particles = ParticleStore{};
  for (float x : {0.0f, 0.02f, 0.2f, 0.4f, 0.9f, 1.2f}) addSphParticle(w, glm::vec3(0.5f + x, 0.5f, 0.5f));
  Blast blast;
  blast.centre = glm::vec3(0.5f);
  blast.impulse_at_1m = 2.0f;
  blast.core_radius = 0.05f;
  blast.reach = 1.0f;
  const float cap = 30.0f;
  ASSERT_GT(blastImpulsePerArea(blast, 0.0f) * sphBlastAreaOverMass(w.params), cap);  // the cap binds in the core
  SphBlastStats stats;
  ASSERT_TRUE(applyBlast(w, blast, cap, &stats).ok());
  const float area_over_mass = sphBlastAreaOverMass(w.params);
  const float d = sphSpacing(w.params);
  EXPECT_FLOAT_EQ(area_over_mass, d * d / sphParticleMass(w.params));
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    EXPECT_EQ(w.particles.velocity[i], blastVelocityChange(blast, w.particles.position[i], area_over_mass, cap))
        << "particle " << i;
  // 1/r^2 between 0.2 and 0.4 m (inside the taper band), the core cap at the centre and 2 cm
  // (both inside core_radius), the speed cap there, nothing beyond reach.
  EXPECT_NEAR(w.particles.velocity[2].x / w.particles.velocity[3].x, 4.0f, 1e-4f);
  EXPECT_EQ(w.particles.velocity[0], glm::vec3(0.0f, cap, 0.0f));  // at the centre: straight up
  EXPECT_EQ(w.particles.velocity[1], glm::vec3(cap, 0.0f, 0.0f));
  EXPECT_EQ(w.particles.velocity[5], glm::vec3(0.0f));
  EXPECT_EQ(stats.particles, 5u);
  EXPECT_NEAR(stats.max_speed_change, cap, 1e-5f * cap);
}

TEST(SphBlast, BadFieldsAreRefusedByNameAndLeaveTheWorldUntouched) {
  Basin b = makeBasin(0.01f, 0.04f, 0.12f);
  const std::vector<glm::vec3> v0 = b.scene.world.particles.velocity;
  Blast blast;
  blast.centre.y = std::nanf("");
  SphStatus status = applyBlast(b.scene.world, blast, 10.0f);
  EXPECT_NE(status.error.find("centre"), std::string::npos) << status.error;
  blast = Blast{};
  blast.impulse_at_1m = std::numeric_limits<float>::infinity();
  status = applyBlast(b.scene.world, blast, 10.0f);
  EXPECT_NE(status.error.find("impulse_at_1m"), std::string::npos) << status.error;
  blast = Blast{};
  blast.reach = 0.5f * blast.core_radius;
  status = applyBlast(b.scene.world, blast, 10.0f);
  EXPECT_NE(status.error.find("reach"), std::string::npos) << status.error;
  status = applyBlast(b.scene.world, Blast{}, 0.0f);
  EXPECT_NE(status.error.find("max_speed_change"), std::string::npos) << status.error;
  status = applyBlast(b.scene.world, Blast{}, std::nanf(""));
  EXPECT_NE(status.error.find("max_speed_change"), std::string::npos) << status.error;
  EXPECT_EQ(b.scene.world.particles.velocity, v0);
}

TEST(SphBlast, CentredOnTheNozzleTheStepShortensAndNothingBreaks) {
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    Basin b = makeBasin(0.01f, 0.04f, 0.12f);
    SphWorld& w = b.scene.world;
    w.params.solver = solver;
    if (solver == SphSolverKind::wcsph) w.params.sound_speed = 40.0f;
    SphEmitter nozzle;
    nozzle.position = glm::vec3(0.0f, 0.07f, 0.0f);
    nozzle.speed = 2.0f;
    nozzle.radius = 0.02f;
    nozzle.rate = 1500.0f;
    w.emitters.push_back(nozzle);
    const std::size_t count_start = w.particles.size();
    const Watch settle = stepAndWatch(b, 0.05);  // the jet runs
    expectSane(settle, count_start, w, 4.0f, "jet before the blast");
    Blast blast;
    blast.centre = nozzle.position;
    blast.impulse_at_1m = 1.6f;
    blast.core_radius = 0.03f;
    blast.reach = 0.5f;
    const float cap = 25.0f;
    SphBlastStats blast_stats;
    ASSERT_TRUE(applyBlast(w, blast, cap, &blast_stats).ok());
    EXPECT_GT(blast_stats.particles, 100u);
    EXPECT_NEAR(blast_stats.max_speed_change, cap, 1e-5f * cap);  // particles within the core got the cap
    const float last_dt = w.last_dt;
    const std::size_t count = w.particles.size();
    const Watch after = stepAndWatch(b, 0.15);
    // The adaptive step reacts at once (WCSPH's sound-speed bound may already be shorter).
    EXPECT_LT(after.first_dt, 2.0f * w.params.cfl * sphSpacing(w.params) / cap) << sphSolverName(solver);
    if (solver == SphSolverKind::dfsph) {
      EXPECT_LT(after.first_dt, 0.5f * last_dt);
    }
    expectSane(after, count, w, 1.1f * (cap + nozzle.speed), sphSolverName(solver));
    EXPECT_GT(after.emitted, 0u);  // the nozzle went on emitting after the blast
  }
}

TEST(SphBlast, TenBlastsInOneStepStayBoundedAndAccounted) {
  Basin b = makeBasin(0.01f, 0.04f, 0.12f);
  SphWorld& w = b.scene.world;
  const double energy_before = sphKineticEnergy(w) + sphPotentialEnergy(w);
  float cap_sum = 0.0f;
  for (int k = 0; k < 10; ++k) {
    Blast blast;
    const float angle = 0.6283185f * static_cast<float>(k);
    blast.centre = glm::vec3(0.08f * std::cos(angle), 0.02f + 0.005f * static_cast<float>(k), 0.08f * std::sin(angle));
    blast.impulse_at_1m = 0.32f;
    blast.core_radius = 0.04f;
    blast.reach = 0.3f;
    const float cap = 6.0f;
    cap_sum += cap;
    ASSERT_TRUE(applyBlast(w, blast, cap).ok());
  }
  const float speed_after = maxSpeed(w);
  EXPECT_GT(speed_after, 6.0f);     // the blasts added up
  EXPECT_LE(speed_after, cap_sum);  // but no more than their caps
  const double energy_blast = sphKineticEnergy(w) + sphPotentialEnergy(w);
  EXPECT_GT(energy_blast, energy_before);
  const std::size_t count = w.particles.size();
  const Watch after = stepAndWatch(b, 0.2);
  // Streams thrown into each other exchange momentum, so a particle may end faster than the blasts
  // made it; the energy bound below is the strict one.
  expectSane(after, count, w, 1.25f * speed_after, "ten blasts");
  // Nothing explodes numerically: the fluid never holds more energy than the blasts gave it
  // (particles leaving through the drains only take energy away).
  EXPECT_LE(after.max_energy, energy_blast * 1.01) << "energy before the blasts " << energy_before;
}

TEST(SphBlast, WaterThrownAt100MetresPerSecondStaysOutOfTheThinWalls) {
  Basin b = makeBasin(0.01f, 0.04f, 0.12f);
  SphWorld& w = b.scene.world;
  Blast blast;
  blast.centre = glm::vec3(-0.12f, 0.02f, 0.0f);  // next to the -x wall: water is thrown at both x walls
  blast.impulse_at_1m = 32.0f;
  blast.core_radius = 0.05f;
  blast.reach = 0.6f;
  ASSERT_TRUE(applyBlast(w, blast, 100.0f).ok());
  const float speed_after = maxSpeed(w);
  EXPECT_GE(speed_after, 99.0f);  // the case is exercised
  const double energy_blast = sphKineticEnergy(w) + sphPotentialEnergy(w);
  const std::size_t count = w.particles.size();
  const Watch after = stepAndWatch(b, 0.08);
  std::printf(
      "[ metric ] 100 m/s blast: %zu steps in 0.08 s, first dt %.2e s, largest move per step %.2f mm, worst "
      "collider distance %.2e m, %zu drained\n",
      after.steps, static_cast<double>(after.first_dt), 1e3 * static_cast<double>(after.max_move),
      static_cast<double>(after.worst_distance), after.removed);
  expectSane(after, count, w, 1.1f * speed_after, "100 m/s");
  EXPECT_LE(after.max_energy, energy_blast * 1.01);
}

TEST(SphBlast, BasinOverflowingFor60SecondsKeepsItsBudgetAndLevel) {
  // Coarse particles (d = 4 cm) so 60 s stay a few seconds of CPU: the basin filled to the brim
  // (three layers, the walls three spacings high), a nozzle pouring in, the overflow running over
  // the rim to the drains.
  Basin b = makeBasin(0.02f, 0.12f, 0.12f, 0.16f);
  SphWorld& w = b.scene.world;
  w.params.max_particles = 300;
  w.params.force_bound = 0.0f;
  w.params.cfl = 0.9f;  // as the game's fountain runs DFSPH
  w.params.max_time_step = 0.015f;
  SphEmitter nozzle;
  nozzle.position = glm::vec3(0.0f, 0.2f, 0.0f);
  nozzle.direction = glm::vec3(0.0f, -1.0f, 0.0f);
  nozzle.speed = 1.0f;
  nozzle.radius = 0.04f;
  nozzle.rate = 100.0f;
  w.emitters.push_back(nozzle);
  const float volume_per_particle = sphParticleMass(w.params) / w.params.rest_density;
  auto basinVolume = [&] {
    std::size_t in = 0;
    for (const glm::vec3& x : w.particles.position)
      if (std::abs(x.x) < b.inner && std::abs(x.z) < b.inner) ++in;
    return static_cast<double>(in) * volume_per_particle;
  };
  const double brim_volume = basinVolume();
  std::size_t count = w.particles.size(), emitted = 0, removed = 0, peak = 0;
  double at_30 = 0.0;
  float top_speed = 0.0f;
  bool finite = true;
  const SphStatus status = advanceSph(w, 60.0, [&](const SphStepStats& s) {
    emitted += s.emitted;
    removed += s.removed;
    peak = std::max(peak, s.particles);
    if (at_30 == 0.0 && w.time >= 30.0) at_30 = basinVolume();
    finite = finite && std::isfinite(s.kinetic_energy);
  });
  ASSERT_TRUE(status.ok()) << status.error;
  top_speed = maxSpeed(w);
  const double at_60 = basinVolume();
  std::printf(
      "[ metric ] overflow 60 s: %zu emitted, %zu drained, peak %zu particles (budget %zu); water in the "
      "basin %.2f L at the brim, %.2f L at 30 s, %.2f L at 60 s (drift 30 -> 60 s %+.1f %%)\n",
      emitted, removed, peak, w.params.max_particles, 1e3 * brim_volume, 1e3 * at_30, 1e3 * at_60,
      100.0 * (at_60 - at_30) / at_30);
  EXPECT_TRUE(finite && allFinite(w));
  EXPECT_EQ(w.particles.size(), count + emitted - removed);
  EXPECT_LE(peak, w.params.max_particles);
  EXPECT_GT(removed, 4000u);  // the overflow reached the drains all along
  EXPECT_LT(top_speed, 5.0f);
  // The basin stays full (the overflow runs off rather than piling up or emptying it).
  EXPECT_GT(at_60, 0.8 * brim_volume);
  EXPECT_LT(at_60, 1.5 * brim_volume);
  EXPECT_LT(std::abs(at_60 - at_30), 0.1 * at_30);
  EXPECT_GE(worstDistance(w), -1e-5f);
}

}  // namespace
