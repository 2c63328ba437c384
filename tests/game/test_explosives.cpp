// Explosives (game/explosives): a thrown charge flies, lands and detonates when its fuse runs out;
// the detonation pushes crates by the shared blast law and is handed on as a fluid::Blast; charges
// are recycled at max_live; bad parameters are named; randomised throws stay finite.
#include "game/explosives/explosives.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace {

struct Yard {
  std::unique_ptr<engine::PhysicsWorld> physics = engine::createPhysicsWorld({});
  game::Explosives explosives;
  engine::BodyId crate = -1;
  Yard() {
    engine::addStaticPlane(*physics, {0, 1, 0}, 0.0f);
    engine::BodyDesc desc;
    desc.mass = 20.0f;
    desc.position = {3.0f, 0.3f, 0.0f};
    crate = engine::addBox(*physics, desc, glm::vec3(0.3f));
  }
  // One game step: physics first, then the fuses (the order the game uses).
  void step(double dt = 1.0 / 60.0) {
    engine::stepPhysics(*physics, dt, 2);
    game::stepExplosives(explosives, *physics, dt);
  }
};

TEST(Explosives, AChargeDetonatesWhenItsFuseRunsOutAndPushesTheCrate) {
  Yard yard;
  yard.explosives.params.fuse_seconds = 1.5f;
  yard.explosives.params.throw_speed = 3.0f;  // lands about 1.5 m out, within reach of the crate
  game::throwExplosive(yard.explosives, *yard.physics, {0.0f, 1.0f, 0.0f}, {1.0f, 0.5f, 0.0f});
  EXPECT_EQ(game::liveCharges(yard.explosives), 1);
  int detonated_at = -1;
  glm::vec3 blast_centre(0.0f);
  for (int s = 0; s < 120 && detonated_at < 0; ++s) {
    yard.step();
    if (!yard.explosives.detonations.empty()) {
      detonated_at = s;
      blast_centre = yard.explosives.detonations[0].centre;
    }
  }
  EXPECT_EQ(detonated_at, 89);  // 1.5 s at 60 Hz: the 90th step
  EXPECT_EQ(yard.explosives.detonated, 1u);
  EXPECT_EQ(game::liveCharges(yard.explosives), 0);
  EXPECT_FALSE(engine::bodyEnabled(*yard.physics, yard.explosives.charges[0].body));
  // It flew toward +x and came to the ground before the fuse ran out.
  EXPECT_GT(blast_centre.x, 1.0f);
  EXPECT_LT(blast_centre.y, 0.3f);
  // The crate 3 m away was pushed away from the blast, by the shared law.
  const glm::vec3 v = engine::bodyState(*yard.physics, yard.crate).linear_velocity;
  EXPECT_GT(glm::dot(v, glm::vec3(3.0f, 0.3f, 0.0f) - blast_centre), 0.0f);
  EXPECT_GT(glm::length(v), 0.05f);
  EXPECT_GE(yard.explosives.bodies_pushed, 1u);
  // The blast is handed on: the next step has none.
  yard.step();
  EXPECT_TRUE(yard.explosives.detonations.empty());
}

TEST(Explosives, ImpactDetonationWhenEnabled) {
  Yard yard;
  yard.explosives.params.impact_speed_change = 4.0f;
  yard.explosives.params.fuse_seconds = 10.0f;
  game::throwExplosive(yard.explosives, *yard.physics, {0.0f, 0.5f, 0.0f}, {0.0f, -1.0f, 0.0f});
  int steps = 0;
  while (yard.explosives.detonated == 0 && steps < 60) {
    yard.step();
    ++steps;
  }
  EXPECT_EQ(yard.explosives.detonated, 1u);
  EXPECT_LT(steps, 10) << "thrown at the ground at 9 m/s, it hits within a few steps";
}

TEST(Explosives, ThrowsBeyondMaxLiveRecycleTheOldestCharge) {
  Yard yard;
  yard.explosives.params.max_live = 3;
  yard.explosives.params.fuse_seconds = 5.0f;
  for (int k = 0; k < 5; ++k) {
    game::throwExplosive(yard.explosives, *yard.physics, {0.0f, 1.0f + k, 0.0f}, {0.0f, 1.0f, 0.0f});
    yard.step();
  }
  EXPECT_EQ(yard.explosives.charges.size(), 3u);
  EXPECT_EQ(game::liveCharges(yard.explosives), 3);
  EXPECT_EQ(yard.explosives.thrown, 5u);
  EXPECT_EQ(engine::bodyCount(*yard.physics), 2 + 3);  // plane, crate, three charges
}

