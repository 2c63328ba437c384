// The blob body: hard cases stay finite and sane, determinism, thread-count invariance, the
// exchange of momentum with rigid bodies, the program checks and the state machine.
#include "blob_test_level.hpp"

#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>

namespace {

using fluid::BlobBehaviour;
using fluid::BlobBehaviourKind;

void expectSane(const fluid::BlobWorld& w, std::size_t n) {
  EXPECT_EQ(w.particles.size(), n);
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
  EXPECT_LE(fluid::blobMaxSpeed(w.particles.velocity), 1.0001f * w.params.max_speed);
}

TEST(BlobBody, RestingBlobStaysOneStillBody) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  blobtest::runUntilGoal(w, BlobBehaviour{}, 2.0f);
  const float radius = fluid::blobBodyRadius(w.params);
  std::printf("[blob] idle: shape error %.3f body radii after 2 s\n",
              fluid::blobShapeError(w.particles.position, w.particles.rest) / radius);
  EXPECT_LT(fluid::blobShapeError(w.particles.position, w.particles.rest), 0.1f * radius);
  EXPECT_LT(fluid::blobMaxSpeed(w.particles.velocity), 0.2f);
  EXPECT_GE(blobtest::minDistance(w, 0), -0.01f * w.params.spacing);
}

TEST(BlobBody, RejectsBadParamsAndNonFiniteState) {
  fluid::BlobWorld w;
  w.params.spacing = -1.0f;
  fluid::BlobStatus st = fluid::initBlob(w, glm::vec3(0.0f));
  EXPECT_NE(st.error.find("spacing = -1"), std::string::npos) << st.error;
  w.params = fluid::BlobParams{};
  w.params.particle_count = 100;
  ASSERT_TRUE(fluid::initBlob(w, glm::vec3(0.0f)).ok());
  w.particles.velocity[7].x = std::nanf("");
  st = fluid::stepBlob(w);
  EXPECT_NE(st.error.find("particle 7"), std::string::npos) << st.error;
  EXPECT_TRUE(std::isnan(w.particles.velocity[7].x));  // left untouched
  EXPECT_EQ(fluid::blastBlob(w, blobtest::blastOfSpeed(w, glm::vec3(std::nanf("")), 10.0f, 1.0f)), 0u);
}

TEST(BlobBody, BlastExactlyAtAParticleStaysFinite) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const std::size_t n = w.particles.size();
  EXPECT_GT(fluid::blastBlob(w, blobtest::blastOfSpeed(w, w.particles.position[123], 30.0f, 1.0f)), 1u);
  expectSane(w, n);
  EXPECT_GT(glm::length(w.particles.velocity[123]), 29.0f);  // full strength (the core's), straight up
  for (int s = 0; s < 60; ++s) ASSERT_TRUE(fluid::stepBlob(w).ok());
  expectSane(w, n);
}

// The game's blasts (fluid/core/blast.hpp) push the blob by the same law as the water and the crates:
// each particle gains exactly blastVelocityChange with its cross-section over mass; a bad blast does nothing.
TEST(BlobBody, GameBlastFollowsTheSharedLaw) {
  fluid::BlobWorld w = blobtest::restingBlob();
  const fluid::Blast blast{glm::vec3(0.5f, 0.4f, 0.0f), 60.0f, 0.25f, 4.0f};
  const float r = fluid::blobParticleRadius(w.params);
  const float area_over_mass = 3.14159265f * r * r / fluid::blobParticleMass(w.params);
  const std::vector<glm::vec3> x = w.particles.position;
  EXPECT_EQ(fluid::blastBlob(w, blast), w.particles.size());  // all within reach
  for (std::size_t i = 0; i < x.size(); i += 97) {
    const glm::vec3 dv = fluid::blastVelocityChange(blast, x[i], area_over_mass, w.params.max_speed);
    EXPECT_NEAR(glm::length(w.particles.velocity[i] - dv), 0.0f, 1e-5f) << i;
  }
  // Nearer particles are pushed harder (the 1/r^2 falloff outside the core).
  EXPECT_GT(glm::length(w.particles.velocity[0]), 0.0f);
  fluid::Blast bad = blast;
  bad.reach = 0.1f;  // below core_radius: validateBlast rejects it
  const std::vector<glm::vec3> v = w.particles.velocity;
  EXPECT_EQ(fluid::blastBlob(w, bad), 0u);
  EXPECT_EQ(w.particles.velocity, v);
  fluid::Blast at_particle = blast;
  at_particle.centre = w.particles.position[10];  // exactly at a particle: up, capped, finite
  fluid::blastBlob(w, at_particle);
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
  EXPECT_LE(fluid::blobMaxSpeed(w.particles.velocity), w.params.max_speed * 1.0001f);
}

