// Bake a depth-map collider (Kolb et al. 2004, fluid/collide) from an OBJ and query points.
//   bake_collider model.obj [resolution] [x y z ...]
// Prints the signed distance (negative inside) and the outward normal at each point; without
// points it queries the centre of the model's bounds and a point just beyond its top.
#include "fluid/collide/collide.hpp"
#include "fluid/io/obj_mesh.hpp"

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s model.obj [resolution=128] [x y z ...]\n", argv[0]);
    return 2;
  }
  fluid::ObjMesh model;
  if (const fluid::IoStatus read = fluid::readObjMesh(argv[1], model); !read.ok()) {
    std::fprintf(stderr, "%s\n", read.error.c_str());
    return 1;
  }
  const int resolution = argc > 2 ? std::atoi(argv[2]) : 128;

  // Three front-back pairs along x, y and z over the padded bounds (the paper's §5.2 set).
  const fluid::MeshView view{model.positions, model.indices};
  const fluid::Bounds bounds = fluid::meshBounds(view);
  const std::vector<fluid::MapSpec> specs = fluid::defaultMapSpecs(bounds, resolution);
  fluid::DepthMapCollider collider;
  if (const fluid::BakeStatus baked = fluid::bakeDepthMaps(view, specs, {}, collider); !baked.ok()) {
    std::fprintf(stderr, "%s: %s\n", argv[1], baked.error.c_str());
    return 1;
  }

  std::vector<glm::vec3> points;
  for (int i = 3; i + 2 < argc; i += 3)
    points.push_back({std::strtof(argv[i], nullptr), std::strtof(argv[i + 1], nullptr), std::strtof(argv[i + 2], nullptr)});
  if (points.empty()) {
    const glm::vec3 centre = 0.5f * (bounds.lo + bounds.hi);
    points = {centre, {centre.x, bounds.hi.y + 0.1f, centre.z}};
  }
  std::vector<fluid::ColliderSample> samples(points.size());
  collider.query(points, samples);  // collider space = the model's coordinates

  std::printf("%s: %zu triangles, %d depth maps, %zu bytes\n", argv[1], model.indices.size() / 3,
              collider.depthMapCount(), collider.bytes());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const fluid::ColliderSample& s = samples[i];
    std::printf("(%g, %g, %g): %s distance %g, normal (%g, %g, %g)\n", points[i].x, points[i].y, points[i].z,
                s.valid ? "" : "(beyond reach)", s.distance, s.normal.x, s.normal.y, s.normal.z);
  }
  return 0;
}
