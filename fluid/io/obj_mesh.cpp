#include "fluid/io/obj_mesh.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>

namespace fluid {
namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSpace(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !isSpace(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// Token text in messages: at most 40 bytes, control bytes as '?'.
std::string shownToken(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c);
  }
  if (text.size() > 40) out += "...";
  return out;
}

bool parseDouble(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

bool parseIndex(std::string_view token, long long& value) {
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

}  // namespace

IoStatus parseObjMesh(const std::string& text, const std::string& name, ObjMesh& out) {
  out.positions.clear();
  out.indices.clear();
  std::size_t line_number = 0, faces = 0;
  std::vector<std::uint32_t> polygon;
  auto fail = [&](const std::string& message) {
    out.positions.clear();
    out.indices.clear();
    return IoStatus{name + ":" + std::to_string(line_number) + ": " + message};
  };
  std::string_view rest(text);
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    std::string_view line = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end + 1);
    ++line_number;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const std::vector<std::string_view> items = tokens(line);
    if (items.empty()) continue;
    const std::string_view keyword = items[0];
    if (keyword == "v") {
      if (items.size() < 4) return fail("v with " + std::to_string(items.size() - 1) + " numbers (needs x y z)");
      double xyz[3];
      for (int a = 0; a < 3; ++a) {
        if (!parseDouble(items[a + 1], xyz[a]) || !std::isfinite(xyz[a]) ||
            std::abs(xyz[a]) > std::numeric_limits<float>::max())
          return fail("v coordinate '" + shownToken(items[a + 1]) + "' is not a finite number");
      }
      if (out.positions.size() >= std::numeric_limits<std::uint32_t>::max()) return fail("too many vertices");
      out.positions.push_back({float(xyz[0]), float(xyz[1]), float(xyz[2])});
    } else if (keyword == "f") {
      if (items.size() < 4) return fail("f with " + std::to_string(items.size() - 1) + " vertices (needs 3 or more)");
      polygon.clear();
      for (std::size_t k = 1; k < items.size(); ++k) {
        const std::string_view ref = items[k].substr(0, items[k].find('/'));
        long long index = 0;
        if (!parseIndex(ref, index) || index == 0)
          return fail("f vertex '" + shownToken(items[k]) + "' is not a vertex number (1-based, or negative)");
        const long long count = static_cast<long long>(out.positions.size());
        const long long zero_based = index > 0 ? index - 1 : count + index;
        if (zero_based < 0 || zero_based >= count)
          return fail("f vertex " + std::to_string(index) + " refers to no vertex (" + std::to_string(count) +
                      " defined so far)");
        polygon.push_back(static_cast<std::uint32_t>(zero_based));
      }
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
        out.indices.insert(out.indices.end(), {polygon[0], polygon[k], polygon[k + 1]});
      ++faces;
    } else if (keyword != "vt" && keyword != "vn" && keyword != "o" && keyword != "g" && keyword != "s" &&
               keyword != "usemtl" && keyword != "mtllib" && keyword != "l" && keyword != "p") {
      return fail("unknown or unsupported OBJ statement '" + shownToken(keyword) +
                  "' (polygonal geometry only: v, vt, vn, f, l, p, o, g, s, usemtl, mtllib)");
    }
  }
  if (faces == 0) return fail("end of file and no face (f) statement: nothing to bake");
  return {};
}

IoStatus readObjMesh(const std::filesystem::path& path, ObjMesh& out) {
  out.positions.clear();
  out.indices.clear();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return {path.string() + ": no such file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {path.string() + ": cannot open for reading"};
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parseObjMesh(text, path.string(), out);
}

}  // namespace fluid