TEST(BlobBody, TenBlastsInOneStepStayBounded) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const std::size_t n = w.particles.size();
  for (int k = 0; k < 10; ++k) fluid::blastBlob(w, blobtest::blastOfSpeed(w, glm::vec3(0.0f, 0.3f, 0.0f), 60.0f, 1.5f));
  expectSane(w, n);
  EXPECT_GT(fluid::blobMaxSpeed(w.particles.velocity), 100.0f);
  for (int s = 0; s < 120; ++s) ASSERT_TRUE(fluid::stepBlob(w).ok());
  expectSane(w, n);
  EXPECT_GE(blobtest::minDistance(w, 0), -0.01f * w.params.spacing);
}

TEST(BlobBody, FlungAt100MetresPerSecondAtAThinWallNoneEndsInsideOrBeyond) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const float thickness = 0.05f;  // thinner than one particle spacing
  w.colliders.push_back(blobtest::wall(1.5f, thickness));
  const std::size_t n = w.particles.size();
  for (glm::vec3& v : w.particles.velocity) v = glm::vec3(100.0f, 0.0f, 0.0f);
  fluid::BlobStepStats stats;
  std::size_t swept = 0;
  for (int s = 0; s < 60; ++s) {
    ASSERT_TRUE(fluid::stepBlob(w, &stats).ok());
    swept += stats.swept;
    EXPECT_GE(blobtest::minDistance(w, 1), -0.01f * w.params.spacing) << "step " << s;
    float far = -1e30f;
    for (const glm::vec3& x : w.particles.position) far = std::max(far, x.x);
    EXPECT_LT(far, 1.5f) << "a particle crossed the wall, step " << s;
  }
  EXPECT_GT(swept, 0u);  // the swept sampling did the work
  expectSane(w, n);
}

TEST(BlobBody, TargetInsideAWallStaysOutsideAndFinite) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  w.colliders.push_back(blobtest::wall(1.5f, 1.0f));
  const std::size_t n = w.particles.size();
  for (BlobBehaviourKind kind : {BlobBehaviourKind::chase, BlobBehaviourKind::tentacles}) {
    BlobBehaviour b;
    b.kind = kind;
    b.speed = 3.0f;
    blobtest::runUntilGoal(w, b, 2.0f, glm::vec3(2.0f, 0.5f, 0.0f), false);  // inside the wall
    expectSane(w, n);
    EXPECT_GE(blobtest::minDistance(w, 1), -0.01f * w.params.spacing);
  }
  BlobBehaviour coat;  // a coat point deep inside the wall: the layer lands on its nearest face
  coat.kind = BlobBehaviourKind::coat_wall;
  coat.point = glm::vec3(2.0f, 1.0f, 0.0f);
  coat.wall_collider = 1;
  blobtest::runUntilGoal(w, coat, 2.0f, glm::vec3(0.0f), false);
  expectSane(w, n);
  EXPECT_GE(blobtest::minDistance(w, 1), -0.01f * w.params.spacing);
}

