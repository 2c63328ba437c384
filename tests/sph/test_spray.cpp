// Spray (SphParams::spray_speed, fluid/sph/spray.hpp): drops a blast throws out of the water fly
// ballistic outside the SPH solve and rejoin it where they land. A pool 0.2 m deep in a 1 m box
// (3,125 particles), blasted from just above its surface. Every case checks the count, the ids,
// no NaN and that no particle leaves the box below its rim.
#include "collider_distance.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/blast.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <vector>

namespace {

using namespace fluid;

constexpr double kFrame = 1.0 / 60.0;

// The game's fountain regime (content/scenes/fountain.json): a CFL number of 0.9 and steps of up
// to a frame, so calm water takes about one step per frame.
SphScene sprayPool(float spray_speed) {
  SphScene scene;
  SphWorld& w = scene.world;
  SphParams& p = w.params;
  p.particle_radius = 0.02f;
  p.viscosity = 0.01f;
  p.cfl = 0.9f;
  p.max_time_step = static_cast<float>(kFrame);
  p.max_density_error = 0.005f;
  p.force_bound = 0.0f;
  p.max_particles = 100000;
  p.domain_min = glm::vec3(-0.5f);
  p.domain_max = glm::vec3(1.5f, 3.0f, 1.5f);
  p.spray_speed = spray_speed;
  p.spray_terminal_speed = 8.0f;
  CollisionMaterial wall;
  wall.resilience = 0.0f;
  addSphContainer(scene, glm::vec3(0.0f), glm::vec3(1.0f, 1.5f, 1.0f), wall);
  addSphBlock(w, glm::vec3(0.0f), glm::vec3(1.0f, 0.2f, 1.0f));  // 25 x 5 x 25
  return scene;
}

Blast poolBlast(float impulse_at_1m) {
  Blast b;
  b.centre = glm::vec3(0.5f, 0.25f, 0.5f);
  b.impulse_at_1m = impulse_at_1m;
  b.core_radius = 0.1f;
  b.reach = 1.0f;
  return b;
}

std::multiset<std::uint32_t> ids(const SphWorld& w) { return {w.particles.id.begin(), w.particles.id.end()}; }

// Every particle is finite, and none is inside the box's walls or floor below the rim (the
// collision skin aside).
void expectInsideTheBox(const SphWorld& w, const char* when) {
  const float skin = 1e-4f;
  std::size_t outside = 0, nonfinite = 0;
  for (std::size_t i = 0; i < w.particles.size(); ++i) {
    const glm::vec3 x = w.particles.position[i], v = w.particles.velocity[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z)) ++nonfinite;
    if (x.y < 1.5f && (x.y < -skin || x.x < -skin || x.z < -skin || x.x > 1.0f + skin || x.z > 1.0f + skin)) ++outside;
  }
  EXPECT_EQ(nonfinite, 0u) << when;
  EXPECT_EQ(outside, 0u) << when;
}

struct BlastRun {
  double calm_steps = 0.0;   // SPH steps per frame over the last 0.5 s before the blast
  double blast_steps = 0.0;  // over the 2 s after it
  std::size_t most_spray = 0, spray_at_end = 0, left = 0, joined = 0;
  float top_speed = 0.0f;  // fastest particle right after the blast
};

// 0.5 s calm, the blast, 2 s after it, in frames of 1/60 s (advanceSph, as the game steps).
BlastRun blastRun(SphScene& scene, const Blast& blast, float cap) {
  SphWorld& w = scene.world;
  const auto ids0 = ids(w);
  BlastRun run;
  std::size_t steps = 0;
  const auto frames = [&](int count) {
    for (int f = 0; f < count; ++f) {
      const SphStatus st = advanceSph(w, kFrame, [&](const SphStepStats& s) {
        ++steps;
        run.most_spray = std::max(run.most_spray, s.spray);
        run.left += s.spray_left;
        run.joined += s.spray_joined;
        EXPECT_EQ(s.particles, ids0.size());
        EXPECT_EQ(s.nonfinite, 0u);
      });
      EXPECT_TRUE(st.ok()) << st.error;
      EXPECT_LE(w.particles.spray_count, w.particles.size());
    }
  };
  frames(30);
  run.calm_steps = steps / 30.0;
  EXPECT_TRUE(applyBlast(w, blast, cap).ok());
  for (const glm::vec3& v : w.particles.velocity) run.top_speed = std::max(run.top_speed, glm::length(v));
  steps = 0;
  frames(120);
  run.blast_steps = steps / 120.0;
  run.spray_at_end = w.particles.spray_count;
  EXPECT_EQ(ids(w), ids0) << "every particle keeps its id, none is lost or made";
  expectInsideTheBox(w, "after the blast");
  return run;
}

