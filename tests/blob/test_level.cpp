// The blob against the level's own models (content/models/blob_*.obj from
// scripts/generate_content.py), baked into depth-map colliders (Kolb et al. 2004, fluid/collide) as
// the game will: it emerges from the sewer bore, and no particle ends inside the exact mesh.
#include "blob_test_level.hpp"
#include "fluid/collide/collide.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace {

struct ObjMesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  fluid::MeshView view() const { return {positions, indices}; }
};

// Positions and triangles of a generated OBJ ("v x y z", "f a/b/c ..." with 1-based indices).
ObjMesh readObj(const std::string& path) {
  ObjMesh mesh;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      glm::vec3 p;
      s >> p.x >> p.y >> p.z;
      mesh.positions.push_back(p);
    } else if (tag == "f") {
      std::string corner;
      while (s >> corner) mesh.indices.push_back(static_cast<std::uint32_t>(std::stoul(corner)) - 1);
    }
  }
  return mesh;
}

std::shared_ptr<fluid::DepthMapCollider> bake(const ObjMesh& mesh, const std::string& maps) {
  std::vector<fluid::MapSpec> specs;
  std::string error;
  EXPECT_TRUE(
      fluid::parseMapSpec(maps, fluid::meshBounds(mesh.view()), 128, fluid::DepthMapFormat::front_back16, specs, error))
      << error;
  auto collider = std::make_shared<fluid::DepthMapCollider>();
  const fluid::BakeStatus st = fluid::bakeDepthMaps(mesh.view(), specs, {}, *collider);
  EXPECT_TRUE(st.ok()) << st.error;
  return collider;
}

TEST(BlobLevel, EmergesFromTheBakedSewerAndStaysOutOfTheLevel) {
  const std::string models = std::string(FLUIDDEMO_SOURCE_DIR) + "/content/models/";
  const ObjMesh street = readObj(models + "blob_street.obj");
  const ObjMesh sewer = readObj(models + "blob_sewer.obj");
  ASSERT_FALSE(street.indices.empty());
  ASSERT_FALSE(sewer.indices.empty());
  fluid::BlobWorld w;
  ASSERT_TRUE(fluid::initBlob(w, glm::vec3(0.0f)).ok());
  // The bore is concave: the axis pairs cannot see its walls, a LESS depth cube at its centre does
  // (Kolb §4.1, §4.3), as issue 18 asks of every concave level model.
  w.colliders.push_back(blobtest::collider(bake(street, "axes")));
  w.colliders.push_back(blobtest::collider(bake(sewer, "axes,cube@0:-1.15:0:1.3")));
  const float pipe = 0.45f;  // BLOB_PIPE_RADIUS in scripts/generate_content.py
  ASSERT_TRUE(fluid::placeBlob(w, fluid::blobColumn(w.params, glm::vec3(0.0f, -0.05f, 0.0f), pipe)).ok());
  fluid::BlobBehaviour b;
  b.kind = fluid::BlobBehaviourKind::emerge;
  const float t = blobtest::runUntilGoal(w, b, 4.0f);
  // Exact signed distance to the models (BVH reference), not the baked maps.
  const fluid::MeshDistance exact_street(street.view()), exact_sewer(sewer.view());
  float worst = 1e30f;
  for (const glm::vec3& x : w.particles.position)
    worst = std::min({worst, exact_street.sample(x).distance, exact_sewer.sample(x).distance});
  std::printf(
      "[blob] level: emerged from the baked sewer after %.2f s; nearest particle %.4f m from the models "
      "(negative: inside)\n",
      t, worst);
  EXPECT_GT(t, 0.0f);
  EXPECT_GE(worst, -0.02f);  // within a texel of the 128^2 maps (1.3-2.4 cm)
}

