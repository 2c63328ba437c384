#include "fluid/io/vtk_io.hpp"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

namespace fluid {
namespace {

// Legacy VTK binary data is big-endian. (std::byteswap is C++23.)
template <typename T>
void putBigEndian(std::ostream& out, T value) {
  static_assert(sizeof(T) == 4);
  std::uint32_t u = std::bit_cast<std::uint32_t>(value);
  if constexpr (std::endian::native == std::endian::little) u = __builtin_bswap32(u);
  out.write(reinterpret_cast<const char*>(&u), sizeof u);
}

}  // namespace

IoStatus writeParticleVtk(const std::filesystem::path& path, const ParticlePositions& particles, VtkEncoding encoding,
                          OverwritePolicy overwrite) {
  std::error_code ec;
  if (overwrite == OverwritePolicy::refuse && std::filesystem::exists(path, ec))
    return {path.string() + ": already exists (not overwritten)"};
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) return {path.string() + ": cannot open for writing: " + std::strerror(errno)};
  const bool binary = encoding == VtkEncoding::binary;
  const std::size_t n = particles.size();
  f << "# vtk DataFile Version 3.0\nfluiddemo particles\n" << (binary ? "BINARY" : "ASCII")
    << "\nDATASET POLYDATA\nPOINTS " << n << " float\n";
  char buf[96];
  for (std::size_t i = 0; i < n; ++i) {
    if (binary) {
      putBigEndian(f, particles[i].x), putBigEndian(f, particles[i].y), putBigEndian(f, particles[i].z);
    } else {
      std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", double(particles[i].x), double(particles[i].y),
                    double(particles[i].z));
      f << buf;
    }
  }
  f << (binary ? "\n" : "") << "VERTICES " << n << ' ' << 2 * n << '\n';
  for (std::size_t i = 0; i < n; ++i) {
    if (binary) {
      putBigEndian(f, std::int32_t{1}), putBigEndian(f, static_cast<std::int32_t>(i));
    } else {
      f << "1 " << i << '\n';
    }
  }
  f.flush();
  if (!f) return {path.string() + ": write failed"};
  return {};
}

void writeMeshLegacyVtk(std::ostream& out, const TriangleMeshView& m) {
  const std::size_t triangles = m.indices.size() / 3;
  out << "# vtk DataFile Version 3.0\nfluiddemo mesh\nBINARY\nDATASET POLYDATA\nPOINTS " << m.positions.size()
      << " float\n";
  for (const glm::vec3& p : m.positions) putBigEndian(out, p.x), putBigEndian(out, p.y), putBigEndian(out, p.z);
  out << "\nPOLYGONS " << triangles << ' ' << 4 * triangles << '\n';
  for (std::size_t t = 0; t < triangles; ++t) {
    putBigEndian(out, std::int32_t{3});
    for (int k = 0; k < 3; ++k) putBigEndian(out, static_cast<std::int32_t>(m.indices[3 * t + k]));
  }
  out << "\nPOINT_DATA " << m.positions.size() << "\nNORMALS Normals float\n";
  for (const glm::vec3& n : m.normals) putBigEndian(out, n.x), putBigEndian(out, n.y), putBigEndian(out, n.z);
  out << '\n';
}

void writeMeshVtu(std::ostream& out, const TriangleMeshView& m) {
  const std::size_t triangles = m.indices.size() / 3;
  char buf[96];
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
         "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << m.positions.size() << "\" NumberOfCells=\"" << triangles << "\">\n"
      << "      <Points>\n        <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const glm::vec3& p : m.positions) {
    std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", double(p.x), double(p.y), double(p.z));
    out << buf;
  }
  out << "        </DataArray>\n      </Points>\n      <PointData Normals=\"Normals\">\n"
         "        <DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const glm::vec3& n : m.normals) {
    std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", double(n.x), double(n.y), double(n.z));
    out << buf;
  }
  out << "        </DataArray>\n      </PointData>\n      <Cells>\n"
         "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < triangles; ++t)
    out << m.indices[3 * t] << ' ' << m.indices[3 * t + 1] << ' ' << m.indices[3 * t + 2] << '\n';
  out << "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < triangles; ++t) out << 3 * (t + 1) << '\n';
  out << "        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t t = 0; t < triangles; ++t) out << "5\n";  // VTK_TRIANGLE
  out << "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
}

}  // namespace fluid