TEST(SphSpray, ABlastCostsAboutWhatCalmWaterCosts) {
  SphScene with = sprayPool(3.0f), without = sprayPool(0.0f);
  const BlastRun on = blastRun(with, poolBlast(6.0f), 20.0f);
  const BlastRun off = blastRun(without, poolBlast(6.0f), 20.0f);
  std::printf("steps per frame, calm / 2 s after the blast: spray %.2f / %.2f, without %.2f / %.2f; most spray %zu, "
              "%zu left, %zu joined, %zu spray at the end; fastest drop %.1f m/s\n",
              on.calm_steps, on.blast_steps, off.calm_steps, off.blast_steps, on.most_spray, on.left, on.joined,
              on.spray_at_end, on.top_speed);
  EXPECT_GT(on.top_speed, 15.0f) << "the blast throws water fast";
  EXPECT_GT(on.most_spray, 100u) << "the blast makes spray";
  // In a box this small the blast also sets the whole pool sloshing at 2-5 m/s, which the SPH must
  // step; the drops no longer add to that (the game's fountain measures against calm water:
  // tests/game/test_fountain_pump.cpp).
  EXPECT_LT(on.blast_steps, 0.85 * off.blast_steps) << "without spray the fastest drop sets every step";
  EXPECT_LT(on.spray_at_end, on.most_spray / 10) << "the drops rejoin the pool where they land";
  EXPECT_EQ(off.most_spray, 0u);
}

TEST(SphSpray, ABlastThrowingWaterAtAHundredMetresPerSecondStaysInTheBox) {
  SphScene scene = sprayPool(3.0f);
  const BlastRun run = blastRun(scene, poolBlast(60.0f), 100.0f);
  std::printf("100 m/s blast: fastest %.1f m/s, steps per frame %.2f (calm %.2f), most spray %zu\n", run.top_speed,
              run.blast_steps, run.calm_steps, run.most_spray);
  EXPECT_GT(run.top_speed, 99.0f);
  SphScene without = sprayPool(0.0f);
  const BlastRun off = blastRun(without, poolBlast(60.0f), 100.0f);
  std::printf("without spray: steps per frame %.2f\n", off.blast_steps);
  // Without spray the drops fly on up without drag and are still out of the box after 2 s; with it
  // they fall back at their terminal speed and land in the pool, and the steps stay fewer still.
  EXPECT_LE(run.blast_steps, off.blast_steps);
  for (const glm::vec3& v : scene.world.particles.velocity) EXPECT_LT(glm::length(v), 100.0f);
}

TEST(SphSpray, SameStateForOneAndTwoThreads) {
  std::vector<glm::vec3> x[2], v[2];
  std::vector<std::uint32_t> id[2];
  std::size_t spray[2];
  for (int t = 0; t < 2; ++t) {
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(t + 1));
    SphScene scene = sprayPool(3.0f);
    SphWorld& w = scene.world;
    for (int f = 0; f < 10; ++f) ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
    ASSERT_TRUE(applyBlast(w, poolBlast(6.0f), 20.0f).ok());
    for (int f = 0; f < 40; ++f) ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
    x[t] = w.particles.position;
    v[t] = w.particles.velocity;
    id[t] = w.particles.id;
    spray[t] = w.particles.spray_count;
  }
  EXPECT_GT(spray[0], 0u) << "the comparison runs while there is spray";
  EXPECT_EQ(spray[0], spray[1]);
  EXPECT_EQ(id[0], id[1]);
  ASSERT_EQ(x[0].size(), x[1].size());
  for (std::size_t i = 0; i < x[0].size(); ++i) {
    ASSERT_EQ(x[0][i], x[1][i]) << "particle " << i;
    ASSERT_EQ(v[0][i], v[1][i]) << "particle " << i;
  }
}

