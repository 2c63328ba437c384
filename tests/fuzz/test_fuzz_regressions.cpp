// Each input here crashed, hung or misbehaved before the parser fix named next to it (issue 15,
// item 5); fuzz_smoke and the libFuzzer runs found or would find them. Every one is now a
// rejection naming the file and the place, or a correct load.
#include "fuzz_targets.hpp"

#include "fluid/collide/collide.hpp"
#include "fluid/io/particle_io.hpp"
#include "game/world/collider_model.hpp"
#include "game/scene/scene_config.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string plyHeader(const std::string& format, const std::string& elements) {
  return "ply\nformat " + format + " 1.0\n" + elements + "end_header\n";
}

TEST(FuzzRegressions, PlyAsciiListCountIsBoundedByTheLine) {
  // Was: `for (k < 1e18) words >> token` -- a loop of 1e18 steps on a 100-byte file.
  const std::string ply = plyHeader("ascii",
                                    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                                    "property list uchar int l\n") +
                          "1 2 3 1e18\n";
  fluid::ParticlePositions particles;
  const auto t0 = std::chrono::steady_clock::now();
  const fluid::IoStatus status = fluid::parseParticleText(ply, "ply", "h.ply", particles);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  EXPECT_EQ(status.error, "h.ply:9: bad list count '1e18' of property l");
  // A count larger than the items on the line is named too.
  const std::string short_list = plyHeader("ascii", "element face 1\nproperty list uchar int v\n") + "4 1 2 3\n";
  EXPECT_EQ(fluid::parseParticleText(short_list, "ply", "s.ply", particles).error,
            "s.ply:6: list v has fewer than 4 items");
}

TEST(FuzzRegressions, PlyBinaryListCountOfTypeDoubleIsCheckedBeforeUse) {
  // Was: static_cast<std::streamsize>(1e300) (undefined) for a list whose count type is double.
  std::string ply = plyHeader("binary_little_endian", "element face 1\nproperty list double int v\n");
  const double count = 1e300;
  ply.append(reinterpret_cast<const char*>(&count), 8);
  fluid::ParticlePositions particles;
  const fluid::IoStatus status = fluid::parseParticleText(ply, "ply", "d.ply", particles);
  EXPECT_TRUE(contains(status.error, "d.ply: byte 89 (face 0): list v of 1e+300 items does not fit")) << status.error;
}

TEST(FuzzRegressions, PlyCountsAreCheckedAgainstTheFileBeforeLoopingOrAllocating) {
  fluid::ParticlePositions particles;
  // Was: 1e18 iterations doing nothing (binary items without properties hold no bytes).
  const std::string empty_items = plyHeader("binary_little_endian", "element junk 1000000000000000000\n");
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(fluid::parseParticleText(empty_items, "ply", "e.ply", particles).ok());
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  // Was: reserve(2^24) floats for a file of a few bytes, then a read error.
  const std::string many = plyHeader(
      "binary_little_endian", "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n");
  EXPECT_EQ(fluid::parseParticleText(many + "abc", "ply", "m.ply", particles).error,
            "m.ply:3: element vertex claims 4000000000 items but only 3 bytes follow the header");
}

TEST(FuzzRegressions, PlyEmptyElementWithoutPropertiesAndNonIntegerCounts) {
  // libFuzzer (UBSan): "element vert 0" without properties divided by its 0 item bytes; the
  // count "0.0" was read as 0 and the ".0" ignored.
  fluid::ParticlePositions particles;
  const std::string vertex = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  std::string ply = plyHeader("binary_little_endian", "element vert 0\n" + vertex);
  const float xyz[3] = {1.5f, -2.0f, 3.0f};
  ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  ASSERT_TRUE(fluid::parseParticleText(ply, "ply", "z.ply", particles).ok());
  EXPECT_EQ(particles.at(0), glm::vec3(1.5f, -2.0f, 3.0f));
  EXPECT_EQ(fluid::parseParticleText(plyHeader("ascii", "element vert 0.0\n"), "ply", "f.ply", particles).error,
            "f.ply:3: bad element line 'element vert 0.0' (expected: element NAME COUNT)");
}

