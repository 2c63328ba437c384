// The `blob` effect in a World (no GL): the blob_monster scene builds the monster from its section
// and program, it rises out of the sewer onto the street (baked colliders), a blast sends it to
// reassemble, catching the player resets the round, and bad programs are errors naming file, key, value.
#include "engine/camera/camera.hpp"
#include "game/explosives/explosives.hpp"
#include "game/paths.hpp"
#include "game/world/blob_monster.hpp"
#include "game/world/rigid_bodies.hpp"
#include "game/world/world.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

game::World blobWorld(const std::string& program = {}) {
  game::SceneConfig scene;
  game::SceneStatus st = game::loadSceneFile(game::scenesDir() / "blob_monster.json", scene);
  EXPECT_TRUE(st.ok()) << st.error;
  if (!program.empty()) {
    st = game::applyOverride(scene, "blob.program=" + program);
    EXPECT_TRUE(st.ok()) << st.error;
  }
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  return world;
}

std::string buildError(const std::string& program_text) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "fluiddemo_bad.program.json";
  std::ofstream(file) << program_text;
  game::SceneConfig scene;
  EXPECT_TRUE(game::loadSceneFile(game::scenesDir() / "blob_monster.json", scene).ok());
  EXPECT_TRUE(game::applyOverride(scene, "blob.program=" + file.string()).ok());
  game::World world;
  std::string error;
  EXPECT_FALSE(game::buildWorld(scene, game::contentDir(), world, error));
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  return error;
}

const std::string& stateName(const game::BlobMonster& blob) { return blob.program.states[blob.machine.state].name; }

void steps(game::World& world, int n) {
  for (int i = 0; i < n; ++i) game::stepWorld(world, nullptr);
}

TEST(BlobEffect, RisesOutOfTheSewerOntoTheStreet) {
  game::World world = blobWorld();
  game::BlobMonster* blob = game::findState<game::BlobMonster>(world);
  ASSERT_NE(blob, nullptr);
  EXPECT_EQ(blob->world.particles.size(), 1000u);
  EXPECT_EQ(blob->level_colliders, 7u);  // street, sewer, wall and the four building fronts, baked from the models
  EXPECT_LT(fluid::blobCentroid(blob->world.particles.position).y, 0.0f);  // starts in the pipe
  steps(world, 60);
  EXPECT_EQ(stateName(*blob), "emerge");
  steps(world, 8 * 60);  // the program leaves emerge on its goal, at the latest after 8 s
  EXPECT_NE(stateName(*blob), "emerge");
  const glm::vec3 c = fluid::blobCentroid(blob->world.particles.position);
  std::printf("[blob] game: after 9 s state %s, centroid (%.2f, %.2f, %.2f)\n", stateName(*blob).c_str(), c.x, c.y,
              c.z);
  EXPECT_GT(c.y, 0.2f);  // out of the pipe, on the street
  EXPECT_EQ(blob->world.particles.size(), 1000u);
  EXPECT_TRUE(world.nonfinite_state.empty()) << world.nonfinite_state;
  EXPECT_EQ(world.failures.count, 0u) << world.failures.first;
}

TEST(BlobEffect, ABlastThrowsParticlesAndStartsReassembly) {
  game::World world = blobWorld();
  game::BlobMonster* blob = game::findState<game::BlobMonster>(world);
  ASSERT_NE(blob, nullptr);
  steps(world, 6 * 60);
  const glm::vec3 c = fluid::blobCentroid(blob->world.particles.position);
  // A charge placed beside the body with a one-step fuse: the explosives effect publishes its
  // blast (EffectLinks::blasts) in the step it goes off, and the blob applies it in the same step.
  game::Explosives* explosives = game::findState<game::Explosives>(world);
  ASSERT_NE(explosives, nullptr);
  explosives->params.fuse_seconds = 1.0f / 120.0f;
  explosives->params.throw_speed = 0.0f;
  explosives->params.impulse_at_1m = 60.0f;
  explosives->params.core_radius = 0.25f;
  explosives->params.reach = 4.0f;
  game::throwExplosive(*explosives, *world.links.bodies->physics, c + glm::vec3(0.3f, 0.0f, 0.0f), {1, 0, 0});
  steps(world, 1);
  ASSERT_EQ(explosives->detonated, 1u);
  EXPECT_GT(blob->blasted_particles, 500u);
  EXPECT_EQ(stateName(*blob), "reassemble");
  EXPECT_GT(fluid::blobMaxSpeed(blob->world.particles.velocity), 2.0f);
  steps(world, 60);
  EXPECT_TRUE(world.nonfinite_state.empty()) << world.nonfinite_state;
}

