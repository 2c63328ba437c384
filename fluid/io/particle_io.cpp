#include "fluid/io/particle_io.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <vector>
#include <type_traits>

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

// File text quoted in a message: at most 40 bytes, control bytes as '?', so a garbage token
// cannot flood the terminal.
std::string shown(std::string_view text) {
  constexpr std::size_t kMax = 40;
  std::string out;
  for (std::size_t i = 0; i < std::min(text.size(), kMax); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c);
  }
  if (text.size() > kMax) out += "...";
  return out;
}

// Short form of a value for messages (%g: 1e+300, not 301 digits).
std::string formatValue(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

bool finiteFloat(double value) { return std::isfinite(value) && std::abs(value) <= std::numeric_limits<float>::max(); }

// Stores one particle when all three coordinates are finite floats; false otherwise.
bool storeParticle(const double (&xyz)[3], ParticlePositions& out) {
  if (!finiteFloat(xyz[0]) || !finiteFloat(xyz[1]) || !finiteFloat(xyz[2])) return false;
  out.push_back({static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2])});
  return true;
}

// The message for a particle storeParticle refused; `location` is e.g. "file.xyz:12: ".
std::string badParticle(const double (&xyz)[3], const std::string& location) {
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  int axis = 0;
  while (axis < 2 && finiteFloat(xyz[axis])) ++axis;
  return location + "coordinate " + kAxis[axis] + " is not a finite float (" + formatValue(xyz[axis]) + ")";
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
        return {where(name, line) + "'" + shown(fields[column]) + "' is not a number"};
      }
    }
    if (!storeParticle(xyz, out)) {
      out.clear();
      return {badParticle(xyz, where(name, line))};
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
  std::size_t header_line = 0;  // where it was declared, for messages
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  bool ascii = false, big_endian = false;
  std::vector<PlyElement> elements;
};

std::size_t plyTypeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// Bytes one item of `element` takes at least in a binary file (lists counted as empty).
std::size_t plyMinItemBytes(const PlyElement& element) {
  std::size_t bytes = 0;
  for (const PlyProperty& property : element.properties) {
    bytes += plyTypeSize(property.count_type.empty() ? property.type : property.count_type);
  }
  return bytes;
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

// A list length must be a whole number no larger than the data that could hold it.
bool validListCount(double count, std::uint64_t limit) {
  return std::isfinite(count) && count >= 0.0 && count == std::floor(count) && count <= static_cast<double>(limit);
}

std::uint64_t position(std::istream& in) { return static_cast<std::uint64_t>(std::max<std::streamoff>(in.tellg(), 0)); }

// Offset of the end of `in` (the limit of every count in the file); leaves the position as it was.
std::uint64_t endOffset(std::istream& in) {
  const std::istream::pos_type here = in.tellg();
  if (here < 0) return 0;
  in.seekg(0, std::ios::end);
  const std::uint64_t end = position(in);
  in.seekg(here);
  return end;
}

// Reads the header through end_header; `line` counts the lines read.
IoStatus readPlyHeader(std::istream& in, const std::string& name, std::size_t& line, PlyHeader& header) {
  std::string line_text;
  auto fail = [&](const std::string& message) { return IoStatus{where(name, line) + message}; };
  if (!std::getline(in, line_text) || trim(line_text) != "ply") {
    line = 1;
    return fail("not a PLY file (first line must be 'ply')");
  }
  ++line;
  std::string format;
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
      std::string count_text;
      words >> element.name >> count_text;
      const auto [end, error] =
          std::from_chars(count_text.data(), count_text.data() + count_text.size(), element.count);
      if (!words || error != std::errc() || end != count_text.data() + count_text.size())
        return fail("bad element line '" + shown(line_text) + "' (expected: element NAME COUNT)");
      element.header_line = line;
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) return fail("property before any element");
      PlyProperty property;
      std::string type;
      words >> type;
      if (type == "list") {
        words >> property.count_type >> property.type >> property.name;
        if (plyTypeSize(property.count_type) == 0)
          return fail("unknown list count type '" + shown(property.count_type) + "'");
      } else {
        property.type = type;
        words >> property.name;
      }
      if (!words || plyTypeSize(property.type) == 0) return fail("bad property line '" + shown(line_text) + "'");
      header.elements.back().properties.push_back(property);
    } else if (keyword == "end_header") {
      header_done = true;
      break;
    } else if (keyword != "comment" && keyword != "obj_info" && !keyword.empty()) {
      return fail("unknown header keyword '" + shown(keyword) + "'");
    }
  }
  if (!header_done) return fail("header has no end_header");
  header.ascii = format == "ascii";
  header.big_endian = format == "binary_big_endian";
  if (!header.ascii && !header.big_endian && format != "binary_little_endian")
    return fail("unknown PLY format '" + shown(format) + "'");
  return {};
}

