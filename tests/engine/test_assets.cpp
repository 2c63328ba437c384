#include "engine/assets/assets.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace {

namespace fs = std::filesystem;

class AssetFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fluiddemo_assets_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& bytes) {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  static std::string readAll(const fs::path& path) {
    std::ifstream file(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  }
  fs::path dir_;
};

const fs::path kContent = fs::path(FLUIDDEMO_SOURCE_DIR) / "content";

TEST_F(AssetFiles, ProjectModelsAndTexturesLoad) {
  engine::MeshData mesh;
  std::string error;
  ASSERT_TRUE(engine::loadMesh(kContent / "models" / "crate.obj", mesh, error)) << error;
  EXPECT_EQ(mesh.indices.size(), 36u);  // 6 faces x 2 triangles
  EXPECT_EQ(mesh.positions.size(), mesh.normals.size());
  EXPECT_NEAR(mesh.bounds_max.x - mesh.bounds_min.x, 1.0f, 1e-5f);
  for (const char* name : {"basin.obj", "statue.obj", "ground.obj"}) {
    ASSERT_TRUE(engine::loadMesh(kContent / "models" / name, mesh, error)) << error;
    EXPECT_GT(mesh.indices.size(), 0u);
  }
  engine::ImageData image;
  ASSERT_TRUE(engine::loadImage(kContent / "textures" / "paving.png", image, error)) << error;
  EXPECT_EQ(image.width, 256);
  EXPECT_EQ(image.rgba.size(), 256u * 256u * 4u);
}

TEST_F(AssetFiles, GltfWithEmbeddedBufferLoads) {
  // One triangle: 3 float3 positions (36 bytes) then 3 uint16 indices (+2 padding), base64.
  const std::string gltf = R"({
    "asset": {"version": "2.0"},
    "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "translation": [0, 2, 0]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"byteLength": 44,
                 "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })";
  engine::MeshData mesh;
  std::string error;
  ASSERT_TRUE(engine::loadMesh(write("triangle.gltf", gltf), mesh, error)) << error;
  EXPECT_EQ(mesh.indices.size(), 3u);
  EXPECT_NEAR(mesh.bounds_min.y, 2.0f, 1e-6f);  // the node's translation is applied
  EXPECT_NEAR(mesh.bounds_max.y, 3.0f, 1e-6f);
}

TEST_F(AssetFiles, MissingFilesAreNamed) {
  engine::MeshData mesh;
  engine::ImageData image;
  std::string error;
  EXPECT_FALSE(engine::loadMesh(dir_ / "nope.obj", mesh, error));
  EXPECT_NE(error.find("nope.obj"), std::string::npos) << error;
  EXPECT_NE(error.find("not found"), std::string::npos) << error;
  EXPECT_FALSE(engine::loadImage(dir_ / "nope.png", image, error));
  EXPECT_NE(error.find("nope.png"), std::string::npos) << error;
}

TEST_F(AssetFiles, EmptyGarbageAndTruncatedModelsFailWithTheFileName) {
  engine::MeshData mesh;
  std::string error;
  EXPECT_FALSE(engine::loadMesh(write("empty.obj", ""), mesh, error));
  EXPECT_NE(error.find("empty.obj"), std::string::npos) << error;

  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage.push_back(static_cast<char>((i * 7919) % 251));
  EXPECT_FALSE(engine::loadMesh(write("garbage.obj", garbage), mesh, error));
  EXPECT_NE(error.find("garbage.obj"), std::string::npos) << error;
  EXPECT_FALSE(
      engine::loadMesh(write("garbage.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [tru"), mesh, error));
  EXPECT_NE(error.find("garbage.gltf"), std::string::npos) << error;

  // Cut inside the vertex list: no faces survive, so the model is rejected.
  const std::string crate = readAll(kContent / "models" / "crate.obj");
  const std::size_t cut = crate.find("vt ");
  ASSERT_NE(cut, std::string::npos);
  EXPECT_FALSE(engine::loadMesh(write("truncated.obj", crate.substr(0, cut)), mesh, error));
  EXPECT_NE(error.find("truncated.obj"), std::string::npos) << error;
  EXPECT_TRUE(mesh.indices.empty());
}

TEST_F(AssetFiles, TruncatedAndGarbageImagesFailWithTheFileName) {
  engine::ImageData image;
  std::string error;
  const std::string png = readAll(kContent / "textures" / "crate.png");
  ASSERT_GT(png.size(), 100u);
  EXPECT_FALSE(engine::loadImage(write("truncated.png", png.substr(0, png.size() / 3)), image, error));
  EXPECT_NE(error.find("truncated.png"), std::string::npos) << error;
  EXPECT_FALSE(engine::loadImage(write("header_only.png", png.substr(0, 20)), image, error));
  EXPECT_NE(error.find("header_only.png"), std::string::npos) << error;
  EXPECT_FALSE(engine::loadImage(write("garbage.png", std::string(3000, '\x5a')), image, error));
  EXPECT_NE(error.find("garbage.png"), std::string::npos) << error;
  EXPECT_TRUE(image.rgba.empty());
}

}  // namespace