// The catch is seen (issue 35 item 2): the goo grabs the camera and pulls it in, facing it, the
// screen tints, a banner gives the round's time, the round counter goes up, and the round resets.
TEST(BlobEffect, CatchingThePlayerPullsTheCameraInTintsTheScreenAndCountsTheRound) {
  game::World world = blobWorld();
  game::BlobMonster* blob = game::findState<game::BlobMonster>(world);
  ASSERT_NE(blob, nullptr);
  game::Effect* effect = nullptr;
  for (const auto& e : world.effects)
    if (e->name() == "blob") effect = e.get();
  ASSERT_NE(effect, nullptr);
  steps(world, 4 * 60);
  EXPECT_EQ(blob->round, 1);
  EXPECT_NEAR(blob->round_seconds, 4.0, 1e-9);
  EXPECT_EQ(blob->tint.a, 0.0f);
  EXPECT_TRUE(effect->hud().banner.empty());
  EXPECT_NE(effect->hud().line.find("round 1"), std::string::npos) << effect->hud().line;
  int chase = -1;
  for (std::size_t k = 0; k < blob->program.states.size(); ++k)
    if (blob->program.states[k].behaviour.kind == fluid::BlobBehaviourKind::chase) chase = static_cast<int>(k);
  ASSERT_GE(chase, 0);
  fluid::enterBlobState(blob->program, blob->machine, blob->world, chase, blob->target);
  const glm::vec3 start_eye = world.camera.position;
  const glm::vec3 c = fluid::blobCentroid(blob->world.particles.position);
  world.camera.position = glm::vec3(c.x + 0.85f, 1.7f, c.z);  // the player walks within its reach
  world.camera.pitch_degrees = 0.0f;                          // looking ahead: the goo is below the view
  const auto gooDistance = [&] {
    return glm::length(world.camera.position - fluid::blobCentroid(blob->world.particles.position));
  };
  const auto gooOffView = [&] {  // angle (deg) between the view and the direction to the goo
    const glm::vec3 to = glm::normalize(fluid::blobCentroid(blob->world.particles.position) - world.camera.position);
    return glm::degrees(std::acos(std::clamp(glm::dot(to, engine::cameraForward(world.camera)), -1.0f, 1.0f)));
  };
  const float before = gooDistance(), off_before = gooOffView();
  steps(world, 2);
  EXPECT_EQ(blob->catches, 1);
  EXPECT_GT(blob->caught_timer, 0.0f);
  const std::string banner = effect->hud().banner;
  EXPECT_NE(banner.find("CAUGHT"), std::string::npos) << banner;
  EXPECT_NE(banner.find("round 1 lasted 4.0 s"), std::string::npos) << banner;
  steps(world, 30);  // half a second into the catch
  const float during = gooDistance(), off_during = gooOffView(), tint = blob->tint.a;
  std::printf(
      "[blob] catch: camera %.2f m from the goo's centroid -> %.2f m after 0.5 s, the goo %.0f deg -> %.0f deg off "
      "the view; screen tint alpha %.2f; banner '%s'\n",
      before, during, off_before, off_during, tint, banner.c_str());
  EXPECT_LT(during, before - 0.25f);  // pulled in: to 1.1 m of the goo's centre (blob.cpp grab)
  EXPECT_LT(during, 1.25f);
  EXPECT_LT(off_during, 20.0f);
  EXPECT_GT(off_before, 45.0f);
  EXPECT_GE(tint, 0.5f);
  steps(world, static_cast<int>(blob->params.caught_seconds * 60.0f) - 30 + 2);
  EXPECT_EQ(blob->caught_timer, 0.0f);
  EXPECT_EQ(blob->tint.a, 0.0f);
  EXPECT_TRUE(effect->hud().banner.empty());
  EXPECT_LT(fluid::blobCentroid(blob->world.particles.position).y, 0.0f);  // back in the pipe
  EXPECT_EQ(world.camera.position, start_eye);                             // the player back at the start
  EXPECT_EQ(stateName(*blob), "emerge");
  EXPECT_EQ(blob->round, 2);
  EXPECT_NE(effect->hud().line.find("round 2"), std::string::npos) << effect->hud().line;
  std::printf("[blob] rounds: round %d after one catch, HUD '%s'\n", blob->round, effect->hud().line.c_str());
}