TEST(FuzzRegressions, ParticleMessagesQuoteAtMostAShortToken) {
  fluid::ParticlePositions particles;
  const std::string token(5000, 'q');
  const fluid::IoStatus status = fluid::parseParticleText("1 2 " + token + "\n", "xyz", "t.xyz", particles);
  EXPECT_LT(status.error.size(), 100u) << status.error;
  EXPECT_TRUE(contains(status.error, "t.xyz:1: 'qqqq")) << status.error;
  // %g, not std::to_string's 300 digits.
  EXPECT_EQ(fluid::parseParticleText("1 2 1e300\n", "xyz", "b.xyz", particles).error,
            "b.xyz:1: coordinate z is not a finite float (1e+300)");
}

// A valid collider file with one texel changed, checksum rewritten (fuzz_targets' collider target).
std::vector<std::uint8_t> colliderWithTexel(fluid::DepthMapFormat format, std::size_t texel, const void* bytes) {
  fluid::DepthMap map;
  map.format = format;
  map.resolution = 4;
  map.texels.assign(4 * 4 * fluid::texelBytes(format), 0);
  std::memcpy(map.texels.data() + texel * fluid::texelBytes(format), bytes, fluid::texelBytes(format));
  std::vector<fluid::DepthMap> maps;
  maps.push_back(map);
  return fluid::serializeCollider(fluid::DepthMapCollider(std::move(maps), 2));
}

TEST(FuzzRegressions, ColliderTexelsMustDecode) {
  // Was: normal index (255, 255) in an R_n = 2 file read normal_table_[765] of 4 in sample().
  const std::uint8_t fixed8[4] = {255, 255, 0x10, 0x00};
  fluid::DepthMapCollider collider;
  fluid::FileStatus status =
      fluid::deserializeCollider(colliderWithTexel(fluid::DepthMapFormat::fixed8, 5, fixed8), "n.fdm", collider);
  EXPECT_TRUE(contains(status.error, "n.fdm: byte 148: map 0: texel 5 does not decode")) << status.error;
  // Was: a NaN depth voted NaN distances.
  const float nan_depth[4] = {0.0f, 0.0f, 1.0f, std::numeric_limits<float>::quiet_NaN()};
  status =
      fluid::deserializeCollider(colliderWithTexel(fluid::DepthMapFormat::float32, 0, nan_depth), "f.fdm", collider);
  EXPECT_TRUE(contains(status.error, "f.fdm: byte 128: map 0: texel 0 does not decode")) << status.error;
  // Every other rejection names the byte too.
  std::vector<std::uint8_t> bytes = colliderWithTexel(fluid::DepthMapFormat::fixed8, 0, fixed8);
  bytes[12] = 1;  // normal resolution 1
  EXPECT_EQ(fluid::deserializeCollider(bytes, "r.fdm", collider).error,
            "r.fdm: byte 12: normal_resolution 1 out of range 2..256");
}

TEST(FuzzRegressions, ColliderScalesAreBoundedSoDistancesStayFinite) {
  // Was: z_scale 3e38 loaded, and a query 2 units in front of a map answered distance +inf.
  const std::uint8_t fixed8[4] = {0, 0, 0x10, 0x00};
  std::vector<std::uint8_t> bytes = colliderWithTexel(fluid::DepthMapFormat::fixed8, 0, fixed8);
  const float huge = 3e38f;
  std::memcpy(bytes.data() + 40 + 16 * 4, &huge, 4);  // z_scale, after the 16 matrix floats
  fluid::DepthMapCollider collider;
  EXPECT_EQ(fluid::deserializeCollider(bytes, "z.fdm", collider).error,
            "z.fdm: byte 104: map 0: scale 16 is 3e+38, expected in (0, 1e7]");
}

TEST(FuzzRegressions, SceneNumberBeyondDoubleIsAnErrorWithItsPlace) {
  // Was: json::out_of_range (406) escaped the parse_error catch: std::terminate.
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText("{\n  \"scene\": {\"step_hz\": 1e999}}", "big.json", scene);
  EXPECT_EQ(status.error, "big.json: invalid JSON at line 2, column 24: number overflow parsing '1e999'");
}

TEST(FuzzRegressions, SetTextWithInvalidUtf8IsAnErrorNotAThrow) {
  // Was: json::dump() of the value for the message threw type_error 316 (invalid UTF-8).
  game::SceneConfig scene;
  ASSERT_TRUE(game::parseSceneText(R"({"effects": {"sph_fluid": {}}})", "s.json", scene).ok());
  const game::SceneStatus status = game::applyOverride(scene, "sph_fluid.solver=\xff\xfe");
  EXPECT_TRUE(contains(status.error, "--set sph_fluid.solver=\xff\xfe: value \"")) << status.error;
  EXPECT_TRUE(contains(status.error, "is not one of: dfsph, wcsph")) << status.error;
}