// One ASCII item (one line) into `values`; lists are skipped.
IoStatus readPlyAsciiItem(std::istream& in, const std::string& name, const PlyElement& element, std::size_t item,
                          std::size_t& line, std::vector<double>& values) {
  std::string line_text;
  if (!std::getline(in, line_text)) {
    return {where(name, line) + "file ends after " + std::to_string(item) + " of " + std::to_string(element.count) +
            " " + shown(element.name) + " lines"};
  }
  ++line;
  std::istringstream words{line_text};
  std::string token;
  for (std::size_t i = 0; i < element.properties.size(); ++i) {
    const PlyProperty& property = element.properties[i];
    if (!property.count_type.empty()) {
      double count = 0;
      if (!(words >> token) || !parseNumber(token, count) || !validListCount(count, line_text.size()))
        return {where(name, line) + "bad list count '" + shown(token) + "' of property " + shown(property.name)};
      for (double k = 0; k < count; ++k) {
        if (!(words >> token))
          return {where(name, line) + "list " + shown(property.name) + " has fewer than " + formatValue(count) +
                  " items"};
      }
      continue;
    }
    if (!(words >> token)) return {where(name, line) + "missing value of property " + shown(property.name)};
    if (!parseNumber(token, values[i])) return {where(name, line) + "'" + shown(token) + "' is not a number"};
  }
  return {};
}

// One binary item into `values`; lists are skipped. `offset` is the item's first byte on entry
// and the next item's on return (kept here, not asked of the stream: tellg per item is slow).
IoStatus readPlyBinaryItem(std::istream& in, const std::string& name, const PlyElement& element, std::size_t item,
                           std::uint64_t& offset, std::uint64_t end, bool big_endian, std::vector<double>& values) {
  const std::uint64_t start = offset;
  auto location = [&] {
    return name + ": byte " + std::to_string(start) + " (" + shown(element.name) + " " + std::to_string(item) + "): ";
  };
  for (std::size_t i = 0; i < element.properties.size(); ++i) {
    const PlyProperty& property = element.properties[i];
    unsigned char bytes[8];
    const std::string& type = property.count_type.empty() ? property.type : property.count_type;
    const std::size_t size = plyTypeSize(type);
    if (!in.read(reinterpret_cast<char*>(bytes), static_cast<std::streamsize>(size))) {
      return {location() + "binary data ends inside " + shown(element.name) + " " + std::to_string(item) + " of " +
              std::to_string(element.count)};
    }
    offset += size;
    if (property.count_type.empty()) {
      values[i] = readPlyValue(type, bytes, big_endian);
      continue;
    }
    const double count = readPlyValue(type, bytes, big_endian);
    const std::uint64_t item_size = plyTypeSize(property.type);
    if (!validListCount(count, (end > offset ? end - offset : 0) / item_size))
      return {location() + "list " + shown(property.name) + " of " + formatValue(count) +
              " items does not fit in the rest of the file"};
    in.ignore(static_cast<std::streamsize>(count) * static_cast<std::streamsize>(item_size));
    offset += static_cast<std::uint64_t>(count) * item_size;
  }
  return {};
}

