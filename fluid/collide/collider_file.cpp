// Versioned binary collider files so baking happens once (issue 5, item 2).
//
// Layout (little-endian):
//   char[8]  magic "FLDMAPS\0"
//   u32      version (kColliderFileVersion)
//   u32      normal index resolution R_n (2..256)
//   u32      map count k (1..1024)
//   u32      reserved, 0
//   k × map: u32 format, u32 compare, u32 resolution, u32 flags (bit 0: encloses the collider;
//            bit 1, version 2 front_back16 only: margin ring, DepthMap::margin_ring),
//            f32[16] collider_to_map (column-major), f32 z_scale, f32[3] cube_scale,
//            u64 texel byte count (must equal N·N·(6 for cube8)·texelBytes), texel bytes
//   version 2 only: u32 source record byte count (<= kMaxSourceBytes), then the record: UTF-8
//            lines "model=NAME", "model_fnv1a64=16 hex digits", "recipe=TEXT", each ending in
//            '\n' (all three, in this order; an empty record = no source)
//   u64      FNV-1a 64 of every byte before it
// The record sits after the maps so that version 1 and 2 maps start at the same offsets.
#include "fluid/collide/collide.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string_view>
#include "fluid/core/fnv1a.hpp"

#include <unistd.h>

namespace fluid {

static_assert(std::endian::native == std::endian::little, "collider files assume a little-endian host");

namespace {

constexpr char kMagic[8] = {'F', 'L', 'D', 'M', 'A', 'P', 'S', '\0'};
constexpr std::uint32_t kMaxSourceBytes = 4096;
constexpr const char* kSourceKeys[3] = {"model", "model_fnv1a64", "recipe"};

std::string sourceText(const ColliderSource& source) {
  if (source.empty()) return {};
  char hash[20];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(source.model_fnv1a64));
  return std::string(kSourceKeys[0]) + "=" + source.model + "\n" + kSourceKeys[1] + "=" + hash + "\n" + kSourceKeys[2] +
         "=" + source.recipe + "\n";
}

// Parses the record written by sourceText; returns "" or what is wrong (naming the field).
std::string parseSourceText(std::string_view text, ColliderSource& out) {
  out = {};
  if (text.empty()) return {};
  for (const char* key : kSourceKeys) {
    const std::size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    const std::size_t eq = line.find('=');
    if (eol == std::string_view::npos || eq == std::string_view::npos || line.substr(0, eq) != key)
      return std::string("source record: expected a line '") + key + "=...'";
    const std::string_view value = line.substr(eq + 1);
    for (char c : value)
      if (static_cast<unsigned char>(c) < 0x20)
        return std::string("source record: ") + key + " has a control character";
    if (std::string_view(key) == "model_fnv1a64") {
      std::uint64_t hash = 0;
      const auto [end, errc] = std::from_chars(value.data(), value.data() + value.size(), hash, 16);
      if (value.size() != 16 || errc != std::errc() || end != value.data() + value.size())
        return "source record: model_fnv1a64 '" + std::string(value.substr(0, 20)) + "' is not 16 hex digits";
      out.model_fnv1a64 = hash;
    } else {
      (std::string_view(key) == "model" ? out.model : out.recipe) = std::string(value);
    }
    text.remove_prefix(eol + 1);
  }
  if (!text.empty()) return "source record: " + std::to_string(text.size()) + " bytes after the recipe line";
  return {};
}

std::uint64_t fnv1a(std::span<const std::uint8_t> bytes) { return fluid::fnv1a64(bytes.data(), bytes.size()); }

template <class T>
void put(std::vector<std::uint8_t>& out, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

struct Reader {
  std::span<const std::uint8_t> bytes;
  std::size_t at = 0;
  template <class T>
  bool get(T& value) {
    if (bytes.size() - at < sizeof(T)) return false;
    std::memcpy(&value, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return true;
  }
};

// Every texel must decode to something a query can use: finite float32 values, normal indices
// inside the R_n x R_n table, finite binary16 depths. Returns the first bad texel or -1.
std::int64_t firstBadTexel(const DepthMap& m, std::uint32_t rn) {
  const std::size_t size = texelBytes(m.format);
  const std::size_t count = m.texels.size() / size;
  auto index_ok = [rn](std::uint32_t i, std::uint32_t j) { return i < rn && j < rn; };
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint8_t* t = m.texels.data() + k * size;
    bool ok = true;
    switch (m.format) {
      case DepthMapFormat::float32: {
        float v[4];
        std::memcpy(v, t, 16);
        ok = std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) && std::isfinite(v[3]);
        break;
      }
      case DepthMapFormat::fixed8:
      case DepthMapFormat::cube8: {
        const bool background = t[2] == 0xFF && t[3] == 0xFF;
        ok = background || index_ok(t[0], t[1]);
        break;
      }
      case DepthMapFormat::front_back16:
        for (int l = 0; l < 2 && ok; ++l) {
          std::uint16_t index, depth;
          std::memcpy(&index, t + 2 * l, 2);
          std::memcpy(&depth, t + 4 + 2 * l, 2);
          const bool background = depth == kHalfBackground;
          ok = background || (index_ok(index & 0xFFu, index >> 8) && ((depth >> 10) & 0x1Fu) != 0x1Fu);
        }
        break;
    }
    if (!ok) return static_cast<std::int64_t>(k);
  }
  return -1;
}

}  // namespace