// The street is closed (issue 35 item 3): building fronts stand around it (baked colliders and
// Bullet meshes), the crates start and stay inside them, and the monster, hunting a player in the
// street's far corner, keeps inside the camera's bounds and never enters a front.
TEST(BlobEffect, TheHuntKeepsToTheClosedStreet) {
  game::World world = blobWorld();
  game::BlobMonster* blob = game::findState<game::BlobMonster>(world);
  game::RigidBodies* bodies = game::findState<game::RigidBodies>(world);
  ASSERT_NE(blob, nullptr);
  ASSERT_NE(bodies, nullptr);
  steps(world, 4 * 60);
  int chase = -1;
  for (std::size_t k = 0; k < blob->program.states.size(); ++k)
    if (blob->program.states[k].behaviour.kind == fluid::BlobBehaviourKind::chase) chase = static_cast<int>(k);
  ASSERT_GE(chase, 0);
  fluid::enterBlobState(blob->program, blob->machine, blob->world, chase, blob->target);
  const glm::vec3 lo = world.camera.bounds_min;
  world.camera.position = glm::vec3(lo.x, 1.7f, lo.z);  // the player in the street's far corner
  float worst_x = 0.0f, worst_z = 0.0f, deepest = 1e30f;
  int hunted = 0;
  for (; hunted < 25 * 60 && blob->catches == 0; ++hunted) {
    steps(world, 1);
    for (const glm::vec3& x : blob->world.particles.position)
      worst_x = std::min(worst_x, x.x), worst_z = std::min(worst_z, x.z);
  }
  for (std::size_t c = 3; c < blob->level_colliders; ++c)  // the four fronts follow street, sewer, wall
    for (const glm::vec3& x : blob->world.particles.position) {
      fluid::ColliderSample sample;
      const glm::vec3 local = fluid::toColliderSpace(blob->world.colliders[c].pose, x);
      blob->world.colliders[c].shape->query({&local, 1}, {&sample, 1});
      if (sample.valid) deepest = std::min(deepest, sample.distance);
    }
  const glm::vec3 c = fluid::blobCentroid(blob->world.particles.position);
  std::printf(
      "[blob] closed street: hunting a player at (%.1f, %.1f) the goo reached (%.2f, %.2f), caught %d after %.1f s; "
      "its furthest particle x %.2f, z %.2f (fronts' faces at x -7, z -9.5); deepest into a front %.3f m\n",
      lo.x, lo.z, c.x, c.z, blob->catches, hunted / 60.0, worst_x, worst_z, deepest);
  EXPECT_EQ(blob->catches, 1);  // it reached him in the corner
  EXPECT_GE(c.x, lo.x);
  EXPECT_GE(c.z, lo.z);
  EXPECT_GE(worst_x, -7.0f - 0.01f * blob->params.spacing);  // a particle may touch a face, not cross it
  EXPECT_GE(worst_z, -9.5f - 0.01f * blob->params.spacing);
  EXPECT_GE(deepest, -0.01f * blob->params.spacing);
  for (const engine::BodyState& b : bodies->current) {
    EXPECT_GT(b.position.x, -7.0f);
    EXPECT_LT(b.position.x, 7.0f);
    EXPECT_GT(b.position.z, -9.5f);
    EXPECT_LT(b.position.z, 6.8f);
  }
}

TEST(BlobEffect, ACrateDroppedOnItAndTheBlobPushEachOther) {
  game::World world = blobWorld();
  game::BlobMonster* blob = game::findState<game::BlobMonster>(world);
  game::RigidBodies* bodies = game::findState<game::RigidBodies>(world);
  ASSERT_NE(blob, nullptr);
  ASSERT_NE(bodies, nullptr);
  steps(world, 4 * 60);  // out of the pipe
  const glm::vec3 c = fluid::blobCentroid(blob->world.particles.position);
  game::throwCrate(*bodies, c + glm::vec3(0.0f, 2.5f, 0.0f), glm::vec3(0.0f, -1.0f, 0.0f));
  const engine::BodyId crate = bodies->crates.back();
  float upward = 0.0f;  // momentum the particles gave the thrown crate (N s, +y)
  int coupled = 0;
  for (int i = 0; i < 60; ++i) {
    steps(world, 1);
    for (std::size_t k = 0; k < blob->crate_of_collider.size(); ++k) {
      if (bodies->crates[static_cast<std::size_t>(blob->crate_of_collider[k])] != crate) continue;
      ++coupled;
      upward += blob->world.colliders[blob->level_colliders + k].impulse.y;  // what the particles lost to it
    }
  }
  const engine::BodyState after = engine::bodyState(*bodies->physics, crate);
  std::printf(
      "[blob] game: a crate dropped on the blob: coupled %d of 60 steps, the goo lost %.2f N s upward to it (before "
      "the cap; capped %llu times), crate speed %.2f m/s after 1 s\n",
      coupled, upward, static_cast<unsigned long long>(blob->crate_forces_capped), glm::length(after.linear_velocity));
  EXPECT_LT(glm::length(after.linear_velocity), 5.0f) << "the goo does not fire the crate away";
  EXPECT_GT(coupled, 10);
  EXPECT_GT(upward, 0.0f) << "the goo pushes the crate up";
  EXPECT_LT(fluid::blobCentroid(blob->world.particles.position).y, c.y + 0.5f);
  EXPECT_TRUE(world.nonfinite_state.empty()) << world.nonfinite_state;
  EXPECT_EQ(blob->world.particles.size(), 1000u);
}