TEST(Explosives, BadParametersAreNamed) {
  game::ExplosiveParams p;
  EXPECT_EQ(game::validateExplosiveParams(p), "");
  p.fuse_seconds = 0.0f;
  EXPECT_NE(game::validateExplosiveParams(p).find("explosives.fuse_seconds = 0"), std::string::npos);
  p = {};
  p.reach = 0.1f;
  EXPECT_NE(game::validateExplosiveParams(p).find("blast.reach"), std::string::npos);
  p = {};
  p.max_live = 0;
  EXPECT_NE(game::validateExplosiveParams(p).find("explosives.max_live"), std::string::npos);
}

// Many random throws, some chained by blasts, for 20 s: every body stays finite, every charge is
// accounted for (thrown = detonated + still live + recycled while live).
TEST(Explosives, RandomisedThrowsForTwentySecondsStayFinite) {
  Yard yard;
  yard.explosives.params.fuse_seconds = 0.8f;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uint64_t recycled = 0;
  for (int s = 0; s < 1200; ++s) {
    if (s % 13 == 0) {
      const int live_before = game::liveCharges(yard.explosives);
      const bool full = live_before == yard.explosives.params.max_live;
      game::throwExplosive(yard.explosives, *yard.physics, {u(rng), 1.0f + u(rng), u(rng)}, {u(rng), u(rng), u(rng)});
      recycled += full ? 1u : 0u;
    }
    yard.step();
    ASSERT_EQ(engine::findNonFiniteBody(*yard.physics), -1) << "step " << s;
  }
  EXPECT_EQ(yard.explosives.thrown,
            yard.explosives.detonated + static_cast<std::uint64_t>(game::liveCharges(yard.explosives)) + recycled);
  EXPECT_GT(yard.explosives.detonated, 80u);
}

}  // namespace

// ---- the explosives effect in the fountain scene (no GL: the sprites do not run) ----------------

#include "game/paths.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"