std::vector<std::uint8_t> serializeCollider(const DepthMapCollider& collider, const ColliderSource& source) {
  std::vector<std::uint8_t> out;
  for (char c : kMagic) out.push_back(static_cast<std::uint8_t>(c));
  put(out, kColliderFileVersion);
  put(out, static_cast<std::uint32_t>(collider.normalResolution()));
  put(out, static_cast<std::uint32_t>(collider.maps().size()));
  put(out, std::uint32_t{0});
  for (const DepthMap& m : collider.maps()) {
    put(out, static_cast<std::uint32_t>(m.format));
    put(out, static_cast<std::uint32_t>(m.compare));
    put(out, m.resolution);
    put(out, static_cast<std::uint32_t>((m.encloses_collider ? 1 : 0) | (m.margin_ring ? 2 : 0)));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) put(out, m.collider_to_map[c][r]);
    put(out, m.z_scale);
    put(out, m.cube_scale.x);
    put(out, m.cube_scale.y);
    put(out, m.cube_scale.z);
    put(out, static_cast<std::uint64_t>(m.texels.size()));
    out.insert(out.end(), m.texels.begin(), m.texels.end());
  }
  const std::string text = sourceText(source);
  put(out, static_cast<std::uint32_t>(text.size()));
  out.insert(out.end(), text.begin(), text.end());
  put(out, fnv1a(out));
  return out;
}

