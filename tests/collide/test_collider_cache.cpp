// Baked collider files as a cache of a model (fluid/collide/collider_cache.hpp): the source record
// round-trips, a changed model or recipe is detected as stale (error with load_only, re-bake with
// load_or_bake), and corrupt or mutated files give errors naming the file and the field.
#include "collide_meshes.hpp"
#include "fluid/collide/collider_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A scratch directory per test; the "model" file's bytes are what is hashed, the loader returns a
// small torus (fluid/ reads no model format: the game passes its assimp loader).
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() / ("fluiddemo_cache_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(dir);
    fs::create_directories(dir / "colliders");
    fs::create_directories(dir / "models");
    writeModel("torus v1\n");
  }
  ~Scratch() { fs::remove_all(dir); }
  fs::path model() const { return dir / "models" / "torus.obj"; }
  fs::path baked() const { return dir / "colliders" / "torus.fdm"; }
  void writeModel(const std::string& text) const { std::ofstream(model(), std::ios::binary) << text; }
};

int loads = 0;
bool torusLoader(const fs::path&, std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices,
                 std::string&) {
  ++loads;
  const collide_test::Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 24, 8);
  positions = torus.positions;
  indices = torus.indices;
  return true;
}

fluid::BakeRecipe smallRecipe() {
  fluid::BakeRecipe r;
  r.maps = "axes";
  r.resolution = 32;
  r.normal_resolution = 32;
  r.margin = 0.1f;
  return r;
}

std::vector<std::uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void writeBytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

TEST(ColliderCache, BakesOnceThenLoadsTheRecordedFile) {
  Scratch s("once");
  fluid::CachedCollider first, second;
  loads = 0;
  ASSERT_TRUE(fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader,
                                        fluid::CachePolicy::load_or_bake, first)
                  .ok());
  EXPECT_TRUE(first.rebaked);
  EXPECT_TRUE(contains(first.rebake_reason, "no such file")) << first.rebake_reason;
  EXPECT_EQ(first.source.model, "torus.obj");
  EXPECT_EQ(first.source.recipe, "baker=3 maps=axes res=32 format=front-back16 normal_res=32 margin=0.1");
  const fluid::CacheStatus st = fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader,
                                                          fluid::CachePolicy::load_only, second);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_FALSE(second.rebaked);
  EXPECT_EQ(loads, 1);  // the second call read the file, it did not load the model
  EXPECT_EQ(second.source.model_fnv1a64, first.source.model_fnv1a64);
  ASSERT_EQ(second.collider.maps().size(), first.collider.maps().size());
  for (std::size_t m = 0; m < first.collider.maps().size(); ++m)
    EXPECT_EQ(second.collider.maps()[m].texels, first.collider.maps()[m].texels);
}

TEST(ColliderCache, ChangedModelIsStale) {
  Scratch s("stale");
  fluid::CachedCollider c;
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  const std::uint64_t old_hash = c.source.model_fnv1a64;
  s.writeModel("torus v2\n");  // one byte differs
  const fluid::CacheStatus st =
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_only, c);
  EXPECT_TRUE(contains(st.error, s.baked().string() + ": model_fnv1a64 ")) << st.error;
  EXPECT_TRUE(contains(st.error, "(the model changed)")) << st.error;
  // First use re-bakes it and records the new hash.
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  EXPECT_TRUE(c.rebaked);
  EXPECT_TRUE(contains(c.rebake_reason, "the model changed")) << c.rebake_reason;
  EXPECT_NE(c.source.model_fnv1a64, old_hash);
  fluid::ColliderSource on_disk;
  fluid::DepthMapCollider loaded;
  ASSERT_TRUE(fluid::loadCollider(s.baked(), loaded, &on_disk).ok());
  EXPECT_EQ(on_disk.model_fnv1a64, c.source.model_fnv1a64);
}