// A lone drop in empty space reaches the terminal speed and no more (the drag law).
TEST(SphSpray, ADropFallsAtItsTerminalSpeed) {
  SphWorld w;
  w.params.spray_speed = 1.0f;
  w.params.spray_terminal_speed = 6.0f;
  w.params.max_time_step = static_cast<float>(kFrame);
  ASSERT_TRUE(addSphParticle(w, glm::vec3(0.0f, 100.0f, 0.0f), glm::vec3(0.0f, -2.0f, 0.0f)));
  for (int f = 0; f < 300; ++f) ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
  EXPECT_EQ(w.particles.spray_count, 1u);
  EXPECT_NEAR(-w.particles.velocity[0].y, 6.0f, 0.06f);
}

// Drops thrown down at the floor land on it (outside it) and, once slow, are water again.
TEST(SphSpray, DropsLandOnTheFloorAndRejoin) {
  SphScene scene;
  SphWorld& w = scene.world;
  w.params.particle_radius = 0.02f;
  w.params.spray_speed = 2.0f;
  w.params.spray_terminal_speed = 0.0f;
  w.params.max_time_step = static_cast<float>(kFrame);
  CollisionMaterial floor;
  floor.resilience = 0.0f;
  floor.friction = 1.0f;
  addSphContainer(scene, glm::vec3(-1.0f, 0.0f, -1.0f), glm::vec3(1.0f, 1.0f, 1.0f), floor);
  for (int k = 0; k < 5; ++k)
    ASSERT_TRUE(addSphParticle(w, glm::vec3(0.2f * static_cast<float>(k - 2), 0.5f, 0.0f), glm::vec3(0.0f, -30.0f, 0.0f)));
  std::size_t most_spray = 0;
  for (int f = 0; f < 60; ++f) {
    ASSERT_TRUE(advanceSph(w, kFrame, [&](const SphStepStats& s) { most_spray = std::max(most_spray, s.spray); }).ok());
    for (const glm::vec3& x : w.particles.position) ASSERT_GE(x.y, 0.0f) << "frame " << f;
  }
  EXPECT_EQ(most_spray, 5u);
  EXPECT_EQ(w.particles.spray_count, 0u);
}

// A particle added while there is spray is water: it goes in front of the spray.
TEST(SphSpray, ParticlesAddedWhileThereIsSprayAreWater) {
  SphScene scene = sprayPool(3.0f);
  SphWorld& w = scene.world;
  ASSERT_TRUE(applyBlast(w, poolBlast(6.0f), 20.0f).ok());
  for (int f = 0; f < 6 && w.particles.spray_count == 0; ++f)
    ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
  const std::size_t spray = w.particles.spray_count;
  ASSERT_GT(spray, 0u);
  const std::uint32_t id = w.next_id;
  ASSERT_TRUE(addSphParticle(w, glm::vec3(0.51f, 0.1f, 0.51f)));
  EXPECT_EQ(w.particles.spray_count, spray);
  const auto at = std::find(w.particles.id.begin(), w.particles.id.end(), id) - w.particles.id.begin();
  EXPECT_EQ(static_cast<std::size_t>(at), w.particles.sphCount() - 1);
  EXPECT_EQ(w.particles.position[static_cast<std::size_t>(at)].x, 0.51f);
  ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
}