TEST(BlobBody, SqueezedIntoACornerByCratesStaysSane) {
  fluid::BlobWorld w = blobtest::restingBlob();
  // Two crates close in on the body at 2 m/s, pressing it into the corner of two walls; the walls
  // come last in the list, so where a crate overlaps a wall the particle ends outside the wall.
  for (glm::vec3 from : {glm::vec3(-1.6f, 0.5f, 0.0f), glm::vec3(0.0f, 0.5f, -1.6f)}) {
    fluid::BlobCollider crate = blobtest::collider(std::make_shared<fluid::BoxShape>(glm::vec3(0.5f)), from);
    crate.pose.linear_velocity = -2.0f * glm::normalize(glm::vec3(from.x, 0.0f, from.z));
    w.colliders.push_back(crate);
  }
  w.colliders.push_back(blobtest::ground());
  w.colliders.push_back(blobtest::wall(0.8f, 0.5f));  // x >= 0.8
  fluid::BlobCollider back_wall = blobtest::collider(std::make_shared<fluid::BoxShape>(glm::vec3(3.0f, 2.0f, 0.25f)),
                                                     glm::vec3(0.0f, 1.0f, 1.05f));  // z >= 0.8
  w.colliders.push_back(back_wall);
  const std::size_t n = w.particles.size();
  float pushed = 0.0f;            // momentum the crates took from the body (N s)
  for (int s = 0; s < 90; ++s) {  // 1.5 s: the crates stop 0.4 m short of the walls
    for (int c = 0; c < 2; ++c) {
      const glm::vec3 p = w.colliders[c].pose.translation;
      if ((c == 0 ? p.x : p.z) > 0.4f - 0.5f) w.colliders[c].pose.linear_velocity = glm::vec3(0.0f);
    }
    ASSERT_TRUE(fluid::stepBlob(w).ok());
    pushed += glm::length(w.colliders[0].impulse) + glm::length(w.colliders[1].impulse);
  }
  expectSane(w, n);
  EXPECT_LT(fluid::blobMaxSpeed(w.particles.velocity), 20.0f);
  for (std::size_t c = 2; c < 5; ++c) EXPECT_GE(blobtest::minDistance(w, c), -0.01f * w.params.spacing) << c;
  EXPECT_GT(pushed, 10.0f);  // the body pushed back on the crates
  float top = -1e30f;
  for (const glm::vec3& x : w.particles.position) top = std::max(top, x.y);
  std::printf("[blob] corner: squeezed up to %.2f m high, crates took %.0f N s, max speed %.2f m/s\n", top, pushed,
              fluid::blobMaxSpeed(w.particles.velocity));
}

// A crate as wide and tall as the wall driven through the resting body 0.3 m into the wall (the body
// has no way round it), listed after the level as the game lists them (level parts, then the crates
// near the body). Returns the largest x any particle ends at (the wall's face is x = 0.8).
float farthestParticleAfterCrateDrive(bool mark_level) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  w.colliders.push_back(blobtest::wall(0.8f, 0.5f));  // 0.8 <= x <= 1.3
  for (fluid::BlobCollider& c : w.colliders) c.level = mark_level;
  fluid::BlobCollider crate =
      blobtest::collider(std::make_shared<fluid::BoxShape>(glm::vec3(0.5f, 2.0f, 3.0f)), glm::vec3(-1.6f, 1.0f, 0.0f));
  crate.pose.linear_velocity = glm::vec3(2.0f, 0.0f, 0.0f);
  w.colliders.push_back(crate);
  const std::size_t n = w.particles.size();
  for (int s = 0; s < 90; ++s) {  // the crate's face reaches x = 1.1, 0.3 m into the wall, then stops
    if (w.colliders[2].pose.translation.x >= 0.6f) w.colliders[2].pose.linear_velocity = glm::vec3(0.0f);
    EXPECT_TRUE(fluid::stepBlob(w).ok());
  }
  expectSane(w, n);
  float farthest = -1e30f;
  for (const glm::vec3& x : w.particles.position) farthest = std::max(farthest, x.x);
  return farthest;
}

