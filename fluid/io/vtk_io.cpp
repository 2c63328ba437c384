#include "fluid/io/vtk_io.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <string_view>
#include <vector>

namespace fluid {
namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

std::string shownText(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c);
  }
  if (text.size() > 40) out += "...";
  return out;
}

// Reads lines of a text header with a running line number.
struct Cursor {
  std::string_view bytes;
  std::size_t at = 0, line = 0;
  bool next(std::string_view& text) {
    if (at >= bytes.size()) return false;
    std::size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) end = bytes.size();
    text = bytes.substr(at, end - at);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    at = end + 1;
    ++line;
    return true;
  }
};

std::string upper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

bool finiteFloat(double v) { return std::isfinite(v) && std::abs(v) <= std::numeric_limits<float>::max(); }

// std::byteswap is C++23.
std::uint32_t swapBytes(std::uint32_t v) { return __builtin_bswap32(v); }
std::uint64_t swapBytes(std::uint64_t v) { return __builtin_bswap64(v); }

template <typename T>
T bigEndian(const char* bytes) {
  using U = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
  U u;
  std::memcpy(&u, bytes, sizeof u);
  if constexpr (std::endian::native == std::endian::little) u = swapBytes(u);
  return std::bit_cast<T>(u);
}

template <typename T>
void putBigEndian(std::ostream& out, T value) {
  using U = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
  U u = std::bit_cast<U>(value);
  if constexpr (std::endian::native == std::endian::little) u = swapBytes(u);
  out.write(reinterpret_cast<const char*>(&u), sizeof u);
}

}  // namespace

IoStatus parseParticleVtk(const std::string& bytes, const std::string& name, ParticlePositions& out) {
  out.clear();
  Cursor c{bytes};
  std::string_view text;
  auto fail = [&](const std::string& message) {
    out.clear();
    return IoStatus{name + ":" + std::to_string(c.line) + ": " + message};
  };
  if (!c.next(text) || text.rfind("# vtk DataFile Version", 0) != 0)
    return fail("not a legacy VTK file (the first line is not '# vtk DataFile Version x.y')");
  if (!c.next(text)) return fail("end of file before the title line");
  if (!c.next(text)) return fail("end of file before ASCII or BINARY");
  const std::string encoding = upper(std::string_view(text).substr(0, text.find_last_not_of(" \t") + 1));
  if (encoding != "ASCII" && encoding != "BINARY")
    return fail("encoding '" + shownText(text) + "' is neither ASCII nor BINARY");
  const bool binary = encoding == "BINARY";
  // Header lines up to POINTS (DATASET, FIELD-free geometry keywords of structured sets).
  std::size_t count = 0;
  std::string type;
  for (;;) {
    if (!c.next(text)) return fail("end of file and no POINTS section");
    char keyword[32] = {}, kind[32] = {};
    unsigned long long n = 0;
    const std::string line(text);
    if (std::sscanf(line.c_str(), "%31s", keyword) != 1) continue;
    if (upper(keyword) != "POINTS") continue;
    if (std::sscanf(line.c_str(), "%31s %llu %31s", keyword, &n, kind) != 3)
      return fail("POINTS line '" + shownText(line) + "' is not 'POINTS n float|double'");
    type = upper(kind);
    if (type != "FLOAT" && type != "DOUBLE")
      return fail("POINTS of type '" + shownText(kind) + "' (particles must be float or double)");
    // (Binary files get the exact byte count below.) Checked before reserving memory for n points.
    if (!binary && n > (bytes.size() - c.at) / 2 + 1)
      return fail("POINTS " + std::to_string(n) + " is more than the rest of the file can hold");
    count = static_cast<std::size_t>(n);
    break;
  }
  auto reserve = [&] { out.x.reserve(count), out.y.reserve(count), out.z.reserve(count); };
  if (binary) {
    const std::size_t size = type == "FLOAT" ? 4 : 8;
    if ((bytes.size() - c.at) / (3 * size) < count)
      return fail("BINARY POINTS: " + std::to_string(count) + " points need " + std::to_string(count * 3 * size) +
                  " bytes, the file has " + std::to_string(bytes.size() - c.at) + " left");
    reserve();
    const char* p = bytes.data() + c.at;
    for (std::size_t i = 0; i < count; ++i) {
      double xyz[3];
      for (int a = 0; a < 3; ++a, p += size)
        xyz[a] = size == 4 ? double(bigEndian<float>(p)) : bigEndian<double>(p);
      for (int a = 0; a < 3; ++a)
        if (!finiteFloat(xyz[a]))
          return fail("point " + std::to_string(i) + ": coordinate " + "xyz"[a] + " is not a finite float");
      out.push_back({float(xyz[0]), float(xyz[1]), float(xyz[2])});
    }
    return {};
  }
  // ASCII: 3 x count numbers, any number per line.
  std::size_t at = c.at, line = c.line + 1;
  std::vector<double> values;
  values.reserve(3 * count);
  reserve();
  while (values.size() < 3 * count) {
    while (at < bytes.size() && isSpace(bytes[at])) line += bytes[at++] == '\n';
    if (at >= bytes.size()) {
      c.line = line;
      return fail("end of file after " + std::to_string(values.size()) + " of the " + std::to_string(3 * count) +
                  " POINTS numbers");
    }
    std::size_t end = at;
    while (end < bytes.size() && !isSpace(bytes[end])) ++end;
    double v = 0;
    const auto [stop, error] = std::from_chars(bytes.data() + at, bytes.data() + end, v);
    if (error != std::errc() || stop != bytes.data() + end || !finiteFloat(v)) {
      c.line = line;
      return fail("'" + shownText(std::string_view(bytes).substr(at, end - at)) +
                  "' is not a finite float (POINTS number " + std::to_string(values.size() + 1) + ")");
    }
    values.push_back(v);
    at = end;
  }
  for (std::size_t i = 0; i < count; ++i)
    out.push_back({float(values[3 * i]), float(values[3 * i + 1]), float(values[3 * i + 2])});
  return {};
}

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
      putBigEndian(f, particles.x[i]), putBigEndian(f, particles.y[i]), putBigEndian(f, particles.z[i]);
    } else {
      std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", double(particles.x[i]), double(particles.y[i]),
                    double(particles.z[i]));
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
