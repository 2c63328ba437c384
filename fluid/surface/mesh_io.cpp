#include "fluid/surface/mesh_io.hpp"

#include "fluid/io/vtk_io.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

namespace fluid {

void weldSurfaceMesh(const SurfaceMesh& m, const MeshWriteOptions& o, WeldedMesh& w) {
  w.positions.clear();
  w.normals.clear();
  w.indices.clear();
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
}


void centreSurfaceOrigin(const SurfaceInput& input, SurfaceParams& params) {
  if (input.positions.empty()) return;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t i = 0; i < input.positions.count; ++i)
    for (int a = 0; a < 3; ++a) {
      const double p = input.positions.at(i, a);
      lo[a] = std::min(lo[a], p), hi[a] = std::max(hi[a], p);
    }
  const double s = params.cube;
  params.originX = std::round(0.5 * (lo[0] + hi[0]) / s) * s;
  params.originY = std::round(0.5 * (lo[1] + hi[1]) / s) * s;
  params.originZ = std::round(0.5 * (lo[2] + hi[2]) / s) * s;
}

namespace {

// An upper bound of the particles' field (Rosenberg & Birdwell 2008 §2): each particle adds
// f(r) = (r/(sqrt2 Rc))^4 - (r/(sqrt2 Rc))^2 + 1/4, at most 1/4 (at r = 0) and 0 from r = Rc
// on, so at any point the field is at most 1/4 x the particles within Rc of it. A ball of
// radius Rc lies inside the 3x3x3 cells of edge Rc around the cell holding its centre, so
// 1/4 x the largest such 27-cell count bounds the field everywhere.
double fieldUpperBound(const SurfaceInput& input, double rc) {
  auto cell = [rc](float v) {
    return static_cast<std::int64_t>(std::clamp(std::floor(static_cast<double>(v) / rc), -1e15, 1e15));
  };
  struct CellHash {
    std::size_t operator()(const std::array<std::int64_t, 3>& c) const {
      return static_cast<std::size_t>(c[0] * 73856093 ^ c[1] * 19349663 ^ c[2] * 83492791);
    }
  };
  std::unordered_map<std::array<std::int64_t, 3>, std::size_t, CellHash> counts;
  for (std::size_t i = 0; i < input.positions.count; ++i) {
    const glm::vec3 p = input.positions[i];
    ++counts[{cell(p.x), cell(p.y), cell(p.z)}];
  }
  std::size_t most = 0;
  for (const auto& [c, count] : counts) {
    std::size_t around = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto found = counts.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (found != counts.end()) around += found->second;
        }
    most = std::max(most, around);
  }
  return 0.25 * static_cast<double>(most);
}

}  // namespace

std::string unreachableThreshold(const SurfaceInput& input, const SurfaceParams& params, const std::string& option,
                                 const std::string& source) {
  if (input.positions.empty() || !(params.threshold >= 0.25f) || !(params.rc > 0.0f)) return {};
  const double bound = fieldUpperBound(input, params.rc);
  if (params.threshold < bound) return {};
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "%.60s %g is at or above the largest value the field of ", option.c_str(),
                static_cast<double>(params.threshold));
  std::string message = buffer + source;
  std::snprintf(buffer, sizeof buffer, " can reach (%g: at most 0.25 per particle within Rc of a point)", bound);
  return message + buffer + ", so the mesh would be empty";
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

IoStatus writeSurfaceMesh(const std::filesystem::path& path, const SurfaceMesh& mesh, const MeshWriteOptions& options) {
  const std::string ext = lower(path.extension().string());
  if (ext != ".obj" && ext != ".ply" && ext != ".vtk" && ext != ".vtu")
    return {path.string() + ": unknown mesh format '" + ext + "' (use .obj, .ply, .vtk or .vtu)"};
  std::error_code ec;
  if (options.overwrite == OverwritePolicy::refuse && std::filesystem::exists(path, ec))
    return {path.string() + ": exists; not overwriting (use --force to replace it)"};
  if (mesh.normals.size() != mesh.positions.size() || mesh.indices.size() % 3 != 0)
    return {path.string() + ": inconsistent mesh (normals or indices)"};
  for (std::uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) return {path.string() + ": index out of range"};
  WeldedMesh w;
  weldSurfaceMesh(mesh, options, w);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) return {path.string() + ": cannot open for writing: " + std::strerror(errno)};
  if (ext == ".vtk" || ext == ".vtu") {
    const TriangleMeshView view{w.positions, w.normals, w.indices};
    ext == ".vtk" ? writeMeshLegacyVtk(f, view) : writeMeshVtu(f, view);
  } else if (ext == ".obj") {
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
