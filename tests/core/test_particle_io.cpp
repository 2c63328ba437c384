#include "fluid/io/particle_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace {

namespace fs = std::filesystem;

fs::path scratchDir() {
  fs::path dir =
      fs::temp_directory_path() / ("fluiddemo_io_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                   "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(ParticleIo, ParsesXyzWithCommentsAndBlankLines) {
  fluid::ParticlePositions particles;
  const auto status = fluid::parseParticleText("# header\n1 2 3\n\n  -4.5\t5e1 +6 extra\n", "xyz", "t.xyz", particles);
  ASSERT_TRUE(status.ok()) << status.error;
  ASSERT_EQ(particles.size(), 2u);
  EXPECT_EQ(particles.at(1), glm::vec3(-4.5f, 50.0f, 6.0f));
}

TEST(ParticleIo, ReportsFileAndLineOfMalformedXyz) {
  fluid::ParticlePositions particles;
  auto status = fluid::parseParticleText("1 2 3\n1 two 3\n", "xyz", "bad.xyz", particles);
  EXPECT_EQ(status.error, "bad.xyz:2: 'two' is not a number");
  EXPECT_TRUE(particles.empty());
  status = fluid::parseParticleText("1 2 3\n4 5\n", "xyz", "short.xyz", particles);
  EXPECT_EQ(status.error, "short.xyz:2: expected 3 coordinates, found 2");
}

TEST(ParticleIo, RejectsNanAndInfinity) {
  fluid::ParticlePositions particles;
  auto status = fluid::parseParticleText("1 2 3\n\n1 nan 3\n", "xyz", "n.xyz", particles);
  EXPECT_NE(status.error.find("n.xyz:3: coordinate y is not a finite float"), std::string::npos) << status.error;
  status = fluid::parseParticleText("1 2 inf\n", "xyz", "i.xyz", particles);
  EXPECT_NE(status.error.find("i.xyz:1: coordinate z"), std::string::npos) << status.error;
  status = fluid::parseParticleText("1 2 1e300\n", "xyz", "big.xyz", particles);
  EXPECT_FALSE(status.ok());
}

TEST(ParticleIo, CsvWithHeaderPicksColumnsByName) {
  fluid::ParticlePositions particles;
  const auto status = fluid::parseParticleText("id,z,y,x\n7,3,2,1\n", "csv", "p.csv", particles);
  ASSERT_TRUE(status.ok()) << status.error;
  ASSERT_EQ(particles.size(), 1u);
  EXPECT_EQ(particles.at(0), glm::vec3(1, 2, 3));
  EXPECT_FALSE(fluid::parseParticleText("a,b,c\n1,2,3\n", "csv", "h.csv", particles).ok());
}

TEST(ParticleIo, AsciiPlyWithExtraProperties) {
  fluid::ParticlePositions particles;
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n1 2 3 255\n4 5 6 0\n";
  const auto status = fluid::parseParticleText(ply, "ply", "a.ply", particles);
  ASSERT_TRUE(status.ok()) << status.error;
  ASSERT_EQ(particles.size(), 2u);
  EXPECT_EQ(particles.at(1), glm::vec3(4, 5, 6));
}

TEST(ParticleIo, BinaryPlyRoundTripsAndTruncationIsReported) {
  const fs::path dir = scratchDir();
  fluid::ParticlePositions particles;
  particles.push_back({1.5f, -2.25f, 1e5f});
  particles.push_back({0.1f, 0.2f, 0.3f});
  ASSERT_TRUE(fluid::writeParticlePly(dir / "p.ply", particles).ok());
  fluid::ParticlePositions loaded;
  auto status = fluid::readParticleFile(dir / "p.ply", loaded);
  ASSERT_TRUE(status.ok()) << status.error;
  EXPECT_EQ(loaded, particles);

  const auto size = fs::file_size(dir / "p.ply");
  fs::resize_file(dir / "p.ply", size - 5);
  status = fluid::readParticleFile(dir / "p.ply", loaded);
  // The vertex count is checked against the bytes after the header before anything is read.
  EXPECT_NE(status.error.find("p.ply:4: element vertex claims 2 items but only 19 bytes follow the header"),
            std::string::npos)
      << status.error;
  EXPECT_TRUE(loaded.empty());
}

TEST(ParticleIo, XyzRoundTripIsExactAndRefusesToOverwrite) {
  const fs::path dir = scratchDir();
  fluid::ParticlePositions particles;
  particles.push_back({0.1f, 1.0f / 3.0f, 12345.678f});
  ASSERT_TRUE(fluid::writeParticleXyz(dir / "a.xyz", particles).ok());
  fluid::ParticlePositions loaded;
  ASSERT_TRUE(fluid::readParticleFile(dir / "a.xyz", loaded).ok());
  EXPECT_EQ(loaded, particles);

  const auto refused = fluid::writeParticleXyz(dir / "a.xyz", {});
  EXPECT_NE(refused.error.find("already exists"), std::string::npos);
  ASSERT_TRUE(fluid::readParticleFile(dir / "a.xyz", loaded).ok());
  EXPECT_EQ(loaded.size(), 1u);  // the user's file is intact
  EXPECT_TRUE(fluid::writeParticleXyz(dir / "a.xyz", {}, fluid::OverwritePolicy::replace).ok());
}

TEST(ParticleIo, MissingFileAndUnknownExtension) {
  fluid::ParticlePositions particles;
  EXPECT_NE(fluid::readParticleFile("/nonexistent/p.xyz", particles).error.find("/nonexistent/p.xyz: cannot open"),
            std::string::npos);
  EXPECT_NE(fluid::readParticleFile("points.txt", particles).error.find("unknown particle file extension '.txt'"),
            std::string::npos);
  EXPECT_FALSE(fluid::readParticleFile(fs::temp_directory_path() / "dir.xyz/..", particles).ok());
}

TEST(ParticleIo, GarbagePlyHeaderIsRejected) {
  fluid::ParticlePositions particles;
  EXPECT_FALSE(fluid::parseParticleText("ply\nformat ascii 1.0\nelement vertex 3\n", "ply", "t.ply", particles).ok());
  EXPECT_FALSE(fluid::parseParticleText("plx\n", "ply", "t.ply", particles).ok());
  EXPECT_FALSE(
      fluid::parseParticleText("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "ply", "t.ply", particles)
          .ok());
  const auto status = fluid::parseParticleText(
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 "
      "3\n",
      "ply", "t.ply", particles);
  EXPECT_NE(status.error.find("file ends after 1 of 2 vertex lines"), std::string::npos) << status.error;
}

}  // namespace
