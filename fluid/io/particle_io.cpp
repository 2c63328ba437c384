#include "fluid/io/particle_io.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

namespace fluid {
namespace {

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return text;
}

// Parses one whole token as a double; from_chars does not take a leading '+'.
bool parseNumber(std::string_view token, double& value) {
  token = trim(token);
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

std::string where(const std::string& name, std::size_t line) { return name + ":" + std::to_string(line) + ": "; }

// Checks and stores one particle; returns an error message or "".
// `location` is the message prefix, e.g. "file.xyz:12: ".
std::string storeParticle(const double (&xyz)[3], const std::string& location, ParticlePositions& out) {
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    const double value = xyz[axis];
    if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<float>::max()) {
      return location + "coordinate " + kAxis[axis] + " is not a finite float (" + std::to_string(value) + ")";
    }
  }
  out.push_back({static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2])});
  return {};
}

std::vector<std::string_view> split(std::string_view line, bool comma) {
  std::vector<std::string_view> fields;
  if (comma) {
    std::size_t start = 0;
    while (true) {
      const std::size_t at = line.find(',', start);
      fields.push_back(trim(line.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start)));
      if (at == std::string_view::npos) break;
      start = at + 1;
    }
  } else {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      const std::size_t start = i;
      while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i > start) fields.push_back(line.substr(start, i - start));
    }
  }
  return fields;
}

IoStatus parseLines(std::istream& in, bool comma, const std::string& name, ParticlePositions& out) {
  std::string line_text;
  std::size_t line = 0;
  int column_of[3] = {0, 1, 2};
  bool first_data_line = true;
  while (std::getline(in, line_text)) {
    ++line;
    const std::string_view text = trim(line_text);
    if (text.empty() || text.front() == '#') continue;
    const std::vector<std::string_view> fields = split(text, comma);
    double first = 0.0;
    if (comma && first_data_line && !fields.empty() && !parseNumber(fields[0], first)) {
      // A CSV header row: find x, y and z by name.
      for (int axis = 0; axis < 3; ++axis) column_of[axis] = -1;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string field = lowercase(std::string(fields[i]));
        if (field == "x") column_of[0] = static_cast<int>(i);
        if (field == "y") column_of[1] = static_cast<int>(i);
        if (field == "z") column_of[2] = static_cast<int>(i);
      }
      if (column_of[0] < 0 || column_of[1] < 0 || column_of[2] < 0) {
        out.clear();
        return {where(name, line) + "header row must name columns x, y and z"};
      }
      first_data_line = false;
      continue;
    }
    first_data_line = false;
    double xyz[3];
    for (int axis = 0; axis < 3; ++axis) {
      const auto column = static_cast<std::size_t>(column_of[axis]);
      if (column >= fields.size()) {
        out.clear();
        return {where(name, line) + "expected 3 coordinates, found " + std::to_string(fields.size())};
      }
      if (!parseNumber(fields[column], xyz[axis])) {
        out.clear();
        return {where(name, line) + "'" + std::string(fields[column]) + "' is not a number"};
      }
    }
    if (std::string error = storeParticle(xyz, where(name, line), out); !error.empty()) {
      out.clear();
      return {error};
    }
  }
  return {};
}

// ---- PLY -------------------------------------------------------------------------------