TEST(ColliderCache, ChangedRecipeIsStale) {
  Scratch s("recipe");
  fluid::CachedCollider c;
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  fluid::BakeRecipe finer = smallRecipe();
  finer.resolution = 64;
  const fluid::CacheStatus st =
      fluid::loadOrBakeCollider(s.model(), s.baked(), finer, torusLoader, fluid::CachePolicy::load_only, c);
  EXPECT_TRUE(contains(st.error, "recipe 'baker=3 maps=axes res=32")) << st.error;
  EXPECT_TRUE(contains(st.error, "bake parameters changed")) << st.error;
}

TEST(ColliderCache, CorruptOrMutatedFilesNameTheFileAndField) {
  Scratch s("corrupt");
  fluid::CachedCollider c;
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  const std::vector<std::uint8_t> good = readBytes(s.baked());
  const std::string name = s.baked().string();
  auto loadOnly = [&] {
    return fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_only, c)
        .error;
  };
  // A flipped texel byte: the checksum catches it.
  std::vector<std::uint8_t> bad = good;
  bad[200] ^= 0x40;
  writeBytes(s.baked(), bad);
  EXPECT_TRUE(contains(loadOnly(), name + ": byte ")) << loadOnly();
  EXPECT_TRUE(contains(loadOnly(), "checksum mismatch")) << loadOnly();
  // Truncated anywhere: an error, never a crash.
  for (std::size_t len : {std::size_t{0}, std::size_t{7}, std::size_t{30}, good.size() / 2, good.size() - 9}) {
    writeBytes(s.baked(), std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(len)));
    EXPECT_TRUE(contains(loadOnly(), name + ": byte ")) << len << ": " << loadOnly();
  }
  // A source record rewritten with a valid checksum but a malformed hash field.
  fluid::DepthMapCollider collider;
  fluid::ColliderSource source;
  ASSERT_TRUE(fluid::deserializeCollider(good, name, collider, &source).ok());
  std::vector<std::uint8_t> mutated = fluid::serializeCollider(collider, source);
  const std::string key = "model_fnv1a64=";
  const auto at = std::search(mutated.begin(), mutated.end(), key.begin(), key.end());
  ASSERT_NE(at, mutated.end());
  *(at + static_cast<std::ptrdiff_t>(key.size())) = 'z';
  std::uint64_t sum = 14695981039346656037ull;  // FNV-1a 64 of everything before the checksum
  for (std::size_t k = 0; k + 8 < mutated.size(); ++k) sum = (sum ^ mutated[k]) * 1099511628211ull;
  std::memcpy(mutated.data() + mutated.size() - 8, &sum, 8);
  writeBytes(s.baked(), mutated);
  EXPECT_TRUE(contains(loadOnly(), "source record: model_fnv1a64 'z")) << loadOnly();
  EXPECT_TRUE(contains(loadOnly(), "is not 16 hex digits")) << loadOnly();
  // First use replaces the damaged file and says why.
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  EXPECT_TRUE(c.rebaked);
  EXPECT_TRUE(contains(c.rebake_reason, "source record")) << c.rebake_reason;
  EXPECT_EQ(readBytes(s.baked()), good);  // the bake is deterministic
}