// blobDepthMapBounds (the cull that lets particles far from a collider skip its queries): no point
// the baked maps call inside lies outside the box, and a body stepped with the boxes ends
// bit-identical to one stepped without them.
TEST(BlobLevel, DepthMapBoundsHoldEveryInsidePointAndChangeNothing) {
  const std::string models = std::string(FLUIDDEMO_SOURCE_DIR) + "/content/models/";
  const std::vector<std::shared_ptr<fluid::DepthMapCollider>> shapes = {
      bake(readObj(models + "blob_street.obj"), "axes"),
      bake(readObj(models + "blob_sewer.obj"), "axes,cube@0:-1.15:0:1.3"),
      bake(readObj(models + "blob_wall.obj"), "axes")};
  std::size_t inside = 0, outside_box = 0;
  for (std::size_t m = 0; m < shapes.size(); ++m) {
    const auto& shape = shapes[m];
    fluid::BlobCollider c = blobtest::collider(shape);
    fluid::blobDepthMapBounds(c, *shape);
    ASSERT_TRUE(c.bounded);
    std::printf("[blob] depth-map bounds of collider %zu: (%.3f %.3f %.3f) .. (%.3f %.3f %.3f)\n", m, c.inside_lo.x,
                c.inside_lo.y, c.inside_lo.z, c.inside_hi.x, c.inside_hi.y, c.inside_hi.z);
    // The box is the surfaces' extent (to a texel), not the maps' volumes (0.16 m margin): the
    // street's top is y = 0, so the body resting on it is outside the box but for its lowest layer.
    if (m == 0) {
      EXPECT_LT(c.inside_hi.y, 0.05f);
    }
    // Points on a grid over the box widened by 1 m on every side (the street: its central 6 m).
    glm::vec3 lo = c.inside_lo - 1.0f, hi = c.inside_hi + 1.0f;
    lo = glm::max(lo, glm::vec3(-3.0f, -4.0f, -3.0f)), hi = glm::min(hi, glm::vec3(3.0f, 5.0f, 3.0f));
    const int n = 48;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const glm::vec3 p = lo + (hi - lo) * (glm::vec3(i, j, k) + 0.5f) / static_cast<float>(n);
          const fluid::ColliderSample s = shape->sample(p);
          const bool in_box =
              glm::all(glm::greaterThanEqual(p, c.inside_lo)) && glm::all(glm::lessThanEqual(p, c.inside_hi));
          outside_box += !in_box;
          if (s.valid && s.distance < 0.0f) {
            ++inside;
            EXPECT_TRUE(in_box) << "inside point " << p.x << " " << p.y << " " << p.z << " outside the box";
          }
        }
  }
  EXPECT_GT(inside, 1000u);
  EXPECT_GT(outside_box, 1000u);

  // The same run (emerge out of the sewer, then a chase toward the wall) with and without the boxes.
  auto run = [&](bool bounded) {
    fluid::BlobWorld w;
    EXPECT_TRUE(fluid::initBlob(w, glm::vec3(0.0f)).ok());
    for (const auto& shape : shapes) {
      w.colliders.push_back(blobtest::collider(shape));
      if (bounded) fluid::blobDepthMapBounds(w.colliders.back(), *shape);
    }
    EXPECT_TRUE(fluid::placeBlob(w, fluid::blobColumn(w.params, glm::vec3(0.0f, -0.05f, 0.0f), 0.45f)).ok());
    fluid::BlobBehaviour b;
    b.kind = fluid::BlobBehaviourKind::emerge;
    blobtest::runUntilGoal(w, b, 1.5f, glm::vec3(0.0f), false);
    return w.particles.position;
  };
  const std::vector<glm::vec3> with = run(true), without = run(false);
  ASSERT_EQ(with.size(), without.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < with.size(); ++i) differ += with[i] != without[i];
  EXPECT_EQ(differ, 0u);
  std::printf(
      "[blob] depth-map bounds: %zu inside points, all in the boxes; %zu grid points outside them; %zu of %zu "
      "particles differ with the cull\n",
      inside, outside_box, differ, with.size());
}

}  // namespace
