// fluiddemo bake-collider / query-collider: depth-map colliders (fluid/collide, Kolb et al.
// 2004 §4) baked from a model file and queried for signed distance and normal.
// Models are loaded with assimp here, in the game; fluid/collide only sees plain arrays.
#include "game/commands.hpp"

#include "fluid/collide/collide.hpp"
#include "fluid/io/particle_io.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <CLI/CLI.hpp>
#include <assimp/Importer.hpp>

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace game {

namespace {

struct LoadedMesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
};

// All triangles of all meshes, node transforms applied (aiProcess_PreTransformVertices).
bool loadModel(const std::string& path, LoadedMesh& out, std::string& error) {
  if (!std::filesystem::is_regular_file(path)) {
    error = path + ": no such file";
    return false;
  }
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                     aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    error = path + ": cannot load model: " + importer.GetErrorString();
    return false;
  }
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        error = path + ": mesh " + std::to_string(m) + " vertex " + std::to_string(v) + " has a non-finite coordinate";
        return false;
      }
      out.positions.push_back({p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines after triangulation
      for (int k = 0; k < 3; ++k) out.indices.push_back(base + face.mIndices[k]);
    }
  }
  if (out.indices.empty()) {
    error = path + ": the model has no triangles";
    return false;
  }
  return true;
}

}  // namespace

int bakeColliderCommand(const Args& args) {
  CLI::App app{"Bake depth-map colliders (Kolb et al. 2004 §4) from a model (OBJ and anything assimp reads).",
               "fluiddemo bake-collider"};
  std::string model, out_path, maps = "axes", format_name = "front-back16";
  int resolution = 256, normal_resolution = 256, threads = 0;
  bool force = false;
  app.add_option("MODEL", model, "model file (OBJ, glTF, PLY, ...)")->required();
  app.add_option("--out", out_path, "collider file to write")->required();
  app.add_option("--maps", maps,
                 "comma-separated maps: axes | x | y | z (front-back pairs along an axis), cube (GREATER cube at the "
                 "centre), cube-less, cube@X:Y:Z:H (LESS cube for a concave region)")
      ->capture_default_str();
  app.add_option("--res", resolution, "texels per side of every map (4..4096)")->capture_default_str();
  app.add_option("--format", format_name, "ortho map format: float | fixed8 | front-back16 (cubes are always cube8)")
      ->capture_default_str();
  app.add_option("--normal-res", normal_resolution, "L1 normal index resolution (2..256)")->capture_default_str();
  app.add_option("--threads", threads, "baking threads (0 = all)")->capture_default_str();
  app.add_flag("--force", force, "replace --out if it exists");
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  fluid::DepthMapFormat format;
  if (!fluid::parseFormat(format_name, format) || format == fluid::DepthMapFormat::cube8) {
    std::fprintf(stderr, "bake-collider: --format '%s' unknown (expected float, fixed8 or front-back16)\n",
                 format_name.c_str());
    return 2;
  }
  if (resolution < 4 || resolution > 4096) {
    std::fprintf(stderr, "bake-collider: --res %d out of range 4..4096\n", resolution);
    return 2;
  }
  if (!force && std::filesystem::exists(out_path)) {
    std::fprintf(stderr, "bake-collider: %s already exists (use --force to replace it)\n", out_path.c_str());
    return 1;
  }
  LoadedMesh mesh;
  std::string error;
  if (!loadModel(model, mesh, error)) {
    std::fprintf(stderr, "bake-collider: %s\n", error.c_str());
    return 1;
  }
  const fluid::MeshView view{mesh.positions, mesh.indices};
  std::vector<fluid::MapSpec> specs;
  if (!fluid::parseMapSpec(maps, fluid::meshBounds(view), resolution, format, specs, error)) {
    std::fprintf(stderr, "bake-collider: %s\n", error.c_str());
    return 2;
  }
  fluid::DepthMapCollider collider;
  const fluid::BakeStatus status = fluid::bakeDepthMaps(view, specs, {normal_resolution, threads}, collider);
  if (!status.ok()) {
    std::fprintf(stderr, "bake-collider: %s: %s\n", model.c_str(), status.error.c_str());
    return 1;
  }
  const fluid::FileStatus saved =
      fluid::saveCollider(out_path, collider, force ? fluid::Overwrite::replace : fluid::Overwrite::refuse);
  if (!saved.ok()) {
    std::fprintf(stderr, "bake-collider: %s\n", saved.error.c_str());
    return 1;
  }
  std::printf("%s: %zu triangles (%zu degenerate skipped) -> %s: %zu textures, %d depth maps, %zu bytes\n",
              model.c_str(), mesh.indices.size() / 3, status.degenerate_triangles, out_path.c_str(),
              collider.maps().size(), collider.depthMapCount(), collider.bytes());
  return 0;
}

int queryColliderCommand(const Args& args) {
  CLI::App app{
      "Signed distance (negative inside) and unit outward normal per point, one line `d nx ny nz` per input "
      "point in order. Points no depth map has a distance for (outside the collider) print `inf 0 0 0`.",
      "fluiddemo query-collider"};
  std::string collider_path, points_path;
  int threads = 0;
  app.add_option("FILE", collider_path, "collider file from bake-collider")->required();
  app.add_option("--points", points_path, "points (.xyz, .csv or .ply), collider space")->required();
  app.add_option("--threads", threads, "query threads (0 = all)")->capture_default_str();
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  fluid::DepthMapCollider collider;
  const fluid::FileStatus loaded = fluid::loadCollider(collider_path, collider);
  if (!loaded.ok()) {
    std::fprintf(stderr, "query-collider: %s\n", loaded.error.c_str());
    return 1;
  }
  fluid::ParticlePositions particles;
  const fluid::IoStatus read = fluid::readParticleFile(points_path, particles);  // rejects NaN/inf with file:line
  if (!read.ok()) {
    std::fprintf(stderr, "query-collider: %s\n", read.error.c_str());
    return 1;
  }
  std::vector<glm::vec3> points(particles.size());
  for (std::size_t k = 0; k < points.size(); ++k) points[k] = particles.at(k);
  std::vector<fluid::ColliderSample> samples(points.size());
  fluid::queryParallel(collider, points, samples, {threads});
  std::size_t unknown = 0;
  for (const fluid::ColliderSample& s : samples) {
    if (!s.valid) {
      ++unknown;
      std::printf("inf 0 0 0\n");
    } else {
      std::printf("%.9g %.9g %.9g %.9g\n", s.distance, s.normal.x, s.normal.y, s.normal.z);
    }
  }
  if (unknown > 0) {
    std::fprintf(stderr, "query-collider: %zu of %zu points are outside every map's reach (printed as inf 0 0 0)\n",
                 unknown, samples.size());
  }
  return 0;
}

}  // namespace game
