// Replay files: the parser accepts the format of docs/replay.md and names file, line and field for
// every bad input (truncation, unknown version or record, steps going backwards, non-finite
// numbers, bad hashes); a seeded fuzz run of mutated files never crashes and every failure is
// named. Also the frame-time CSV and percentiles, and the scene checks of prepareReplayScene.
#include "game/paths.hpp"
#include "game/replay/frame_times.hpp"
#include "game/replay/replay_file.hpp"
#include "game/replay/replay_runner.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <regex>

namespace {

using game::ReplayFile;
using game::ReplayStatus;

std::string sceneHash(const std::string& scene) {
  std::string bytes, error;
  EXPECT_TRUE(game::readTextFile(game::scenesDir() / (scene + ".json"), bytes, error)) << error;
  return game::hashHex(game::fnv1a64(bytes));
}

std::string validText() {
  return "fluiddemo_replay 1\n"
         "# comment\n"
         "scene crate_yard\n"
         "scene_hash " +
         sceneHash("crate_yard") +
         "\n"
         "set rigid_bodies.throw_speed=12\n"
         "step_hz 60\n"
         "seed 3\n"
         "\n"
         "camera 0 0 3 10 -90 -20\n"
         "action 10 throw_crate   # trailing comment\n"
         "camera 20 10 3 0 -180 -10\n"
         "action 20 throw_crate\n"
         "checkpoint 30 0123456789abcdef rigid_bodies=fedcba9876543210\n"
         "checkpoint 40\n"
         "end 40\n";
}

ReplayStatus parse(const std::string& text, ReplayFile& out) { return game::parseReplayText(text, "t.replay", out); }

::testing::AssertionResult failsWith(const std::string& text, const std::string& line_and_field,
                                     const std::string& part = "") {
  ReplayFile replay;
  const ReplayStatus st = parse(text, replay);
  if (st.ok()) return ::testing::AssertionFailure() << "parsed without error";
  if (st.error.find("t.replay:" + line_and_field) != 0)
    return ::testing::AssertionFailure() << "'" << st.error << "' does not start with 't.replay:" << line_and_field
                                         << "'";
  if (st.error.find(part) == std::string::npos)
    return ::testing::AssertionFailure() << "'" << st.error << "' does not contain '" << part << "'";
  if (st.exit_code != 1) return ::testing::AssertionFailure() << "exit code " << st.exit_code << ", expected 1";
  return ::testing::AssertionSuccess();
}

std::string replaceLine(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(ReplayFile, ValidFileParsesEveryRecord) {
  ReplayFile replay;
  const ReplayStatus st = parse(validText(), replay);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_EQ(replay.version, 1);
  EXPECT_EQ(replay.scene, "crate_yard");
  EXPECT_EQ(game::hashHex(replay.scene_hash), sceneHash("crate_yard"));
  ASSERT_EQ(replay.sets.size(), 1u);
  EXPECT_EQ(replay.sets[0], "rigid_bodies.throw_speed=12");
  EXPECT_EQ(replay.step_hz, 60.0);
  EXPECT_EQ(replay.seed, 3);
  EXPECT_EQ(replay.end_step, 40u);
  ASSERT_EQ(replay.events.size(), 6u);
  EXPECT_EQ(replay.events[1].kind, game::ReplayEventKind::action);
  EXPECT_EQ(replay.events[1].line, 10);
  const game::ReplayEvent& checkpoint = replay.events[4];
  EXPECT_TRUE(checkpoint.has_hash);
  EXPECT_EQ(checkpoint.hash, 0x0123456789abcdefull);
  ASSERT_EQ(checkpoint.parts.size(), 1u);
  EXPECT_EQ(checkpoint.parts[0].name, "rigid_bodies");
  EXPECT_EQ(checkpoint.parts[0].value, 0xfedcba9876543210ull);
  EXPECT_FALSE(replay.events[5].has_hash);  // placeholder for --update-hashes
}

TEST(ReplayFile, CameraIsInterpolatedBetweenKeyframesAndHeldOutside) {
  ReplayFile replay;
  ASSERT_TRUE(parse(validText(), replay).ok());
  game::CameraPose pose;
  ASSERT_TRUE(game::cameraPoseAt(replay, 10, pose));
  EXPECT_FLOAT_EQ(pose.position.x, 5.0f);
  EXPECT_FLOAT_EQ(pose.position.z, 5.0f);
  EXPECT_FLOAT_EQ(pose.yaw_degrees, -135.0f);
  EXPECT_FLOAT_EQ(pose.pitch_degrees, -15.0f);
  ASSERT_TRUE(game::cameraPoseAt(replay, 20, pose));
  EXPECT_FLOAT_EQ(pose.yaw_degrees, -180.0f);
  ASSERT_TRUE(game::cameraPoseAt(replay, 35, pose));  // held after the last keyframe
  EXPECT_FLOAT_EQ(pose.position.x, 10.0f);
}

TEST(ReplayFile, RecordedCameraLinesReadBackBitExact) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coordinate(-50.0f, 50.0f), angle(-89.0f, 89.0f);
  for (int i = 0; i < 1000; ++i) {
    const game::CameraPose pose{{coordinate(rng), coordinate(rng), coordinate(rng)}, angle(rng) * 7.0f, angle(rng)};
    const std::string text = replaceLine(validText(), "camera 0 0 3 10 -90 -20", game::formatCameraLine(0, pose));
    ReplayFile replay;
    ASSERT_TRUE(parse(text, replay).ok());
    const game::ReplayEvent& e = replay.events[0];
    ASSERT_EQ(e.position.x, pose.position.x);
    ASSERT_EQ(e.position.y, pose.position.y);
    ASSERT_EQ(e.position.z, pose.position.z);
    ASSERT_EQ(e.yaw_degrees, pose.yaw_degrees);
    ASSERT_EQ(e.pitch_degrees, pose.pitch_degrees);
  }
}

TEST(ReplayFile, TruncatedFilesAreNamed) {
  const std::string text = validText();
  // Cut at the end of a line: the end record is missing.
  const std::size_t cut = text.find("checkpoint 40");
  EXPECT_TRUE(failsWith(text.substr(0, cut), "14: field 'end'", "truncated"));
  // Cut inside a line: no newline at the end.
  EXPECT_TRUE(failsWith(text.substr(0, cut + 5), "14: field 'end'", "truncated"));
  EXPECT_TRUE(failsWith("", "1: field 'fluiddemo_replay'", "empty file"));
  // Cut inside the header: the first event finds it incomplete.
  EXPECT_TRUE(failsWith("fluiddemo_replay 1\nscene crate_yard\ncamera 0 0 0 0 0 0\nend 5\n", "3: field 'scene_hash'",
                        "missing"));
}

TEST(ReplayFile, UnknownVersionRecordAndActionAreNamed) {
  EXPECT_TRUE(failsWith(replaceLine(validText(), "fluiddemo_replay 1", "fluiddemo_replay 2"),
                        "1: field 'fluiddemo_replay'", "unknown format version '2'"));
  EXPECT_TRUE(
      failsWith(replaceLine(validText(), "action 20 throw_crate", "jump 20"), "12: field 'jump'", "unknown record"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "action 20 throw_crate", "action 20 throw_grenade"),
                        "12: field 'action.name'",
                        "unknown action 'throw_grenade' (known: throw_crate, throw_explosive)"));
}