game::World blobWorldWith(const std::vector<std::string>& overrides) {
  game::SceneConfig scene;
  EXPECT_TRUE(game::loadSceneFile(game::scenesDir() / "blob_monster.json", scene).ok());
  for (const std::string& o : overrides) {
    const game::SceneStatus st = game::applyOverride(scene, o);
    EXPECT_TRUE(st.ok()) << st.error;
  }
  game::World world;
  std::string error;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  return world;
}

// blob.async (Janisz §3.2.6): the goo drawn at frame N is what the synchronous mesher gives for
// frame N-1's particles and tentacles, bit for bit, the tentacles' (u, v) included (frame 0: its own).
// A program that grows tentacles at once, so the tentacle texturing pass runs on the worker's copy.
TEST(BlobEffect, AsyncDrawsThePreviousFramesGooBitForBit) {
  const std::filesystem::path program = std::filesystem::temp_directory_path() / "fluiddemo_async.program.json";
  std::ofstream(program) << R"({"initial": "tentacles", "states": [{"name": "tentacles", "behaviour": "tentacles",
      "tentacles": 4, "tentacle_particles": 30, "tentacle_length": 1.2}]})";
  game::World sync_world = blobWorldWith({"blob.program=" + program.string(), "blob.async=false"});
  game::World async_world = blobWorldWith({"blob.program=" + program.string(), "blob.async=true"});
  const game::BlobMonster& sync_blob = *game::findState<game::BlobMonster>(sync_world);
  const game::BlobMonster& async_blob = *game::findState<game::BlobMonster>(async_world);
  fluid::SurfaceMesh previous;
  int textured = 0;
  for (int frame = 0; frame < 120; ++frame) {
    game::stepWorld(sync_world, nullptr);
    game::stepWorld(async_world, nullptr);
    game::meshWorld(sync_world, nullptr);
    game::meshWorld(async_world, nullptr);
    ASSERT_EQ(async_world.failures.count, 0u) << async_world.failures.first;
    const fluid::SurfaceMesh& expected = frame == 0 ? sync_blob.job.mesh : previous;
    const fluid::SurfaceMesh& got = async_blob.job.mesh;
    ASSERT_FALSE(got.indices.empty()) << "frame " << frame;
    ASSERT_EQ(test_support::meshBitsDiffer(got, expected), "") << "frame " << frame;
    bool has_u = false;
    for (const glm::vec4& a : got.attributes) has_u = has_u || (a.z > 0.5f && a.x > 0.0f);
    textured += has_u ? 1 : 0;
    EXPECT_GT(async_blob.job.worker_ms, 0.0) << "frame " << frame;
    EXPECT_EQ(sync_blob.job.worker_ms, 0.0);
    previous = sync_blob.job.mesh;
  }
  EXPECT_GE(textured, 100) << "the tentacles' u is on the surface in almost every frame";
  std::filesystem::remove(program);
}

TEST(BlobEffect, BadProgramsNameFileKeyAndValue) {
  std::string e = buildError(R"({"states": [{"name": "a", "behaviour": "dance"}]})");
  EXPECT_NE(e.find("states[0].behaviour = \"dance\""), std::string::npos) << e;
  e = buildError(R"({"states": [{"name": "a", "behaviour": "ball", "triggers": [{"when": "after_seconds",
                 "value": 1, "next": "b"}]}]})");
  EXPECT_NE(e.find("next = 'b' names no state"), std::string::npos) << e;
  e = buildError(R"({"states": [{"name": "a", "behaviour": "ball", "speed": -3}]})");
  EXPECT_NE(e.find("speed"), std::string::npos) << e;
  EXPECT_NE(e.find("-3"), std::string::npos) << e;
  e = buildError(R"({"states": [{"name": "a", "behaviour": "coat_wall", "wall": "nowall"}]})");
  EXPECT_NE(e.find("states[0].wall = \"nowall\""), std::string::npos) << e;
  e = buildError(R"({"states": [{"name": "a", "behaviour": "ball", "colour": 1}]})");
  EXPECT_NE(e.find("states[0].colour = 1: unknown key"), std::string::npos) << e;
  e = buildError("{not json");
  EXPECT_NE(e.find("invalid JSON"), std::string::npos) << e;
}

TEST(BlobEffect, AMissingProgramFileIsNamed) {
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile(game::scenesDir() / "blob_monster.json", scene).ok());
  ASSERT_TRUE(game::applyOverride(scene, "blob.program=blob/no_such.program.json").ok());
  game::World world;
  std::string error;
  EXPECT_FALSE(game::buildWorld(scene, game::contentDir(), world, error));
  EXPECT_NE(error.find("no_such.program.json"), std::string::npos) << error;
}

}  // namespace
