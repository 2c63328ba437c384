// Replays without GL (ReplayRunOptions::render = false, the same steps, inputs and checkpoints as
// a rendered replay): the committed replays' checkpoints hold at 1 and 2 threads, a perturbed
// simulation constant fails the gate naming the step and the subsystem, and a session recorded
// through the recorder replays to the live session's hashes.
#include "game/paths.hpp"
#include "game/replay/recorder.hpp"
#include "game/replay/replay_runner.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <unistd.h>
#include <algorithm>
#include <filesystem>

namespace {

game::ReplayFile load(const std::string& name) {
  game::ReplayFile replay;
  const game::ReplayStatus st = game::loadReplayFile(game::contentDir() / "replays" / (name + ".replay"), replay);
  EXPECT_TRUE(st.ok()) << st.error;
  return replay;
}

int simulate(const game::ReplayFile& replay, int frames, game::ReplayResult& result, std::string& error,
             std::vector<std::string> perturb = {}) {
  game::ReplayRunOptions options;
  options.render = false;
  options.frames = frames;
  options.extra_overrides = std::move(perturb);
  return game::runReplay(replay, options, result, error);
}

TEST(ReplayRun, CheckpointsHoldAndHashesAgreeAtOneAndTwoThreads) {
  const game::ReplayFile replay = load("fountain_tour");
  std::vector<game::CheckpointOutcome> per_threads[2];
  for (int threads = 1; threads <= 2; ++threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    game::ReplayResult result;
    std::string error;
    ASSERT_EQ(simulate(replay, 300, result, error), 0) << error;
    ASSERT_EQ(result.checkpoints.size(), 2u);  // steps 150 and 300
    for (const auto& c : result.checkpoints) EXPECT_TRUE(c.matched);
    per_threads[threads - 1] = result.checkpoints;
  }
  for (std::size_t i = 0; i < per_threads[0].size(); ++i) {
    EXPECT_EQ(per_threads[0][i].combined, per_threads[1][i].combined);
    // rigid_bodies, explosives, sph_fluid, gulls (GPU sprites are not hashed)
    ASSERT_EQ(per_threads[0][i].parts.size(), 4u);
    for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(per_threads[0][i].parts[k].value, per_threads[1][i].parts[k].value);
  }
}

// A perturbed constant (test-only override after the replay's own header) must fail the gate.
TEST(ReplayRun, PerturbedGravityFailsTheGateNamingStepAndSubsystem) {
  const game::ReplayFile replay = load("crate_yard_tour");
  game::ReplayResult result;
  std::string error;
  ASSERT_EQ(simulate(replay, 150, result, error), 0) << error;  // the control run passes
  ASSERT_EQ(simulate(replay, 150, result, error, {"rigid_bodies.gravity=0,-9.8101,0"}), 1);
  EXPECT_NE(error.find("crate_yard_tour.replay:"), std::string::npos) << error;
  EXPECT_NE(error.find("checkpoint at step 150 failed: first differing subsystem 'rigid_bodies'"), std::string::npos)
      << error;
  EXPECT_EQ(result.rows.size(), 150u);  // it stopped at the failing checkpoint
}

TEST(ReplayRun, PerturbedViscosityFailsTheGateInTheFluid) {
  const game::ReplayFile replay = load("fountain_tour");
  game::ReplayResult result;
  std::string error;
  ASSERT_EQ(simulate(replay, 150, result, error, {"sph_fluid.viscosity=0.0201"}), 1);
  EXPECT_NE(error.find("checkpoint at step 150 failed"), std::string::npos) << error;
  EXPECT_NE(error.find("sph_fluid"), std::string::npos) << error;
  EXPECT_EQ(error.find("sprite_particles"), std::string::npos) << error;  // the sprites do not touch the water
}

// The explosives are hashed: a charge whose fuse differs fails the first checkpoint after the
// throw, in the explosives' part, before its blast has moved anything else.
TEST(ReplayRun, ADifferentFuseFailsTheGateInTheExplosives) {
  game::ReplayFile replay = load("fountain_tour");
  const auto thrown = std::find_if(replay.events.begin(), replay.events.end(), [](const game::ReplayEvent& e) {
    return e.kind == game::ReplayEventKind::action && e.action == game::PlayerAction::throw_explosive;
  });
  ASSERT_NE(thrown, replay.events.end());
  // 0.5 s after the throw: the 2.5 s fuse still runs.
  const std::uint64_t check_step = thrown->step + 30;
  replay.events.erase(std::remove_if(replay.events.begin(), replay.events.end(),
                                     [](const game::ReplayEvent& e) { return e.kind == game::ReplayEventKind::checkpoint; }),
                      replay.events.end());
  game::ReplayEvent checkpoint;
  checkpoint.kind = game::ReplayEventKind::checkpoint;
  checkpoint.step = check_step;
  const auto after = std::find_if(replay.events.begin(), replay.events.end(),
                                  [&](const game::ReplayEvent& e) { return e.step > check_step; });
  replay.events.insert(after, checkpoint);
  // Record this build's hashes at the new checkpoint, then check against them.
  game::ReplayRunOptions record;
  record.render = false;
  record.frames = static_cast<int>(check_step);
  record.update_hashes = true;
  game::ReplayResult recorded;
  std::string error;
  ASSERT_EQ(game::runReplay(replay, record, recorded, error), 0) << error;
  ASSERT_EQ(recorded.checkpoints.size(), 1u);
  for (game::ReplayEvent& e : replay.events) {
    if (e.kind != game::ReplayEventKind::checkpoint) continue;
    e.has_hash = true;
    e.hash = recorded.checkpoints[0].combined;
    e.parts = recorded.checkpoints[0].parts;
  }
  game::ReplayResult result;
  ASSERT_EQ(simulate(replay, static_cast<int>(check_step), result, error), 0) << error;  // the control run passes
  ASSERT_EQ(simulate(replay, static_cast<int>(check_step), result, error, {"explosives.fuse_seconds=2.4"}), 1);
  EXPECT_NE(error.find("failed: first differing subsystem 'explosives'"), std::string::npos) << error;
  EXPECT_NE(error.find("(differing: explosives)"), std::string::npos) << error;  // nothing else moved yet
}

// A "live" session driven through the recorder's own API (camera moving every step, throws at
// three steps, two of them in one step), then replayed: every recorded checkpoint must match.
TEST(ReplayRun, RecordedSessionReplaysToTheLiveHashes) {
  const auto path = std::filesystem::temp_directory_path() / ("record_" + std::to_string(::getpid()) + ".replay");
  std::filesystem::remove(path);
  game::SceneConfig scene;
  ASSERT_TRUE(game::loadSceneFile(game::scenesDir() / "fountain.json", scene).ok());
  ASSERT_TRUE(game::applyOverride(scene, "rigid_bodies.throw_speed=11").ok());
  game::ReplayRecorder recorder;
  recorder.checkpoint_every = 50;
  std::string error;
  ASSERT_TRUE(game::startRecording(path, false, "fountain", scene, {"rigid_bodies.throw_speed=11"}, recorder, error))
      << error;
  // Never replaces an existing file without force.
  game::ReplayRecorder second;
  EXPECT_FALSE(game::startRecording(path, false, "fountain", scene, {}, second, error));
  EXPECT_NE(error.find("exists (pass --force"), std::string::npos) << error;

  game::World world;
  ASSERT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
  std::vector<game::StateHash> live;
  for (int step = 0; step < 170; ++step) {
    world.camera.yaw_degrees += 0.37f;
    world.camera.position.x += 0.011f;
    std::vector<game::PlayerAction> actions;
    if (step == 20 || step == 90) actions = {game::PlayerAction::throw_crate};
    if (step == 91) actions = {game::PlayerAction::throw_crate, game::PlayerAction::throw_crate};
    game::recordInput(recorder, world, actions);
    for (game::PlayerAction a : actions) game::applyPlayerAction(world, a);
    game::stepWorld(world, nullptr);
    game::recordAfterFrame(recorder, world);
  }
  ASSERT_TRUE(game::finishRecording(recorder, error)) << error;

  game::ReplayFile replay;
  const game::ReplayStatus st = game::loadReplayFile(path, replay);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_EQ(replay.end_step, 170u);
  ASSERT_EQ(replay.sets.size(), 1u);
  game::ReplayResult result;
  ASSERT_EQ(simulate(replay, 0, result, error), 0) << error;
  ASSERT_EQ(result.checkpoints.size(), 4u);  // 50, 100, 150 and the last step 170
  for (const auto& c : result.checkpoints) EXPECT_TRUE(c.matched) << "step " << c.step;
  EXPECT_EQ(result.checkpoints.back().step, 170u);
  std::size_t throws = 0;
  for (const auto& e : replay.events) throws += e.kind == game::ReplayEventKind::action;
  EXPECT_EQ(throws, 4u);
  std::filesystem::remove(path);
}

}  // namespace