TEST(ReplayFile, StepsGoingBackwardsAreNamed) {
  EXPECT_TRUE(failsWith(replaceLine(validText(), "action 20 throw_crate", "action 5 throw_crate"),
                        "12: field 'action.step'", "goes backwards (line 11 is at step 20)"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "end 40", "end 35"), "15: field 'end.step'", "before the event"));
  EXPECT_TRUE(
      failsWith(replaceLine(validText(), "checkpoint 40", "checkpoint 0"), "14: field 'checkpoint.step'", ">= 1"));
}

TEST(ReplayFile, NonFiniteAndMalformedNumbersAreNamed) {
  EXPECT_TRUE(failsWith(replaceLine(validText(), "camera 20 10 3 0", "camera 20 nan 3 0"), "11: field 'camera.x'",
                        "non-finite value 'nan'"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "camera 20 10 3 0", "camera 20 10 inf 0"), "11: field 'camera.y'",
                        "non-finite"));
  EXPECT_TRUE(
      failsWith(replaceLine(validText(), "camera 20 10 3 0", "camera 20 10 3 1e400"), "11: field 'camera.z'", "1e400"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "-180 -10", "-180 -100"), "11: field 'camera.pitch'", "outside"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "camera 20 10 3 0 -180 -10", "camera 20 10 3 0 -180"),
                        "11: field 'camera'", "expected 'camera STEP X Y Z YAW PITCH'"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "action 10", "action -10"), "10: field 'action.step'",
                        "expected a step number"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "0123456789abcdef", "0123456789abcdeg"), "13: field 'checkpoint.hash'",
                        "16 hex digits"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "rigid_bodies=fedcba9876543210", "rigid_bodies=12"),
                        "13: field 'checkpoint.rigid_bodies'", "16 hex digits"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "step_hz 60", "step_hz 0"), "6: field 'step_hz'", "outside"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "seed 3", "seed -3"), "7: field 'seed'", "non-negative"));
}