struct PlyProperty {
  std::string name;
  std::string type;        // scalar type, or the item type of a list
  std::string count_type;  // non-empty for list properties
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

std::size_t plyTypeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

template <typename T>
T readScalar(const unsigned char* bytes, bool big_endian) {
  unsigned char buffer[sizeof(T)];
  std::memcpy(buffer, bytes, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(buffer, buffer + sizeof(T));
  T value;
  std::memcpy(&value, buffer, sizeof(T));
  return value;
}

double readPlyValue(const std::string& type, const unsigned char* bytes, bool big_endian) {
  if (type == "char" || type == "int8") return readScalar<std::int8_t>(bytes, big_endian);
  if (type == "uchar" || type == "uint8") return readScalar<std::uint8_t>(bytes, big_endian);
  if (type == "short" || type == "int16") return readScalar<std::int16_t>(bytes, big_endian);
  if (type == "ushort" || type == "uint16") return readScalar<std::uint16_t>(bytes, big_endian);
  if (type == "int" || type == "int32") return readScalar<std::int32_t>(bytes, big_endian);
  if (type == "uint" || type == "uint32") return readScalar<std::uint32_t>(bytes, big_endian);
  if (type == "float" || type == "float32") return readScalar<float>(bytes, big_endian);
  return readScalar<double>(bytes, big_endian);
}

IoStatus readPly(std::istream& in, const std::string& name, ParticlePositions& out) {
  std::string line_text;
  std::size_t line = 0;
  auto fail = [&](const std::string& message) {
    out.clear();
    return IoStatus{where(name, line) + message};
  };
  if (!std::getline(in, line_text) || trim(line_text) != "ply")
    return fail("not a PLY file (first line must be 'ply')");
  ++line;
  std::string format;
  std::vector<PlyElement> elements;
  bool header_done = false;
  while (std::getline(in, line_text)) {
    ++line;
    std::istringstream words{line_text};
    std::string keyword;
    words >> keyword;
    if (keyword == "format") {
      words >> format;
    } else if (keyword == "element") {
      PlyElement element;
      long long count = -1;
      words >> element.name >> count;
      if (!words || count < 0) return fail("bad element line '" + line_text + "'");
      element.count = static_cast<std::size_t>(count);
      elements.push_back(element);
    } else if (keyword == "property") {
      if (elements.empty()) return fail("property before any element");
      PlyProperty property;
      std::string type;
      words >> type;
      if (type == "list") {
        words >> property.count_type >> property.type >> property.name;
        if (plyTypeSize(property.count_type) == 0) return fail("unknown list count type '" + property.count_type + "'");
      } else {
        property.type = type;
        words >> property.name;
      }
      if (!words || plyTypeSize(property.type) == 0) return fail("bad property line '" + line_text + "'");
      elements.back().properties.push_back(property);
    } else if (keyword == "end_header") {
      header_done = true;
      break;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      return fail("unknown header keyword '" + keyword + "'");
    }
  }
  if (!header_done) return fail("header has no end_header");
  const bool ascii = format == "ascii";
  const bool big_endian = format == "binary_big_endian";
  if (!ascii && !big_endian && format != "binary_little_endian") return fail("unknown PLY format '" + format + "'");

  for (const PlyElement& element : elements) {
    const bool is_vertex = element.name == "vertex";
    int column_of[3] = {-1, -1, -1};
    for (std::size_t i = 0; i < element.properties.size(); ++i) {
      const PlyProperty& property = element.properties[i];
      if (!property.count_type.empty()) continue;
      if (property.name == "x") column_of[0] = static_cast<int>(i);
      if (property.name == "y") column_of[1] = static_cast<int>(i);
      if (property.name == "z") column_of[2] = static_cast<int>(i);
    }
    if (is_vertex && (column_of[0] < 0 || column_of[1] < 0 || column_of[2] < 0)) {
      return fail("vertex element lacks scalar properties x, y, z");
    }
    if (is_vertex) {
      out.x.reserve(std::min<std::size_t>(element.count, 1u << 24));
    }
    for (std::size_t item = 0; item < element.count; ++item) {
      std::vector<double> values(element.properties.size(), 0.0);
      if (ascii) {
        if (!std::getline(in, line_text))
          return fail("file ends after " + std::to_string(item) + " of " + std::to_string(element.count) + " " +
                      element.name + " lines");
        ++line;
        std::istringstream words{line_text};
        for (std::size_t i = 0; i < element.properties.size(); ++i) {
          const PlyProperty& property = element.properties[i];
          std::string token;
          if (!property.count_type.empty()) {
            double count = 0;
            if (!(words >> token) || !parseNumber(token, count) || count < 0) return fail("bad list count");
            for (long long k = 0; k < static_cast<long long>(count); ++k) words >> token;
            continue;
          }
          if (!(words >> token) || !parseNumber(token, values[i])) return fail("'" + token + "' is not a number");
        }
      } else {
        for (std::size_t i = 0; i < element.properties.size(); ++i) {
          const PlyProperty& property = element.properties[i];
          unsigned char bytes[8];
          if (!property.count_type.empty()) {
            const std::size_t count_size = plyTypeSize(property.count_type);
            if (!in.read(reinterpret_cast<char*>(bytes), static_cast<std::streamsize>(count_size)))
              return fail("file ends inside " + element.name + " " + std::to_string(item));
            const double count = readPlyValue(property.count_type, bytes, big_endian);
            if (count < 0) return fail("negative list count");
            in.ignore(static_cast<std::streamsize>(count) * static_cast<std::streamsize>(plyTypeSize(property.type)));
            continue;
          }
          const std::size_t size = plyTypeSize(property.type);
          if (!in.read(reinterpret_cast<char*>(bytes), static_cast<std::streamsize>(size))) {
            out.clear();
            return {name + ": binary data ends inside " + element.name + " " + std::to_string(item) + " of " +
                    std::to_string(element.count)};
          }
          values[i] = readPlyValue(property.type, bytes, big_endian);
        }
      }
      if (is_vertex) {
        const double xyz[3] = {values[static_cast<std::size_t>(column_of[0])],
                               values[static_cast<std::size_t>(column_of[1])],
                               values[static_cast<std::size_t>(column_of[2])]};
        const std::string location = ascii ? where(name, line) : name + ": vertex " + std::to_string(item) + ": ";
        if (std::string error = storeParticle(xyz, location, out); !error.empty()) {
          out.clear();
          return {error};
        }
      }
    }
  }
  return {};
}

IoStatus openForWrite(const std::filesystem::path& path, OverwritePolicy overwrite, std::ofstream& file, bool binary) {
  std::error_code error;
  if (overwrite == OverwritePolicy::refuse && std::filesystem::exists(path, error)) {
    return {path.string() + ": already exists (not overwritten)"};
  }
  file.open(path, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
  if (!file) return {path.string() + ": cannot open for writing"};
  return {};
}

}  // namespace

IoStatus parseParticleText(const std::string& text, const std::string& format, const std::string& name,
                           ParticlePositions& out) {
  out.clear();
  std::istringstream in{text};
  if (format == "xyz") return parseLines(in, false, name, out);
  if (format == "csv") return parseLines(in, true, name, out);
  if (format == "ply") return readPly(in, name, out);
  return {name + ": unknown particle format '" + format + "' (xyz, csv or ply)"};
}

IoStatus readParticleFile(const std::filesystem::path& path, ParticlePositions& out) {
  out.clear();
  const std::string name = path.string();
  const std::string extension = lowercase(path.extension().string());
  if (extension != ".xyz" && extension != ".csv" && extension != ".ply") {
    return {name + ": unknown particle file extension '" + extension + "' (use .xyz, .csv or .ply)"};
  }
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return {name + ": is a directory, not a particle file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {name + ": cannot open for reading"};
  if (extension == ".ply") return readPly(in, name, out);
  return parseLines(in, extension == ".csv", name, out);
}

IoStatus writeParticleXyz(const std::filesystem::path& path, const ParticlePositions& particles,
                          OverwritePolicy overwrite) {
  std::ofstream file;
  if (IoStatus status = openForWrite(path, overwrite, file, false); !status.ok()) return status;
  std::string text;
  text.reserve(particles.size() * 40);
  char buffer[128];
  for (std::size_t i = 0; i < particles.size(); ++i) {
    // %.9g round-trips every float.
    const int length = std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g\n", static_cast<double>(particles.x[i]),
                                     static_cast<double>(particles.y[i]), static_cast<double>(particles.z[i]));
    text.append(buffer, static_cast<std::size_t>(length));
  }
  file << text;
  if (!file) return {path.string() + ": write failed"};
  return {};
}

IoStatus writeParticleXyzWithIds(const std::filesystem::path& path, const ParticlePositions& particles,
                                 const std::vector<std::uint32_t>& ids, OverwritePolicy overwrite) {
  if (ids.size() != particles.size())
    return {path.string() + ": " + std::to_string(ids.size()) + " ids for " + std::to_string(particles.size()) +
            " particles"};
  std::ofstream file;
  if (IoStatus status = openForWrite(path, overwrite, file, false); !status.ok()) return status;
  std::string text;
  text.reserve(particles.size() * 48);
  char buffer[160];
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const int length = std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g %u\n", static_cast<double>(particles.x[i]),
                                     static_cast<double>(particles.y[i]), static_cast<double>(particles.z[i]),
                                     static_cast<unsigned>(ids[i]));
    text.append(buffer, static_cast<std::size_t>(length));
  }
  file << text;
  if (!file) return {path.string() + ": write failed"};
  return {};
}

IoStatus writeParticlePly(const std::filesystem::path& path, const ParticlePositions& particles,
                          OverwritePolicy overwrite) {
  std::ofstream file;
  if (IoStatus status = openForWrite(path, overwrite, file, true); !status.ok()) return status;
  file << "ply\nformat binary_little_endian 1.0\ncomment written by fluiddemo\nelement vertex " << particles.size()
       << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const float xyz[3] = {particles.x[i], particles.y[i], particles.z[i]};
    for (float value : xyz) {
      auto bits = std::bit_cast<std::uint32_t>(value);
      if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
      file.write(reinterpret_cast<const char*>(&bits), sizeof bits);
    }
  }
  if (!file) return {path.string() + ": write failed"};
  return {};
}

}  // namespace fluid