namespace {

struct FountainRun {
  game::World world;
  FountainRun() {
    game::SceneConfig scene;
    const game::SceneStatus status = game::loadSceneFile(game::contentDir() / "scenes" / "fountain.json", scene);
    EXPECT_TRUE(status.ok()) << status.error;
    std::string error;
    EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  }
  void steps(int n) {
    for (int i = 0; i < n; ++i) game::stepWorld(world, nullptr);
  }
  game::SphFluid& sph() { return *game::findState<game::SphFluid>(world); }
  game::Explosives& explosives() { return *game::findState<game::Explosives>(world); }
};

float maxSpeed(const game::SphFluid& sph) {
  float fastest = 0.0f;
  for (const glm::vec3& v : sph.world.particles.velocity) fastest = std::max(fastest, glm::length(v));
  return fastest;
}

// Thrown from the replay's first viewpoint, the charge lands in the basin and its blast throws the
// water up: the SPH pushes are counted, the water speeds up, nothing becomes NaN, and the count is
// accounted by the emitter and the drains.
TEST(ExplosivesInTheFountain, AChargeThrownIntoTheBasinThrowsTheWaterOut) {
  FountainRun run;
  run.steps(240);  // let the jet fill the dish
  game::SphFluid& sph = run.sph();
  const float calm = maxSpeed(sph);
  run.world.camera.position = {-7.53f, 2.6f, -5.44f};
  run.world.camera.yaw_degrees = 36.0f;
  run.world.camera.pitch_degrees = -5.0f;  // the charge leaves along the aim: over the rim into the water
  game::playerThrowExplosive(run.world);
  ASSERT_EQ(run.explosives().thrown, 1u);
  float fastest_after = 0.0f;
  glm::vec3 centre(0.0f);
  for (int s = 0; s < 150; ++s) {
    run.steps(1);
    if (!run.explosives().detonations.empty()) centre = run.explosives().detonations[0].centre;
    fastest_after = std::max(fastest_after, maxSpeed(sph));
    ASSERT_EQ(run.world.nonfinite_state, "") << "step " << s;
  }
  std::printf("[ metric ] charge detonated at (%.2f, %.2f, %.2f); %llu particle pushes; fastest water %.1f m/s "
              "(%.1f before)\n",
              centre.x, centre.y, centre.z, static_cast<unsigned long long>(sph.blasted_particles), fastest_after, calm);
  EXPECT_EQ(run.explosives().detonated, 1u);
  EXPECT_LT(glm::length(glm::vec2(centre.x, centre.z)), 3.0f) << "the charge lands in or by the basin";
  EXPECT_GT(sph.blasted_particles, 100u);
  EXPECT_GT(fastest_after, calm + 1.0f);
  EXPECT_LE(fastest_after, sph.world.params.max_speed + 1e-3f);
  EXPECT_EQ(sph.error, "");
}

// A charge dropped onto the nozzle and ten detonating in the same step: the water stays finite and
// within its speed cap, and the solver keeps stepping.
TEST(ExplosivesInTheFountain, TenChargesOnTheNozzleInOneStepStayFiniteAndBounded) {
  FountainRun run;
  run.steps(120);
  game::Explosives& explosives = run.explosives();
  explosives.params.fuse_seconds = 0.05f;
  explosives.params.max_live = 10;
  explosives.params.throw_speed = 0.0f;  // dropped, not thrown
  auto* bodies = run.world.links.bodies;
  ASSERT_NE(bodies, nullptr);
  const glm::vec3 nozzle = run.world.links.level.nozzle;
  for (int k = 0; k < 10; ++k) game::throwExplosive(explosives, *bodies->physics, nozzle + glm::vec3(0, 0.05f, 0), {0, 1, 0});
  for (int s = 0; s < 120; ++s) {
    run.steps(1);
    ASSERT_EQ(run.world.nonfinite_state, "") << "step " << s;
  }
  EXPECT_EQ(explosives.detonated, 10u);
  EXPECT_EQ(run.sph().error, "");
  EXPECT_LE(maxSpeed(run.sph()), run.sph().world.params.max_speed + 1e-3f);
  EXPECT_GT(run.sph().blasted_particles, 0u);
}

// The fountain's level with only the Bullet world and the explosives (no water, no crates): the
// aim arc's test needs nothing else, and steps fast.
game::World bareFountain() {
  game::SceneConfig scene;
  EXPECT_TRUE(game::loadSceneFile(game::contentDir() / "scenes" / "fountain.json", scene).ok());
  std::erase_if(scene.effects, [](const game::SectionConfig& s) { return s.name != "rigid_bodies" && s.name != "explosives"; });
  EXPECT_TRUE(game::applyOverride(scene, "rigid_bodies.crates=0").ok());
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  return world;
}

// With the default parameters the charge leaves along the aim (issue 35: it used to leave 20
// degrees above it), at throw_speed.
TEST(ExplosivesAim, TheChargeLeavesAlongTheAim) {
  const game::ExplosiveParams params;
  for (const glm::vec3 aim : {glm::vec3(0, 0, -1), glm::vec3(1, 0.3f, 0), glm::vec3(-0.2f, -0.8f, 0.4f)}) {
    const glm::vec3 v = game::throwVelocity(params, aim);
    EXPECT_NEAR(glm::length(v), params.throw_speed, 1e-4f);
    EXPECT_GT(glm::dot(glm::normalize(v), glm::normalize(aim)), 0.99999f);
  }
}

// The aim arc ends where the thrown charge first touches the level: from eight viewpoints around
// the fountain (aimed over it to the paving behind, into the basin, and at the paving in front), the predicted
// contact (depth-map colliders, analytic flight) against the step where Bullet first turns the
// charge's velocity (its mesh shapes, semi-implicit Euler at 120 Hz). The views aim 10 degrees
// beside the centre: a path grazing the statue's 9 cm spire is decided by millimetres between the
// two collision models (the depth maps' texels, Bullet's margin), which no arc can promise.
TEST(ExplosivesAim, TheArcEndsWhereTheThrownChargeFirstTouches) {
  game::World world = bareFountain();
  game::Explosives& explosives = *game::findState<game::Explosives>(world);
  explosives.params.fuse_seconds = 3.0f;
  const glm::vec3 gravity = world.links.gravity;
  const double dt = world.step_seconds;
  double worst = 0.0;
  for (int view = 0; view < 8; ++view) {
    const float yaw = -90.0f + 45.0f * static_cast<float>(view);
    const float radians = glm::radians(yaw + 180.0f);
    world.camera.position = glm::vec3(9.0f * std::cos(radians), 2.6f, 9.0f * std::sin(radians));
    world.camera.yaw_degrees = yaw + 10.0f;
    world.camera.pitch_degrees = view % 3 == 0 ? 12.0f : (view % 3 == 1 ? 2.0f : -14.0f);
    const glm::vec3 forward = engine::cameraForward(world.camera);
    game::AimArc arc;
    game::predictThrow(explosives.params, game::throwOrigin(world.camera.position, forward), forward, gravity,
                       world.links.colliders->parts, arc);
    ASSERT_TRUE(arc.lands) << "view " << view;
    game::playerThrowExplosive(world);
    const game::Charge& charge = *std::find_if(explosives.charges.begin(), explosives.charges.end(),
                                               [](const game::Charge& c) { return c.live; });
    glm::vec3 before = engine::bodyState(*world.links.bodies->physics, charge.body).linear_velocity;
    glm::vec3 contact(std::numeric_limits<float>::quiet_NaN());
    double contact_time = 0.0;
    for (int s = 1; s < 150 && std::isnan(contact.x); ++s) {
      const glm::vec3 position = engine::bodyState(*world.links.bodies->physics, charge.body).position;
      game::stepWorld(world, nullptr);
      const glm::vec3 after = engine::bodyState(*world.links.bodies->physics, charge.body).linear_velocity;
      // Free flight changes the velocity by g dt; anything more is a contact.
      if (glm::length(after - before - gravity * static_cast<float>(dt)) > 0.5f) {
        contact = position;
        contact_time = s * dt;
      }
      before = after;
    }
    ASSERT_FALSE(std::isnan(contact.x)) << "view " << view << ": the charge never touched anything";
    const double miss = glm::length(contact - arc.end);
    worst = std::max(worst, miss);
    std::printf("[ metric ] view %d: arc lands at (%.2f, %.2f, %.2f) after %.3f s, Bullet's first contact at "
                "(%.2f, %.2f, %.2f) in the step ending %.3f s: %.3f m apart\n",
                view, arc.end.x, arc.end.y, arc.end.z, arc.flight_seconds, contact.x, contact.y, contact.z,
                contact_time, miss);
    // Bullet's contact is seen at the start of the step it happens in (its solver turns a charge
    // that would close the gap within the step), so up to a step's flight before the predicted
    // point; measured within 6 cm.
    EXPECT_LT(miss, 0.15) << "view " << view;
    for (int s = 0; s < 240; ++s) game::stepWorld(world, nullptr);  // the fuse runs out; the next throw
  }
  std::printf("[ metric ] the aim arc's worst miss over 8 throws: %.3f m\n", worst);
}

}  // namespace