TEST(ReplayFile, HeaderRecordsAreCheckedForPlaceAndRepetition) {
  EXPECT_TRUE(
      failsWith(replaceLine(validText(), "action 20 throw_crate", "seed 4"), "12: field 'seed'", "given twice"));
  EXPECT_TRUE(failsWith(replaceLine(validText(), "action 20 throw_crate", "set a.b=1"), "12: field 'set'",
                        "after the first event"));
  EXPECT_TRUE(failsWith(validText() + "camera 50 0 0 0 0 0\n", "16: field 'camera'", "after 'end'"));
}

// The seeded fuzz run of issue 16: a few thousand random mutations of a valid file (bytes replaced,
// inserted, deleted; lines dropped, duplicated, swapped; cuts) never crash the parser, and every
// failure names the file, a line number and a field, with the content exit code.
TEST(ReplayFile, FuzzedMutationsNeverCrashAndEveryFailureIsNamed) {
  const std::string valid = validText();
  const std::regex named(R"(^t\.replay:[0-9]+: field '[^']+': .+)");
  std::mt19937 rng(20261125);
  const std::string alphabet = "0123456789abcdef -.#\n\tnaiefxyz=_";
  int failures = 0, successes = 0;
  for (int round = 0; round < 4000; ++round) {
    std::string text = valid;
    const int mutations = 1 + static_cast<int>(rng() % 4);
    for (int m = 0; m < mutations && !text.empty(); ++m) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 7) {
        case 0:
          text[at] = alphabet[rng() % alphabet.size()];
          break;
        case 1:
          text.insert(at, 1, alphabet[rng() % alphabet.size()]);
          break;
        case 2:
          text.erase(at, 1 + rng() % 8);
          break;
        case 3:
          text.resize(at);  // truncation
          break;
        case 4: {  // duplicate the line holding `at`
          const std::size_t start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
          const std::size_t end = text.find('\n', at);
          if (end != std::string::npos) text.insert(start, text.substr(start, end - start + 1));
          break;
        }
        case 5:  // a random byte, including NUL and high bytes
          text[at] = static_cast<char>(rng() % 256);
          break;
        default: {  // drop the line holding `at`
          const std::size_t start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
          const std::size_t end = text.find('\n', at);
          text.erase(start, end == std::string::npos ? std::string::npos : end - start + 1);
          break;
        }
      }
    }
    ReplayFile replay;
    const ReplayStatus st = parse(text, replay);
    if (st.ok()) {
      ++successes;
      // Whatever parsed is consistent: events in step order, end at or after the last one.
      for (std::size_t i = 1; i < replay.events.size(); ++i)
        ASSERT_LE(replay.events[i - 1].step, replay.events[i].step);
      if (!replay.events.empty()) {
        ASSERT_LE(replay.events.back().step, replay.end_step);
      }
      continue;
    }
    ++failures;
    ASSERT_TRUE(std::regex_search(st.error, named)) << "round " << round << ": unnamed failure '" << st.error << "'";
    ASSERT_EQ(st.exit_code, 1) << st.error;
  }
  // Both outcomes occur, so the run exercised the parser's accepting and refusing paths.
  EXPECT_GT(failures, 1000);
  EXPECT_GT(successes, 50);
}