IoStatus readPly(std::istream& in, const std::string& name, ParticlePositions& out) {
  std::size_t line = 0;
  PlyHeader header;
  if (IoStatus status = readPlyHeader(in, name, line, header); !status.ok()) return status;
  const std::uint64_t end = endOffset(in);
  std::vector<double> values;
  for (const PlyElement& element : header.elements) {
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
      return {where(name, element.header_line) + "vertex element lacks scalar properties x, y, z"};
    }
    // Counts are checked against the bytes that follow before anything is allocated: an ASCII
    // item is at least one line ("\n"), a binary one its scalars and list counts.
    std::uint64_t offset = position(in);  // binary: advanced by readPlyBinaryItem
    const std::uint64_t left = end > offset ? end - offset : 0;
    const std::uint64_t item_bytes = header.ascii ? 1 : plyMinItemBytes(element);
    if (item_bytes == 0) continue;  // binary items without properties hold no bytes
    if (element.count > left / item_bytes) {
      return {where(name, element.header_line) + "element " + shown(element.name) + " claims " +
              std::to_string(element.count) + " items but only " + std::to_string(left) + " bytes follow the header"};
    }
    if (is_vertex) {
      const std::size_t expected = header.ascii ? element.count / 6 : element.count;  // "0 0 0\n" is 6 bytes
      out.reserve(out.size() + expected);
    }
    values.assign(element.properties.size(), 0.0);
    for (std::size_t item = 0; item < element.count; ++item) {
      const std::uint64_t item_start = offset;
      const IoStatus status = header.ascii
                                  ? readPlyAsciiItem(in, name, element, item, line, values)
                                  : readPlyBinaryItem(in, name, element, item, offset, end, header.big_endian, values);
      if (!status.ok()) return status;
      if (!is_vertex) continue;
      const double xyz[3] = {values[static_cast<std::size_t>(column_of[0])],
                             values[static_cast<std::size_t>(column_of[1])],
                             values[static_cast<std::size_t>(column_of[2])]};
      if (!storeParticle(xyz, out)) {
        return {badParticle(xyz, header.ascii ? where(name, line)
                                              : name + ": byte " + std::to_string(item_start) + " (vertex " +
                                                    std::to_string(item) + "): ")};
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
  if (!file) return {path.string() + ": cannot open for writing: " + std::strerror(errno)};
  return {};
}

// ---- legacy VTK particles (the format is described in vtk_io.hpp) ----

namespace vtk {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

std::string shownText(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c >= 0x7f ? '?' : static_cast<char>(c);
  }
  if (text.size() > 40) out += "...";
  return out;
}

// Reads lines of a text header with a running line number.
struct Cursor {
  std::string_view bytes;
  std::size_t at = 0, line = 0;
  bool ended = false;  // the last line read ended with '\n' (binary data starts after it)
  bool next(std::string_view& text) {
    if (at >= bytes.size()) return false;
    std::size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) end = bytes.size();
    text = bytes.substr(at, end - at);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    ended = end < bytes.size();
    at = ended ? end + 1 : bytes.size();
    ++line;
    return true;
  }
};

std::string upper(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}


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

}  // namespace vtk

}  // namespace

IoStatus parseParticleText(const std::string& text, const std::string& format, const std::string& name,
                           ParticlePositions& out) {
  out.clear();
  std::istringstream in{text};
  IoStatus status;
  if (format == "xyz") {
    status = parseLines(in, false, name, out);
  } else if (format == "csv") {
    status = parseLines(in, true, name, out);
  } else if (format == "ply") {
    status = readPly(in, name, out);
  } else {
    status = {name + ": unknown particle format '" + format + "' (xyz, csv or ply)"};
  }
  if (!status.ok()) out.clear();
  return status;
}

IoStatus parseParticleVtk(const std::string& bytes, const std::string& name, ParticlePositions& out) {
  using namespace vtk;
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
  auto reserve = [&] { out.reserve(count); };
  if (binary) {
    const std::size_t size = type == "FLOAT" ? 4 : 8;
    if (!c.ended && count > 0) return fail("end of file after the POINTS line (no point data)");
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

IoStatus readParticleFile(const std::filesystem::path& path, ParticlePositions& out) {
  out.clear();
  const std::string name = path.string();
  const std::string extension = lowercase(path.extension().string());
  if (extension != ".xyz" && extension != ".csv" && extension != ".ply" && extension != ".vtk") {
    return {name + ": unknown particle file extension '" + extension + "' (use .xyz, .csv, .ply or .vtk)"};
  }
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return {name + ": is a directory, not a particle file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {name + ": cannot open for reading: " + std::strerror(errno)};
  if (extension == ".vtk") {
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return parseParticleVtk(bytes, name, out);
  }
  IoStatus status = extension == ".ply" ? readPly(in, name, out) : parseLines(in, extension == ".csv", name, out);
  if (!status.ok()) out.clear();
  return status;
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
    const int length = std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g\n", static_cast<double>(particles[i].x),
                                     static_cast<double>(particles[i].y), static_cast<double>(particles[i].z));
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
    const int length = std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g %u\n", static_cast<double>(particles[i].x),
                                     static_cast<double>(particles[i].y), static_cast<double>(particles[i].z),
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
    const float xyz[3] = {particles[i].x, particles[i].y, particles[i].z};
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