// ---- the same explosives in the blob monster's street ------------------------------------------

#include "game/world/blob_monster.hpp"

namespace {

// A charge lobbed from the scene's start view lands by the monster and blows it apart: its
// particles are pushed by the shared law, the program switches to reassemble, and the body
// stays finite with every particle kept.
TEST(ExplosivesInTheBlobLevel, AChargeBlowsTheMonsterApartAndItReassembles) {
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile(game::contentDir() / "scenes" / "blob_monster.json", scene).ok());
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  for (int s = 0; s < 400; ++s) game::stepWorld(world, nullptr);  // it emerges and balls up
  game::BlobMonster& blob = *game::findState<game::BlobMonster>(world);
  const std::size_t particles = blob.world.particles.position.size();
  world.camera.pitch_degrees += 20.0f;  // a lob toward the monster: the charge leaves along the aim
  game::playerThrowExplosive(world);
  std::size_t pushed = 0;
  bool reassembling = false;
  for (int s = 0; s < 240; ++s) {
    game::stepWorld(world, nullptr);
    ASSERT_EQ(world.nonfinite_state, "") << "step " << s;
    pushed += blob.blasted_particles;
    if (blob.machine.state >= 0 &&
        blob.program.states[static_cast<std::size_t>(blob.machine.state)].name.find("reassemble") != std::string::npos)
      reassembling = true;
  }
  std::printf("[ metric ] blob particles pushed by the blast: %zu of %zu\n", pushed, particles);
  EXPECT_EQ(game::findState<game::Explosives>(world)->detonated, 1u);
  EXPECT_GT(pushed, particles / 4);
  EXPECT_TRUE(reassembling);
  EXPECT_EQ(blob.world.particles.position.size(), particles);
  EXPECT_EQ(blob.error, "");
}

}  // namespace