TEST(ColliderCache, VersionOneFilesLoadButAreStale) {
  Scratch s("v1");
  fluid::CachedCollider c;
  ASSERT_TRUE(
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_or_bake, c)
          .ok());
  // Version 1 layout: the same bytes without the source record (u32 length + text), and no
  // margin-ring flags (version 2 only).
  std::vector<fluid::DepthMap> maps = c.collider.maps();
  for (fluid::DepthMap& m : maps) m.margin_ring = false;
  std::vector<std::uint8_t> v1 =
      fluid::serializeCollider(fluid::DepthMapCollider(std::move(maps), c.collider.normalResolution()));
  v1.erase(v1.end() - 12, v1.end() - 8);
  const std::uint32_t one = 1;
  std::memcpy(v1.data() + 8, &one, 4);
  std::uint64_t sum = 14695981039346656037ull;
  for (std::size_t k = 0; k + 8 < v1.size(); ++k) sum = (sum ^ v1[k]) * 1099511628211ull;
  std::memcpy(v1.data() + v1.size() - 8, &sum, 8);
  fluid::DepthMapCollider loaded;
  fluid::ColliderSource source;
  ASSERT_TRUE(fluid::deserializeCollider(v1, "v1.fdm", loaded, &source).ok());
  EXPECT_TRUE(source.empty());
  writeBytes(s.baked(), v1);
  const fluid::CacheStatus st =
      fluid::loadOrBakeCollider(s.model(), s.baked(), smallRecipe(), torusLoader, fluid::CachePolicy::load_only, c);
  EXPECT_TRUE(contains(st.error, "no source record")) << st.error;
}

TEST(ColliderCache, LevelListErrorsNameFileAndLine) {
  Scratch s("level");
  const fs::path list = s.dir / "colliders" / "test.colliders";
  std::vector<fluid::CachedCollider> parts;
  auto load = [&](const std::string& text) {
    std::ofstream(list, std::ios::trunc) << text;
    return fluid::loadLevelColliders(s.dir, "test", torusLoader, fluid::CachePolicy::load_or_bake, parts).error;
  };
  EXPECT_TRUE(contains(load("# only a comment\n"), "no colliders listed"));
  EXPECT_TRUE(contains(load("\ntorus models/torus.obj axes 32\n"), list.string() + ":2: expected NAME MODEL"));
  EXPECT_TRUE(contains(load("torus models/torus.obj axes 32 cube8 32\n"), ":1: FORMAT 'cube8' unknown"));
  EXPECT_TRUE(contains(load("torus models/torus.obj axes 32 fixed8 32 abc\n"), ":1: MARGIN is not a number"));
  EXPECT_TRUE(contains(load("torus ../torus.obj axes 32 fixed8 32\n"), ":1: MODEL '../torus.obj' must be relative"));
  EXPECT_TRUE(contains(load("torus models/torus.obj axes 2 fixed8 32\n"), ":1: RES (4..4096)"));
  EXPECT_TRUE(contains(load("torus models/torus.obj wedge 32 fixed8 32\n"), "unknown item 'wedge'"));
  EXPECT_TRUE(parts.empty());
  ASSERT_EQ(load("torus models/torus.obj axes 32 front-back16 32 0.1  # comment\n"), "");
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].name, "torus");
  EXPECT_TRUE(fs::exists(s.baked()));
}

TEST(ColliderCache, MarginGivesPointsNearTheSilhouetteAFiniteDistance) {
  // A point off the torus's outer upper edge, 0.21 from the surface, whose x, y and z rays all
  // miss the torus (by 0.06 in each map): without a margin no map has a texel for it (beyond
  // reach); with a 0.1 margin it gets a finite, positive distance.
  const collide_test::Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 48, 16);
  const glm::vec3 p{1.36f, 0.0f, 0.36f};
  for (float margin : {0.0f, 0.1f}) {
    fluid::BakeRecipe r = smallRecipe();
    r.resolution = 128;
    r.margin = margin;
    std::vector<fluid::MapSpec> specs;
    std::string error;
    ASSERT_TRUE(fluid::recipeMapSpecs(r, fluid::meshBounds(torus.view()), specs, error)) << error;
    fluid::DepthMapCollider c;
    ASSERT_TRUE(fluid::bakeDepthMaps(torus.view(), specs, {32, 1}, c).ok());
    const fluid::ColliderSample got = c.sample(p);
    if (margin == 0.0f) {
      EXPECT_FALSE(got.valid);
    } else {
      ASSERT_TRUE(got.valid);
      EXPECT_GT(got.distance, 0.0f);
      EXPECT_LT(got.distance, 0.6f);
    }
  }
}

}  // namespace