// A drop caught between a crate and a wall it overlaps (a crate pressed against the basin rim):
// a still wall whose face, through (1, anchor), leans by `tilt_degrees` (its outward normal
// (-cos, -sin) of the tilt), and a 0.6 m crate reaching `overlap` into it, moving slowly (a moving
// collider: resolved first). The drop flies free for one step (so it is spray), then the colliders
// appear around it. Returns its signed distances to the crate and the wall after that step.
struct SqueezedDrop {
  float crate = 0.0f, wall = 0.0f;
  std::size_t spray = 0;
};
SqueezedDrop squeezeDrop(glm::vec3 at, float tilt_degrees, float anchor, float overlap) {
  SphWorld w;
  w.params.particle_radius = 0.04f;
  w.params.spray_speed = 0.5f;
  w.params.spray_terminal_speed = 0.0f;
  w.params.gravity = glm::vec3(0.0f);
  w.params.max_time_step = 0.002f;
  w.params.domain_min = glm::vec3(-3.0f);
  w.params.domain_max = glm::vec3(3.0f);
  EXPECT_TRUE(addSphParticle(w, at + glm::vec3(0.0f, 0.006f, 0.0f), glm::vec3(0.0f, -3.0f, 0.0f)));
  EXPECT_TRUE(advanceSph(w, 0.002, [](const SphStepStats&) {}).ok());
  SphCollider wall;
  wall.shape = std::make_shared<BoxShape>(glm::vec3(0.5f, 1.0f, 1.0f));
  wall.pose.rotation = glm::angleAxis(glm::radians(tilt_degrees), glm::vec3(0.0f, 0.0f, 1.0f));
  wall.pose.translation = glm::vec3(1.0f, anchor, 0.0f) + wall.pose.rotation * glm::vec3(0.5f, 0.0f, 0.0f);
  wall.integrate_pose = false;
  SphCollider crate;
  crate.shape = std::make_shared<BoxShape>(glm::vec3(0.3f));
  crate.pose.translation = glm::vec3(1.0f + overlap - 0.3f, 0.5f, 0.0f);
  crate.pose.linear_velocity = glm::vec3(0.01f, 0.0f, 0.0f);
  w.colliders = {wall, crate};
  SqueezedDrop out;
  EXPECT_TRUE(advanceSph(w, 0.002, [&](const SphStepStats& s) { out.spray = s.spray; }).ok());
  out.wall = sph_test::distanceTo(w.colliders[0], w.particles.position[0]);
  out.crate = sph_test::distanceTo(w.colliders[1], w.particles.position[0]);
  return out;
}

// The collision passes hand such a drop back and forth between the two faces; where the crate's
// nearest exit from the drop's last position is free (here its bottom), the drop leaves by it
// (without that it ended 6 mm inside the crate). Where no exit is free, the wall wins: the drop
// ends outside it, inside the crate.
TEST(SphSpray, ADropSqueezedBetweenACrateAndAWallLeavesByAFreeExit) {
  const SqueezedDrop free_exit = squeezeDrop(glm::vec3(1.03f, 0.23f, 0.0f), 25.0f, 0.3f, 0.05f);
  EXPECT_EQ(free_exit.spray, 1u);
  EXPECT_GE(free_exit.crate, 0.0f) << "left the crate";
  EXPECT_GE(free_exit.wall, 0.0f) << "and stayed out of the wall";
  const SqueezedDrop caught = squeezeDrop(glm::vec3(1.02f, 0.28f, 0.0f), 15.0f, 0.35f, 0.05f);
  EXPECT_EQ(caught.spray, 1u);
  EXPECT_GE(caught.wall, 0.0f) << "the still wall wins";
  EXPECT_LT(caught.crate, -0.01f) << "no free exit: left inside the crate";
}