TEST(BlobBody, LevelCollidersWinOverACrateListedAfterThem) {
  const float skin = 0.01f * fluid::BlobParams{}.spacing;
  const float marked = farthestParticleAfterCrateDrive(true);
  const float unmarked = farthestParticleAfterCrateDrive(false);
  std::printf(
      "[blob] crate driven 0.3 m into a wall at x = 0.8: farthest particle x = %.3f m (level marked), %.3f m "
      "(list order)\n",
      marked, unmarked);
  EXPECT_LE(marked, 0.8f + skin);  // the level is resolved last: every particle ends on the near side
  // Resolved in list order, the crate comes last and pushes particles out of its far face, inside the
  // wall, which then pushes them out of its own far face: through the wall (x > 1.3).
  EXPECT_GT(unmarked, 1.3f);
}

// Runs a behaviour mix for `steps` and returns the positions and velocities as bytes.
std::vector<glm::vec3> scriptedRun(std::uint64_t seed, int steps) {
  fluid::BlobWorld w;
  w.params.seed = seed;
  EXPECT_TRUE(fluid::initBlob(w, glm::vec3(0.0f, 0.45f, 0.0f)).ok());
  w.colliders.push_back(blobtest::ground());
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::tentacles;
  fluid::startBlobBehaviour(w, b, glm::vec3(3.0f, 1.0f, 0.0f));
  for (int s = 0; s < steps; ++s) {
    if (s == steps / 2) fluid::blastBlob(w, blobtest::blastOfSpeed(w, w.particles.position[5], 20.0f, 1.0f));
    fluid::updateBlobBehaviour(w, b, glm::vec3(3.0f, 1.0f, 0.0f), w.params.step);
    EXPECT_TRUE(fluid::stepBlob(w).ok());
  }
  std::vector<glm::vec3> out = w.particles.position;
  out.insert(out.end(), w.particles.velocity.begin(), w.particles.velocity.end());
  return out;
}

TEST(BlobBody, DeterministicAndThreadCountInvariant) {
  std::vector<glm::vec3> one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = scriptedRun(7, 40);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = scriptedRun(7, 40);
  }
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(glm::vec3)), 0);
  const std::vector<glm::vec3> other = scriptedRun(8, 40);
  EXPECT_NE(std::memcmp(one.data(), other.data(), one.size() * sizeof(glm::vec3)), 0);  // the seed matters
}

TEST(BlobBody, CrateImpulseBalancesTheParticlesMomentum) {
  fluid::BlobWorld w;
  w.params.gravity = glm::vec3(0.0f);
  w.params.drag = 0.0f;  // no external force but the crate
  ASSERT_TRUE(fluid::initBlob(w, glm::vec3(0.0f), glm::vec3(1.0f)).ok());
  fluid::BlobCollider crate =
      blobtest::collider(std::make_shared<fluid::BoxShape>(glm::vec3(0.2f)), glm::vec3(-1.0f, 0.0f, 0.0f));
  crate.pose.linear_velocity = glm::vec3(10.0f, 0.0f, 0.0f);  // thrown through the blob
  w.colliders.push_back(crate);
  const float m = fluid::blobParticleMass(w.params);
  auto momentum = [&] {
    glm::dvec3 p(0.0);
    for (const glm::vec3& v : w.particles.velocity) p += glm::dvec3(v) * double(m);
    return p;
  };
  glm::dvec3 given(0.0);
  for (int s = 0; s < 12; ++s) {
    ASSERT_TRUE(fluid::stepBlob(w).ok());
    given -= glm::dvec3(w.colliders[0].impulse);  // what the crate gave the particles
  }
  const glm::dvec3 p = momentum();
  EXPECT_GT(p.x, 10.0);  // the crate dented the blob: it pushed particles along +x
  EXPECT_NEAR(p.x, given.x, 1e-3 * std::abs(given.x));
  EXPECT_NEAR(p.y, given.y, 1e-3 * std::abs(given.x));
  EXPECT_LT(w.colliders[0].impulse.x, 0.0f);  // ... and the blob pushes back on the crate
}

