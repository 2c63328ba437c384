#include "fluid/surface/mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

namespace fluid {
namespace {

struct Welded {
  std::vector<glm::vec3> positions, normals;
  std::vector<std::uint32_t> indices;
};

Welded weld(const SurfaceMesh& m, const MeshWriteOptions& o) {
  Welded w;
  std::vector<std::uint32_t> order(m.positions.size()), remap(m.positions.size());
  std::iota(order.begin(), order.end(), 0u);
  if (o.weldSeams && m.edgeKeys.size() == m.positions.size()) {
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return m.edgeKeys[a] < m.edgeKeys[b]; });
  }
  std::vector<std::uint32_t> firstOf;  // welded index -> source vertex
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::uint32_t v = order[i];
    const bool same = o.weldSeams && i > 0 && m.edgeKeys[order[i - 1]] == m.edgeKeys[v] &&
                      m.positions[firstOf.back()] == m.positions[v];
    if (!same) firstOf.push_back(v);
    remap[v] = std::uint32_t(firstOf.size() - 1);
  }
  // Keep first-use order so the file reads like the mesh.
  std::vector<std::uint32_t> rank(firstOf.size(), ~0u);
  const glm::dvec3 origin(o.originX, o.originY, o.originZ);
  for (std::uint32_t idx : m.indices) {
    std::uint32_t& r = rank[remap[idx]];
    if (r == ~0u) {
      r = std::uint32_t(w.positions.size());
      const std::uint32_t src = firstOf[remap[idx]];
      w.positions.push_back(glm::vec3(glm::dvec3(m.positions[src]) + origin));
      w.normals.push_back(m.normals[src]);
    }
    w.indices.push_back(r);
  }
  return w;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

IoStatus writeSurfaceMesh(const std::filesystem::path& path, const SurfaceMesh& mesh, const MeshWriteOptions& options) {
  const std::string ext = lower(path.extension().string());
  if (ext != ".obj" && ext != ".ply") return {path.string() + ": unknown mesh format '" + ext + "' (use .obj or .ply)"};
  std::error_code ec;
  if (options.overwrite == OverwritePolicy::refuse && std::filesystem::exists(path, ec))
    return {path.string() + ": exists; not overwriting (use --force to replace it)"};
  if (mesh.normals.size() != mesh.positions.size() || mesh.indices.size() % 3 != 0)
    return {path.string() + ": inconsistent mesh (normals or indices)"};
  for (std::uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) return {path.string() + ": index out of range"};
  const Welded w = weld(mesh, options);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) return {path.string() + ": cannot open for writing: " + std::strerror(errno)};
  if (ext == ".obj") {
    f << "# fluiddemo mesh: " << w.positions.size() << " vertices, " << w.indices.size() / 3 << " triangles\n";
    char buf[128];
    for (const glm::vec3& p : w.positions) {
      std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
      f << buf;
    }
    for (const glm::vec3& n : w.normals) {
      std::snprintf(buf, sizeof buf, "vn %.6g %.6g %.6g\n", n.x, n.y, n.z);
      f << buf;
    }
    for (std::size_t i = 0; i < w.indices.size(); i += 3) {
      const std::uint32_t a = w.indices[i] + 1, b = w.indices[i + 1] + 1, c = w.indices[i + 2] + 1;
      f << "f " << a << "//" << a << ' ' << b << "//" << b << ' ' << c << "//" << c << '\n';
    }
  } else {
    f << "ply\nformat binary_little_endian 1.0\ncomment fluiddemo mesh\nelement vertex " << w.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
         "property float nz\nelement face "
      << w.indices.size() / 3 << "\nproperty list uchar uint vertex_indices\nend_header\n";
    auto put = [&](const void* p, std::size_t n) { f.write(static_cast<const char*>(p), std::streamsize(n)); };
    static_assert(sizeof(float) == 4);
    for (std::size_t v = 0; v < w.positions.size(); ++v) {
      const float data[6] = {w.positions[v].x, w.positions[v].y, w.positions[v].z,
                             w.normals[v].x,   w.normals[v].y,   w.normals[v].z};
      put(data, sizeof data);  // x86/ARM hosts are little-endian
    }
    for (std::size_t i = 0; i < w.indices.size(); i += 3) {
      const unsigned char three = 3;
      put(&three, 1);
      put(&w.indices[i], 3 * sizeof(std::uint32_t));
    }
  }
  f.flush();
  if (!f) return {path.string() + ": write failed"};
  return {};
}

}  // namespace fluid