// Water faster than spray_speed leaves the solve even deep inside calm water (a splash the bulk
// would otherwise have to step at the splash's speed): there it is a submerged drop that the
// water's drag slows within a few frames, the water taking the momentum it loses, and it rejoins.
// A cube of water floating without gravity or walls, its centre particle kicked at 6 m/s.
TEST(SphSpray, FastWaterInsideCalmWaterLeavesTheSolveAndTheWaterSlowsIt) {
  SphWorld w;
  SphParams& p = w.params;
  p.particle_radius = 0.02f;
  p.gravity = glm::vec3(0.0f);
  p.cfl = 0.9f;
  p.max_time_step = static_cast<float>(kFrame);
  p.spray_speed = 3.0f;
  p.domain_min = glm::vec3(-2.0f);
  p.domain_max = glm::vec3(2.0f);
  addSphBlock(w, glm::vec3(0.0f), glm::vec3(0.4f));  // 10 x 10 x 10
  const glm::vec3 centre(0.22f);
  std::size_t kicked = 0;
  for (std::size_t i = 1; i < w.particles.size(); ++i)
    if (glm::length(w.particles.position[i] - centre) < glm::length(w.particles.position[kicked] - centre)) kicked = i;
  const std::uint32_t id = w.particles.id[kicked];
  // Off the lattice's rows: along a row the drop would pass within half a spacing of each particle
  // of it and could rejoin nowhere (gateCrowdedRejoins), which a real pool's disorder never keeps up.
  const glm::vec3 kick = 6.0f * glm::normalize(glm::vec3(1.0f, 0.37f, 0.23f));
  w.particles.velocity[kicked] = kick;
  const auto momentum = [&] {
    glm::dvec3 sum(0.0);
    for (const glm::vec3& v : w.particles.velocity) sum += glm::dvec3(v);
    return sum;
  };
  const auto kickedIndex = [&] {
    return static_cast<std::size_t>(std::find(w.particles.id.begin(), w.particles.id.end(), id) - w.particles.id.begin());
  };
  std::size_t left = 0, steps = 0, spray_steps = 0;
  for (int f = 0; f < 30; ++f) {
    ASSERT_TRUE(advanceSph(w, kFrame, [&](const SphStepStats& s) {
                  left += s.spray_left;
                  ++steps;
                  spray_steps += s.spray > 0 ? 1 : 0;
                  EXPECT_EQ(s.nonfinite, 0u);
                }).ok());
    if (f == 0) {
      // The water around was at rest, so its solve moved nothing: the momentum the drop lost is in
      // the water (the solve's own drift, later, is a few per cent of it per frame).
      const glm::dvec3 total = momentum();
      EXPECT_EQ(w.particles.spray_count, 1u);
      EXPECT_LT(glm::length(w.particles.velocity[kickedIndex()]), 4.0f) << "slowed by the water within the frame";
      EXPECT_NEAR(total.x, kick.x, 1e-3) << "the water took the momentum the drop lost";
      EXPECT_NEAR(total.y, kick.y, 1e-3);
      EXPECT_NEAR(total.z, kick.z, 1e-3);
    }
  }
  EXPECT_EQ(left, 1u) << "the kicked particle left the solve among its calm neighbours, and only it";
  EXPECT_LT(steps, 35u) << "the bulk sets the step, not the kicked particle";
  EXPECT_LE(spray_steps, 10u) << "it rejoined within 10 frames";
  EXPECT_EQ(w.particles.spray_count, 0u);
  const glm::vec3 end = w.particles.position[kickedIndex()];
  EXPECT_TRUE(glm::all(glm::lessThan(end, glm::vec3(0.4f)))) << "stopped inside the cube, not flown through";
}

// Drops that fall together (the jet's crown slowing at its apex, a blast's sheet) pass through one
// another as spray and can end a step bunched within a millimetre, all slow among water. Let in at
// once they would start the next step at over three times the rest density (245 % error); the rejoin gate lets them in
// a few at a time, each where it does not crowd the water, so no step starts far above rho_0.
TEST(SphSpray, DropsBunchedInTheWaterRejoinOneAtATime) {
  SphScene scene = sprayPool(3.0f);
  SphWorld& w = scene.world;
  for (int f = 0; f < 30; ++f) ASSERT_TRUE(advanceSph(w, kFrame, [](const SphStepStats&) {}).ok());
  // Eight drops within a millimetre, moving down fast into the pool's middle just under its surface.
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 offset(0.0003f * static_cast<float>(k % 2), 0.0003f * static_cast<float>((k / 2) % 2),
                           0.0003f * static_cast<float>(k / 4));
    ASSERT_TRUE(addSphParticle(w, glm::vec3(0.51f, 0.16f, 0.51f) + offset, glm::vec3(0.0f, -4.0f, 0.0f)));
  }
  std::size_t most_joined = 0, crowded = 0, joined = 0;
  float worst = 0.0f;
  for (int f = 0; f < 120; ++f)
    ASSERT_TRUE(advanceSph(w, kFrame, [&](const SphStepStats& s) {
                  most_joined = std::max(most_joined, s.spray_joined);
                  joined += s.spray_joined;
                  crowded += s.rejoins_crowded;
                  worst = std::max(worst, s.max_density_error);
                  EXPECT_EQ(s.nonfinite, 0u);
                }).ok());
  std::printf("bunched drops: %zu rejoined, at most %zu in a step, %zu waits, worst density error %.1f %%\n", joined,
              most_joined, crowded, 100.0 * worst);
  EXPECT_GE(joined, 8u);
  EXPECT_LE(most_joined, 2u) << "bunched drops rejoin one or two a step";
  EXPECT_GT(crowded, 0u) << "the gate held some back";
  EXPECT_LT(worst, 0.45f) << "no step starts with a particle far above the rest density";
  EXPECT_EQ(w.particles.spray_count, 0u) << "all of them are water in the end";
}

}  // namespace