TEST(FuzzRegressions, SceneMessagesStayShort) {
  // Was: nlohmann's "last read: '...'" quoted everything after an unclosed string.
  game::SceneConfig scene;
  const std::string text = "{\"description\": \"" + std::string(100000, 'x');
  const game::SceneStatus status = game::parseSceneText(text, "u.json", scene);
  EXPECT_LT(status.error.size(), 300u) << status.error.substr(0, 400);
  EXPECT_TRUE(contains(status.error, "u.json: invalid JSON: parse error at line 1, column")) << status.error;
  const std::string long_key = "{\"effects\": {}, \"" + std::string(10000, 'k') + "\": 1}";
  EXPECT_LT(game::parseSceneText(long_key, "k.json", scene).error.size(), 200u);
}

std::string loadObj(const std::string& text, game::ColliderModel& model) {
  std::string error;
  game::loadColliderModelFromMemory(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), "obj",
                                    "m.obj", model, error);
  return error;
}

TEST(FuzzRegressions, ObjFilesAreCheckedBeforeAssimpSeesThem) {
  game::ColliderModel model;
  // libFuzzer (ASan): assimp 5.2.5's OBJ importer wrote through a wild pointer on this input.
  EXPECT_EQ(
      loadObj("normals\nmtllib m\n", model),
      "m.obj:1: unknown or unsupported OBJ statement 'normals' (polygonal geometry only: v, vt, vn, f, l, p, o, g, "
      "s, usemtl, mtllib)");
  // Indices name elements defined before them; messages give the line.
  EXPECT_EQ(loadObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", model),
            "m.obj:4: f item 3: vertex index 4 names no vertex (3 defined so far)");
  EXPECT_EQ(loadObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2 3\n", model),
            "m.obj:4: f item 1: normal index 1 names no normal (0 defined so far)");
  EXPECT_EQ(loadObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 2 3\n", model),
            "m.obj:4: f item 1: vertex index -4 names no vertex (3 defined so far)");
  EXPECT_EQ(loadObj("v 0 0 zero\n", model), "m.obj:1: 'zero' is not a number");
  EXPECT_EQ(loadObj("v 0 0 0\n", model), "m.obj:2: end of file and no face (f) statement: nothing to bake");
  // A valid file still loads, relative indices and all.
  EXPECT_EQ(loadObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3//1 -2//1 -1//1\n", model), "");
  EXPECT_EQ(model.indices.size(), 3u);
}

TEST(FuzzRegressions, AssimpNeverParsesAMaterialLibrary) {
  // libFuzzer (ASan): with an `mtllib` it cannot open, assimp 5.2.5 reading from memory falls back
  // to "<magic>.mtl", which its memory IO system serves as the OBJ bytes themselves, and the MTL
  // parser then wrote through a wild pointer (here on an `o` name full of NUL bytes). mtllib
  // statements are blanked before assimp sees the text (for files too: no .mtl is ever opened).
  game::ColliderModel model;
  const std::string obj = std::string("mtllib m.mtl\no tetr") + std::string(82, '\0') +
                          "a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  EXPECT_EQ(loadObj(obj, model), "");
  EXPECT_EQ(model.indices.size(), 12u);
}

// Inputs libFuzzer crashed on, kept as files: tests/fuzz/regressions/<target>/<input>.
TEST(FuzzRegressions, SavedCrashInputsPassTheirTarget) {
  const std::filesystem::path root = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "tests" / "fuzz" / "regressions";
  int inputs = 0;
  for (const auto& folder : std::filesystem::directory_iterator(root)) {
    const fuzz::Target* target = fuzz::findTarget(folder.path().filename().string());
    ASSERT_NE(target, nullptr) << folder.path();
    for (const auto& file : std::filesystem::directory_iterator(folder.path())) {
      std::ifstream in(file.path(), std::ios::binary);
      const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      EXPECT_EQ(target->check(bytes), "") << file.path();
      ++inputs;
    }
  }
  EXPECT_GE(inputs, 2);
}

TEST(FuzzRegressions, EveryTargetHandlesAnEmptyInput) {
  // The targets themselves: an empty input is handled (rejected with a place, or accepted).
  for (const fuzz::Target& target : fuzz::targets()) {
    EXPECT_EQ(target.check({}), "") << target.name;
  }
}

}  // namespace