FileStatus deserializeCollider(std::span<const std::uint8_t> bytes, const std::string& name, DepthMapCollider& out,
                               ColliderSource* source) {
  // Every message names the file and the byte offset of the field it is about.
  FileStatus st;
  Reader in{bytes};
  std::size_t field_at = 0;
  auto fail = [&](const std::string& what) {
    st.error = name + ": byte " + std::to_string(field_at) + ": " + what;
    return st;
  };
  if (bytes.size() < 8) return fail("too short to be a collider file (" + std::to_string(bytes.size()) + " bytes)");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) return fail("not a collider file (bad magic; expected \"FLDMAPS\")");
  in.at = 8;
  std::uint32_t version = 0, rn = 0, count = 0, reserved = 0;
  field_at = in.at;
  if (!in.get(version)) return fail("truncated header (version)");
  if (version != 1 && version != kColliderFileVersion) {
    return fail("unsupported version " + std::to_string(version) + " (this build reads version " +
                std::to_string(kColliderFileVersion) + "; re-bake the collider)");
  }
  field_at = in.at;
  if (!in.get(rn)) return fail("truncated header (normal_resolution)");
  if (rn < 2 || rn > 256) return fail("normal_resolution " + std::to_string(rn) + " out of range 2..256");
  field_at = in.at;
  if (!in.get(count)) return fail("truncated header (map count)");
  if (count < 1 || count > 1024) return fail("map count " + std::to_string(count) + " out of range 1..1024");
  field_at = in.at;
  if (!in.get(reserved)) return fail("truncated header (reserved)");
  if (reserved != 0) return fail("reserved header field is " + std::to_string(reserved) + ", expected 0");
  if (bytes.size() < in.at + 8) return fail("truncated (no checksum)");
  const std::uint64_t expected = fnv1a(bytes.subspan(0, bytes.size() - 8));
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  std::vector<DepthMap> maps;
  std::vector<std::size_t> texel_at;  // file offset of each map's texels
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::string where = "map " + std::to_string(k) + ": ";
    DepthMap m;
    std::uint32_t format, compare, encloses;
    field_at = in.at;
    if (!in.get(format) || !in.get(compare) || !in.get(m.resolution) || !in.get(encloses))
      return fail(where + "truncated map header");
    if (format < 1 || format > 4) return fail(where + "unknown format " + std::to_string(format));
    field_at += 4;
    if (compare > 1) return fail(where + "bad compare " + std::to_string(compare));
    field_at += 4;
    if (m.resolution < 4 || m.resolution > 4096)
      return fail(where + "resolution " + std::to_string(m.resolution) + " out of range 4..4096");
    field_at += 4;
    // Bit 0: encloses the collider; bit 1 (version 2, front_back16 only): margin ring.
    const std::uint32_t allowed = version >= 2 && format == 3 ? 3u : 1u;
    if ((encloses & ~allowed) != 0) return fail(where + "bad flags word " + std::to_string(encloses));
    m.format = static_cast<DepthMapFormat>(format);
    m.compare = static_cast<DepthCompare>(compare);
    m.encloses_collider = (encloses & 1u) != 0;
    m.margin_ring = (encloses & 2u) != 0;
    float values[20];
    for (float& v : values) {
      field_at = in.at;
      if (!in.get(v)) return fail(where + "truncated transform");
      if (!std::isfinite(v)) return fail(where + "non-finite transform/scale value");
      // Bounds a bake never comes near (collider coordinates <= 1e5, maps >= 1e-6 wide), so
      // eq. (1) stays finite for every query point a collider can meet.
      const bool scale = &v - values >= 16;
      if (scale ? !(v > 0.0f && v <= 1e7f) : std::fabs(v) > 1e12f) {
        char text[96];
        std::snprintf(
            text, sizeof text,
            scale ? "scale %d is %g, expected in (0, 1e7]" : "transform entry %d is %g, expected within +-1e12",
            static_cast<int>(&v - values), static_cast<double>(v));
        return fail(where + text);
      }
    }
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m.collider_to_map[c][r] = values[c * 4 + r];
    m.z_scale = values[16];
    m.cube_scale = {values[17], values[18], values[19]};
    field_at = in.at;
    std::uint64_t size;
    if (!in.get(size)) return fail(where + "truncated texel size");
    const std::uint64_t want = static_cast<std::uint64_t>(m.resolution) * m.resolution *
                               (m.format == DepthMapFormat::cube8 ? 6u : 1u) * texelBytes(m.format);
    if (size != want)
      return fail(where + "texel byte count " + std::to_string(size) + ", expected " + std::to_string(want));
    field_at = in.at;
    if (bytes.size() - in.at < size + 8) return fail(where + "truncated texel data");
    m.texels.assign(bytes.begin() + static_cast<std::ptrdiff_t>(in.at),
                    bytes.begin() + static_cast<std::ptrdiff_t>(in.at + size));
    texel_at.push_back(in.at);
    in.at += size;
    maps.push_back(std::move(m));
  }
  ColliderSource record;
  std::size_t record_at = 0;
  std::string_view record_text;
  if (version >= 2) {
    field_at = in.at;
    std::uint32_t length = 0;
    if (bytes.size() - in.at < 12 || !in.get(length)) return fail("truncated source record length");
    if (length > kMaxSourceBytes)
      return fail("source record length " + std::to_string(length) + " out of range 0.." +
                  std::to_string(kMaxSourceBytes));
    record_at = in.at;
    if (bytes.size() - in.at < std::size_t{length} + 8) return fail("truncated source record");
    record_text = std::string_view(reinterpret_cast<const char*>(bytes.data() + in.at), length);
    in.at += length;
  }
  field_at = in.at;
  if (bytes.size() - in.at != 8) return fail(std::to_string(bytes.size() - in.at - 8) + " unexpected trailing bytes");
  if (stored != expected) return fail("checksum mismatch (file corrupted)");
  field_at = record_at;
  if (const std::string problem = parseSourceText(record_text, record); !problem.empty()) return fail(problem);
  // After the checksum: a texel that does not decode means a bad writer, not a damaged file.
  for (std::size_t k = 0; k < maps.size(); ++k) {
    if (const std::int64_t bad = firstBadTexel(maps[k], rn); bad >= 0) {
      field_at = texel_at[k] + static_cast<std::size_t>(bad) * texelBytes(maps[k].format);
      return fail("map " + std::to_string(k) + ": texel " + std::to_string(bad) +
                  " does not decode (a non-finite value, or a normal index outside the " + std::to_string(rn) + "x" +
                  std::to_string(rn) + " table)");
    }
  }
  out = DepthMapCollider(std::move(maps), static_cast<int>(rn));
  if (source != nullptr) *source = std::move(record);
  return st;
}

FileStatus saveCollider(const std::filesystem::path& path, const DepthMapCollider& collider, Overwrite overwrite,
                        const ColliderSource& source) {
  FileStatus st;
  std::error_code ec;
  if (overwrite == Overwrite::refuse && std::filesystem::exists(path, ec)) {
    st.error = path.string() + ": already exists (use --force to replace it)";
    return st;
  }
  const std::vector<std::uint8_t> bytes = serializeCollider(collider, source);
  // Written beside the target and renamed over it: a reader (or a second process baking the same
  // cache entry) sees the old file or the new one, never half of one.
  std::filesystem::path partial = path;
  partial += ".partial." + std::to_string(::getpid());
  {
    std::ofstream file(partial, std::ios::binary | std::ios::trunc);
    if (!file) {
      st.error = path.string() + ": cannot open for writing: " + std::strerror(errno);
      return st;
    }
    file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    file.flush();
    if (!file) st.error = path.string() + ": write failed";
  }
  if (st.ok()) std::filesystem::rename(partial, path, ec);
  if (st.ok() && ec) st.error = path.string() + ": cannot replace: " + ec.message();
  if (!st.ok()) std::filesystem::remove(partial, ec);
  return st;
}

FileStatus loadCollider(const std::filesystem::path& path, DepthMapCollider& out, ColliderSource* source) {
  FileStatus st;
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    st.error = path.string() + ": cannot open: " + std::strerror(errno);
    return st;
  }
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) {
    st.error = path.string() + ": read failed";
    return st;
  }
  return deserializeCollider(bytes, path.string(), out, source);
}

}  // namespace fluid
