// Versioned binary collider files so baking happens once (issue 5, item 2).
//
// Layout (little-endian):
//   char[8]  magic "FLDMAPS\0"
//   u32      version (kColliderFileVersion)
//   u32      normal index resolution R_n (2..256)
//   u32      map count k (1..1024)
//   u32      reserved, 0
//   k × map: u32 format, u32 compare, u32 resolution, u32 encloses (0/1),
//            f32[16] collider_to_map (column-major), f32 z_scale, f32[3] cube_scale,
//            u64 texel byte count (must equal N·N·(6 for cube8)·texelBytes), texel bytes
//   u64      FNV-1a 64 of every byte before it
#include "fluid/collide/collide.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace fluid {

static_assert(std::endian::native == std::endian::little, "collider files assume a little-endian host");

namespace {

constexpr char kMagic[8] = {'F', 'L', 'D', 'M', 'A', 'P', 'S', '\0'};

std::uint64_t fnv1a(std::span<const std::uint8_t> bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (std::uint8_t b : bytes) {
    h ^= b;
    h *= 1099511628211ull;
  }
  return h;
}

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

}  // namespace

std::vector<std::uint8_t> serializeCollider(const DepthMapCollider& collider) {
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
    put(out, static_cast<std::uint32_t>(m.encloses_collider ? 1 : 0));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) put(out, m.collider_to_map[c][r]);
    put(out, m.z_scale);
    put(out, m.cube_scale.x);
    put(out, m.cube_scale.y);
    put(out, m.cube_scale.z);
    put(out, static_cast<std::uint64_t>(m.texels.size()));
    out.insert(out.end(), m.texels.begin(), m.texels.end());
  }
  put(out, fnv1a(out));
  return out;
}

FileStatus deserializeCollider(std::span<const std::uint8_t> bytes, const std::string& name, DepthMapCollider& out) {
  FileStatus st;
  auto fail = [&](const std::string& what) {
    st.error = name + ": " + what;
    return st;
  };
  Reader in{bytes};
  char magic[8];
  if (bytes.size() < 8) return fail("too short to be a collider file (" + std::to_string(bytes.size()) + " bytes)");
  std::memcpy(magic, bytes.data(), 8);
  in.at = 8;
  if (std::memcmp(magic, kMagic, 8) != 0) return fail("not a collider file (bad magic; expected \"FLDMAPS\")");
  std::uint32_t version = 0, rn = 0, count = 0, reserved = 0;
  if (!in.get(version)) return fail("truncated header (version)");
  if (version != kColliderFileVersion) {
    return fail("unsupported version " + std::to_string(version) + " (this build reads version " +
                std::to_string(kColliderFileVersion) + "; re-bake the collider)");
  }
  if (!in.get(rn) || !in.get(count) || !in.get(reserved)) return fail("truncated header");
  if (rn < 2 || rn > 256) return fail("normal_resolution " + std::to_string(rn) + " out of range 2..256");
  if (count < 1 || count > 1024) return fail("map count " + std::to_string(count) + " out of range 1..1024");
  if (reserved != 0) return fail("reserved header field is " + std::to_string(reserved) + ", expected 0");
  if (bytes.size() < 8 + 8) return fail("truncated");
  const std::uint64_t expected = fnv1a(bytes.subspan(0, bytes.size() - 8));
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  std::vector<DepthMap> maps;
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::string where = "map " + std::to_string(k) + ": ";
    DepthMap m;
    std::uint32_t format, compare, encloses;
    if (!in.get(format) || !in.get(compare) || !in.get(m.resolution) || !in.get(encloses))
      return fail(where + "truncated map header");
    if (format < 1 || format > 4) return fail(where + "unknown format " + std::to_string(format));
    if (compare > 1) return fail(where + "bad compare " + std::to_string(compare));
    if (encloses > 1) return fail(where + "bad encloses flag " + std::to_string(encloses));
    if (m.resolution < 4 || m.resolution > 4096)
      return fail(where + "resolution " + std::to_string(m.resolution) + " out of range 4..4096");
    m.format = static_cast<DepthMapFormat>(format);
    m.compare = static_cast<DepthCompare>(compare);
    m.encloses_collider = encloses == 1;
    float values[20];
    for (float& v : values) {
      if (!in.get(v)) return fail(where + "truncated transform");
      if (!std::isfinite(v)) return fail(where + "non-finite transform/scale value");
    }
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m.collider_to_map[c][r] = values[c * 4 + r];
    m.z_scale = values[16];
    m.cube_scale = {values[17], values[18], values[19]};
    std::uint64_t size;
    if (!in.get(size)) return fail(where + "truncated texel size");
    const std::uint64_t want = static_cast<std::uint64_t>(m.resolution) * m.resolution *
                               (m.format == DepthMapFormat::cube8 ? 6u : 1u) * texelBytes(m.format);
    if (size != want)
      return fail(where + "texel byte count " + std::to_string(size) + ", expected " + std::to_string(want));
    if (bytes.size() - in.at < size + 8) return fail(where + "truncated texel data");
    m.texels.assign(bytes.begin() + static_cast<std::ptrdiff_t>(in.at),
                    bytes.begin() + static_cast<std::ptrdiff_t>(in.at + size));
    in.at += size;
    maps.push_back(std::move(m));
  }
  if (bytes.size() - in.at != 8) return fail(std::to_string(bytes.size() - in.at - 8) + " unexpected trailing bytes");
  if (stored != expected) return fail("checksum mismatch (file corrupted)");
  out = DepthMapCollider(std::move(maps), static_cast<int>(rn));
  return st;
}

FileStatus saveCollider(const std::filesystem::path& path, const DepthMapCollider& collider, Overwrite overwrite) {
  FileStatus st;
  std::error_code ec;
  if (overwrite == Overwrite::refuse && std::filesystem::exists(path, ec)) {
    st.error = path.string() + ": already exists (use --force to replace it)";
    return st;
  }
  const std::vector<std::uint8_t> bytes = serializeCollider(collider);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) {
    st.error = path.string() + ": cannot open for writing";
    return st;
  }
  file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!file) st.error = path.string() + ": write failed";
  return st;
}

FileStatus loadCollider(const std::filesystem::path& path, DepthMapCollider& out) {
  FileStatus st;
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    st.error = path.string() + ": cannot open";
    return st;
  }
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) {
    st.error = path.string() + ": read failed";
    return st;
  }
  return deserializeCollider(bytes, path.string(), out);
}

}  // namespace fluid
