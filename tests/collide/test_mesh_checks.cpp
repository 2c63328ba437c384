// Checks before a bake: closedness after welding (fluid::checkClosed), the coordinate limit, and
// every model shipped in content/models read as bake-collider reads it.
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"
#include "fluid/collide/mesh_checks.hpp"
#include "game/world/collider_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace {

namespace fs = std::filesystem;

TEST(MeshChecks, ClosedTorusIsClosedAndLosingATriangleOpensIt) {
  collide_test::Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 24, 8);
  fluid::ClosedMeshReport report = fluid::checkClosed(torus.view());
  EXPECT_TRUE(report.closed());
  EXPECT_EQ(report.boundary_edges, 0u);
  torus.indices.resize(torus.indices.size() - 3);  // one hole: its three edges are boundary edges
  report = fluid::checkClosed(torus.view());
  EXPECT_FALSE(report.closed());
  EXPECT_EQ(report.boundary_edges, 3u);
}

TEST(MeshChecks, CoincidentVerticesAreWeldedBeforeCounting) {
  // A tetrahedron whose four faces each have their own three vertices (as OBJ exporters with
  // per-face normals write them), one copy at -0.0 instead of +0.0: closed after welding.
  const glm::vec3 corner[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  for (const auto& face : faces) {
    for (int k : face) {
      indices.push_back(static_cast<std::uint32_t>(positions.size()));
      positions.push_back(corner[k]);
    }
  }
  positions[0].x = -0.0f;
  const fluid::ClosedMeshReport report = fluid::checkClosed({positions, indices});
  EXPECT_EQ(report.welded_vertices, 4u);
  EXPECT_TRUE(report.closed()) << report.boundary_edges;
  // Moving one copy apart opens the two faces' shared edges.
  positions[3] = {1.0f, 1e-3f, 0.0f};
  EXPECT_FALSE(fluid::checkClosed({positions, indices}).closed());
}

TEST(MeshChecks, VerticesBeyondTheLimitOrNonFiniteAreFoundAndNotBaked) {
  std::vector<glm::vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_EQ(fluid::firstBadVertex(positions), -1);
  positions[2].y = 1e30f;
  EXPECT_EQ(fluid::firstBadVertex(positions), 2);
  positions[2].y = fluid::kMaxColliderCoordinate;
  EXPECT_EQ(fluid::firstBadVertex(positions), -1);
  positions[1].z = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(fluid::firstBadVertex(positions), 1);

  collide_test::Mesh torus = collide_test::makeTorus(1.0f, 0.3f, 12, 6);
  torus.positions[5].x = -2e5f;
  const auto specs = fluid::defaultMapSpecs({glm::vec3(-2), glm::vec3(2)}, 16);
  fluid::DepthMapCollider collider;
  const fluid::BakeStatus status = fluid::bakeDepthMaps(torus.view(), specs, {}, collider);
  EXPECT_NE(status.error.find("vertex 5 at (-200000, "), std::string::npos) << status.error;
  EXPECT_NE(status.error.find("beyond the collider coordinate limit"), std::string::npos) << status.error;
}

TEST(ContentModels, EveryShippedModelIsClosed) {
  const fs::path models = fs::path(FLUIDDEMO_SOURCE_DIR) / "content" / "models";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(models)) {
    if (entry.path().extension() != ".obj") continue;
    game::ColliderModel model;
    std::string error;
    ASSERT_TRUE(game::loadColliderModel(entry.path().string(), model, error)) << error;
    EXPECT_EQ(game::openMeshMessage(model, entry.path().filename().string()), "");
    ++checked;
  }
  EXPECT_GE(checked, 4);  // basin, crate, ground, statue
  // The check itself: an open model is reported, with the file and a boundary edge.
  game::ColliderModel open;
  std::string error;
  const fs::path open_box = fs::path(FLUIDDEMO_SOURCE_DIR) / "tests" / "collide" / "data" / "open_box.obj";
  ASSERT_TRUE(game::loadColliderModel(open_box.string(), open, error)) << error;
  const std::string message = game::openMeshMessage(open, "open_box.obj");
  EXPECT_EQ(message.rfind("open_box.obj: the mesh is open: 4 boundary edges", 0), 0u) << message;
}

TEST(ContentModels, ModelLoaderOpensNoDevicesOrOtherFilesFromMemory) {
  // A material library naming a device must not be read (it would block or never end).
  const std::string obj = "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  game::ColliderModel model;
  std::string error;
  ASSERT_TRUE(game::loadColliderModelFromMemory(
      std::span(reinterpret_cast<const std::uint8_t*>(obj.data()), obj.size()), "obj", "mem.obj", model, error))
      << error;
  EXPECT_EQ(model.indices.size(), 3u);
}

}  // namespace