TEST(BlobProgram, ValidationNamesTheStateKeyAndValue) {
  fluid::BlobProgram p;
  p.states.resize(2);
  p.states[0].name = "rise";
  p.states[0].behaviour.kind = BlobBehaviourKind::emerge;
  p.states[0].triggers.push_back({fluid::BlobTriggerKind::goal_reached, 0.0f, "", "bal", -1});
  p.states[1].name = "ball";
  fluid::BlobParams params;
  fluid::BlobStatus st = fluid::validateBlobProgram(p, params);
  EXPECT_NE(st.error.find("'rise'"), std::string::npos) << st.error;
  EXPECT_NE(st.error.find("'bal'"), std::string::npos) << st.error;
  p.states[0].triggers[0].next = "ball";
  EXPECT_TRUE(fluid::validateBlobProgram(p, params).ok());
  EXPECT_EQ(p.states[0].triggers[0].next_index, 1);
  p.states[1].behaviour.speed = -2.0f;
  st = fluid::validateBlobProgram(p, params);
  EXPECT_NE(st.error.find("state 'ball': speed = -2"), std::string::npos) << st.error;
  p.states[1].behaviour.speed = 1.0f;
  p.states[1].behaviour.kind = BlobBehaviourKind::tentacles;
  p.states[1].behaviour.tentacles = 16;
  p.states[1].behaviour.tentacle_particles = 100;
  st = fluid::validateBlobProgram(p, params);
  EXPECT_NE(st.error.find("more than half"), std::string::npos) << st.error;
  fluid::BlobBehaviourKind k;
  EXPECT_FALSE(fluid::parseBlobBehaviour("dance", k));
  EXPECT_TRUE(fluid::parseBlobBehaviour("coat_wall", k));
  EXPECT_EQ(k, BlobBehaviourKind::coat_wall);
}

TEST(BlobProgram, MachineRunsASequenceAndReassemblesAfterABlast) {
  fluid::BlobProgram p;
  p.states.resize(3);
  p.states[0].name = "ball";
  p.states[0].behaviour.kind = BlobBehaviourKind::ball;
  p.states[0].triggers.push_back({fluid::BlobTriggerKind::blasted, 0.0f, "", "reassemble", -1});
  p.states[0].triggers.push_back({fluid::BlobTriggerKind::goal_reached, 0.0f, "", "idle", -1});
  p.states[1].name = "idle";
  p.states[1].triggers.push_back({fluid::BlobTriggerKind::blasted, 0.0f, "", "reassemble", -1});
  p.states[1].triggers.push_back({fluid::BlobTriggerKind::event, 0.0f, "go", "ball", -1});
  p.states[2].name = "reassemble";
  p.states[2].behaviour.kind = BlobBehaviourKind::reassemble;
  p.states[2].triggers.push_back({fluid::BlobTriggerKind::goal_reached, 0.0f, "", "idle", -1});
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  ASSERT_TRUE(fluid::validateBlobProgram(p, w.params).ok());
  fluid::BlobMachine m;
  fluid::BlobInputs in;
  std::vector<int> visited;
  for (int s = 0; s < 600 && visited.size() < 4; ++s) {
    in.blasted = false;
    if (m.state == 1 && visited.size() == 2) {  // in idle after the ball: blow it up
      in.blasted =
          fluid::blastBlob(w, blobtest::blastOfSpeed(w, fluid::blobCentroid(w.particles.position), 10.0f, 1.5f)) > 0;
    }
    const int before = m.state;
    fluid::stepBlobMachine(p, m, w, in);
    ASSERT_TRUE(fluid::stepBlob(w).ok());
    if (m.state != before) visited.push_back(m.state);
  }
  EXPECT_EQ(visited, (std::vector<int>{0, 1, 2, 1}));  // ball -> idle -> (blast) reassemble -> idle
}

}  // namespace
