// Versioned collider files: round trip, and wrong/garbage/truncated files are rejected.
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace {

fluid::DepthMapCollider smallCollider() {
  const collide_test::Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 24, 8);
  std::vector<fluid::MapSpec> specs =
      fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 16, fluid::DepthMapFormat::front_back16, true);
  const auto f32 = fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 8, fluid::DepthMapFormat::float32);
  const auto fx8 = fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 8, fluid::DepthMapFormat::fixed8);
  specs.push_back(f32[0]);
  specs.push_back(fx8[1]);
  fluid::DepthMapCollider c;
  EXPECT_TRUE(fluid::bakeDepthMaps(torus.view(), specs, {64, 1}, c).ok());
  return c;
}

std::filesystem::path tempPath(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("fluiddemo_collide_" + std::to_string(::getpid()) + "_" + name);
}

TEST(ColliderFile, RoundTripsEveryFormat) {
  const fluid::DepthMapCollider c = smallCollider();
  const auto path = tempPath("roundtrip.fdm");
  std::filesystem::remove(path);
  ASSERT_TRUE(fluid::saveCollider(path, c).ok());
  fluid::DepthMapCollider back;
  const fluid::FileStatus st = fluid::loadCollider(path, back);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_EQ(back.normalResolution(), 64);
  ASSERT_EQ(back.maps().size(), c.maps().size());
  for (std::size_t m = 0; m < c.maps().size(); ++m) {
    EXPECT_EQ(back.maps()[m].format, c.maps()[m].format);
    EXPECT_EQ(back.maps()[m].texels, c.maps()[m].texels);
    EXPECT_EQ(back.maps()[m].collider_to_map, c.maps()[m].collider_to_map);
    EXPECT_EQ(back.maps()[m].encloses_collider, c.maps()[m].encloses_collider);
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f);
  for (int k = 0; k < 1000; ++k) {
    const glm::vec3 p{u(rng), u(rng), u(rng)};
    const fluid::ColliderSample a = c.sample(p), b = back.sample(p);
    ASSERT_EQ(a.distance, b.distance);
    ASSERT_EQ(a.normal, b.normal);
  }
  // Nothing the user made is overwritten without asking.
  const fluid::FileStatus again = fluid::saveCollider(path, c);
  EXPECT_NE(again.error.find("already exists"), std::string::npos);
  EXPECT_TRUE(fluid::saveCollider(path, c, fluid::Overwrite::replace).ok());
  std::filesystem::remove(path);
}

TEST(ColliderFile, RejectsWrongMagicVersionAndCorruption) {
  const std::vector<std::uint8_t> good = fluid::serializeCollider(smallCollider());
  fluid::DepthMapCollider out;
  ASSERT_TRUE(fluid::deserializeCollider(good, "good", out).ok());

  auto bad = good;
  bad[0] = 'X';
  EXPECT_NE(fluid::deserializeCollider(bad, "f", out).error.find("bad magic"), std::string::npos);
  bad = good;
  bad[8] = 3;  // version 3 (this build reads 1 and 2)
  EXPECT_NE(fluid::deserializeCollider(bad, "f", out).error.find("unsupported version 3"), std::string::npos);
  bad = good;
  bad[bad.size() / 2] ^= 0x40;  // a texel byte
  EXPECT_NE(fluid::deserializeCollider(bad, "f", out).error.find("checksum"), std::string::npos);
  bad = good;
  bad.push_back(0);
  EXPECT_FALSE(fluid::deserializeCollider(bad, "f", out).ok());
  bad = good;
  bad[24] = 9;  // first map's format
  EXPECT_NE(fluid::deserializeCollider(bad, "f", out).error.find("map 0: unknown format 9"), std::string::npos);
  // Every truncation is an error, never a crash or a partial collider.
  for (std::size_t len = 0; len < good.size(); len += (len < 200 ? 1 : 97)) {
    ASSERT_FALSE(fluid::deserializeCollider(std::span(good.data(), len), "f", out).ok()) << len;
  }
  // Random garbage.
  std::mt19937 rng(2);
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> junk(static_cast<std::size_t>(rng() % 4096));
    for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
    if (k % 2 == 0 && junk.size() >= 8) std::copy(good.begin(), good.begin() + 8, junk.begin());
    EXPECT_FALSE(fluid::deserializeCollider(junk, "f", out).ok());
  }
  const fluid::FileStatus missing = fluid::loadCollider(tempPath("does_not_exist.fdm"), out);
  EXPECT_NE(missing.error.find("cannot open"), std::string::npos);
}

}  // namespace