TEST(ReplayScene, UnknownSceneAndChangedSceneAreNamed) {
  ReplayFile replay;
  ASSERT_TRUE(parse(replaceLine(validText(), "scene crate_yard", "scene nosuchscene"), replay).ok());
  game::SceneConfig scene;
  std::uint64_t hash = 0;
  std::string warning;
  ReplayStatus st = game::prepareReplayScene(replay, game::scenesDir(), false, {}, scene, hash, warning);
  EXPECT_EQ(st.exit_code, 1);
  EXPECT_EQ(st.error.find("t.replay:3: field 'scene': unknown scene 'nosuchscene'"), 0u) << st.error;

  ASSERT_TRUE(parse(replaceLine(validText(), sceneHash("crate_yard"), "0000000000000000"), replay).ok());
  st = game::prepareReplayScene(replay, game::scenesDir(), false, {}, scene, hash, warning);
  EXPECT_EQ(st.error.find("t.replay:4: field 'scene_hash'"), 0u) << st.error;
  EXPECT_NE(st.error.find("--allow-scene-change"), std::string::npos) << st.error;
  st = game::prepareReplayScene(replay, game::scenesDir(), true, {}, scene, hash, warning);
  EXPECT_TRUE(st.ok()) << st.error;
  EXPECT_NE(warning.find("scene_hash"), std::string::npos);

  ASSERT_TRUE(parse(validText(), replay).ok());
  st = game::prepareReplayScene(replay, game::scenesDir(), false, {}, scene, hash, warning);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_EQ(scene.effect("rigid_bodies")->number("throw_speed"), 12.0);  // the header's set record
  ASSERT_TRUE(parse(replaceLine(validText(), "seed 3", "seed 4"), replay).ok());
  st = game::prepareReplayScene(replay, game::scenesDir(), false, {}, scene, hash, warning);
  EXPECT_EQ(st.error.find("t.replay:7: field 'seed'"), 0u) << st.error;
  ASSERT_TRUE(parse(replaceLine(validText(), "throw_speed=12", "throw_speed=-1"), replay).ok());
  st = game::prepareReplayScene(replay, game::scenesDir(), false, {}, scene, hash, warning);
  EXPECT_EQ(st.error.find("t.replay:5: field 'set'"), 0u) << st.error;
}

TEST(FrameTimes, CsvRoundTripsWithTheDocumentedColumns) {
  std::vector<game::FrameRow> rows(3);
  for (int i = 0; i < 3; ++i) {
    rows[i].frame = i;
    rows[i].step = static_cast<std::uint64_t>(i + 1);
    rows[i].phase_ms = {0.5, 1.25, 2.0, 3.0, 4.5, 0.25};
    rows[i].frame_ms = 12.0 + i;
    rows[i].columns.set("particles", 100.0 * i);
    rows[i].columns.set("triangles", 7);
    rows[i].columns.set("water_spray", 3.0 * i);
    rows[i].columns.set("blasts", i % 2);
    rows[i].columns.set("mesh_worker_ms", 0.125 * i);
  }
  game::FrameColumns& health = rows[1].columns;
  health.set("sph_steps", 17);
  health.set("density_err_mean", 0.000412345f);
  health.set("density_err_p99", 0.00375f);
  health.set("density_err_max", 0.0213f);
  health.set("pushed_out", 42);
  health.set("push_depth_mm", 3.125);
  health.set("speed_clamps", 5);
  health.set("dt_min_clamps", 1);
  health.set("dt_request_cuts", 2);
  health.set("warned", 1);
  rows[2].columns.set("nonfinite", 9);
  rows[2].has_hash = true;
  rows[2].state_hash = 0xabcdef0123456789ull;
  // The effects' columns in registry order (explosives, sph_fluid, sprite_particles, fluid_surface,
  // gulls; the blob's triangles and worker time share the water's columns), between the phases and
  // the hash.
  EXPECT_EQ(game::frameCsvHeader(),
            "frame,step,input_ms,physics_ms,fluid_ms,meshing_ms,render_ms,ui_ms,frame_ms,blasts,particles,water_pool,"
            "water_air,water_ground,water_pump,water_spray,sph_steps,sph_fast,sph_iterations,density_err_mean,density_err_p99,"
            "density_err_max,pushed_out,push_depth_mm,speed_clamps,dt_min_clamps,dt_request_cuts,nonfinite,warned,sprites,triangles,"
            "mesh_worker_ms,raycast_records,raycast_dropped,raycast_pool,raycast_pool_bound,gulls_fleeing,state_hash");
  const auto path = std::filesystem::temp_directory_path() / ("replay_csv_" + std::to_string(::getpid()) + ".csv");
  std::string error;
  ASSERT_TRUE(game::writeFrameCsv(path, rows, error)) << error;
  std::vector<game::FrameRow> back;
  ASSERT_TRUE(game::readFrameCsv(path, back, error)) << error;
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[2].frame_ms, 14.0);
  EXPECT_EQ(back[1].phase_ms[4], 4.5);
  EXPECT_EQ(back[2].columns.get("particles"), 200.0);
  EXPECT_EQ(back[2].columns.get("water_spray"), 6.0);
  EXPECT_EQ(back[1].columns.get("blasts"), 1.0);
  EXPECT_EQ(back[2].columns.get("mesh_worker_ms"), 0.25);
  // The SPH health columns come back as written (a float density error survives %.9g).
  const game::FrameColumns& t = back[1].columns;
  EXPECT_EQ(t.get("sph_steps"), 17.0);
  EXPECT_EQ(static_cast<float>(t.get("density_err_mean")), 0.000412345f);
  EXPECT_EQ(static_cast<float>(t.get("density_err_p99")), 0.00375f);
  EXPECT_EQ(static_cast<float>(t.get("density_err_max")), 0.0213f);
  EXPECT_EQ(t.get("pushed_out"), 42.0);
  EXPECT_EQ(t.get("push_depth_mm"), 3.125);
  EXPECT_EQ(t.get("speed_clamps"), 5.0);
  EXPECT_EQ(t.get("dt_min_clamps"), 1.0);
  EXPECT_EQ(t.get("dt_request_cuts"), 2.0);
  EXPECT_EQ(t.get("nonfinite"), 0.0);
  EXPECT_EQ(t.get("warned"), 1.0);
  EXPECT_EQ(back[0].columns.get("warned"), 0.0);
  EXPECT_EQ(back[2].columns.get("nonfinite"), 9.0);
  EXPECT_FALSE(back[1].has_hash);
  EXPECT_TRUE(back[2].has_hash);
  EXPECT_EQ(back[2].state_hash, 0xabcdef0123456789ull);
  // A bad cell is named by file, line and column: a written row with one cell replaced.
  const auto rowWith = [&rows](std::string_view column, std::string_view value) {
    const std::string header = game::frameCsvHeader();
    std::string line = game::frameCsvRow(rows[0]);
    const std::size_t index = static_cast<std::size_t>(
        std::count(header.begin(), header.begin() + static_cast<long>(header.find(column)), ','));
    std::size_t start = 0;
    for (std::size_t k = 0; k < index; ++k) start = line.find(',', start) + 1;
    const std::size_t end = line.find(',', start);
    return line.replace(start, end - start, value) + "\n";
  };
  {
    std::ofstream out(path, std::ios::app);
    out << rowWith("fluid_ms", "x");
  }
  EXPECT_FALSE(game::readFrameCsv(path, back, error));
  EXPECT_NE(error.find(":5: column 'fluid_ms': bad value 'x'"), std::string::npos) << error;
  {  // and so is a bad health cell (warned is 0 or 1)
    ASSERT_TRUE(game::writeFrameCsv(path, rows, error)) << error;
    std::ofstream out(path, std::ios::app);
    out << rowWith("warned", "2");
  }
  EXPECT_FALSE(game::readFrameCsv(path, back, error));
  EXPECT_NE(error.find(":5: column 'warned': bad value '2'"), std::string::npos) << error;
  std::filesystem::remove(path);
}

TEST(FrameTimes, PercentilesAreNearestRank) {
  std::vector<double> values, scratch;
  for (int i = 100; i >= 1; --i) values.push_back(i);  // 1..100, unsorted
  const game::Percentiles p = game::percentiles(values, scratch);
  EXPECT_EQ(p.p50, 50.0);
  EXPECT_EQ(p.p95, 95.0);
  EXPECT_EQ(p.p99, 99.0);
  EXPECT_EQ(p.max, 100.0);
  const game::Percentiles one = game::percentiles({7.0}, scratch);
  EXPECT_EQ(one.p50, 7.0);
  EXPECT_EQ(one.max, 7.0);
}

}  // namespace
