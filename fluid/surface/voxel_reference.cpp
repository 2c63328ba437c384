#include "fluid/surface/voxel_reference.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace fluid {

void makeVoxelLayers(const VoxelView& view, float nearest, float farthest, float angle_degrees, int max_layers,
                     VoxelLayers& out) {
  const double d0 = std::max(static_cast<double>(nearest), 1e-6);
  const double d1 = std::max(static_cast<double>(farthest), d0 * 1.0001);
  const double y_scale = std::max(static_cast<double>(view.projection[1][1]), 1e-6);
  // §4.2: cell width c_w = 2 tan(θ_y/2) / R_y · d = 2 / (P11 R_y) · d; cell depth c_d = tan α · c_w.
  const double alpha = std::clamp(static_cast<double>(angle_degrees), 0.01, 89.0) * M_PI / 180.0;
  const double k = std::tan(alpha) * 2.0 / (y_scale * std::max(view.height, 1));
  const double log_ratio = std::log(d1 / d0);
  const int cap = std::max(32, max_layers / 32 * 32);
  int count = static_cast<int>(std::ceil(log_ratio / std::log1p(k)));
  count = std::clamp((count + 31) / 32 * 32, 32, cap);
  out.count = count;
  out.words = count / 32;
  const double k_used = std::expm1(log_ratio / count);
  out.angle_degrees = static_cast<float>(std::atan(k_used * y_scale * std::max(view.height, 1) / 2.0) * 180.0 / M_PI);
  out.depth.resize(static_cast<std::size_t>(count) + 1);
  for (int i = 0; i <= count; ++i) {
    float d = static_cast<float>(d0 * std::exp(log_ratio * i / count));
    if (i > 0 && !(d > out.depth[i - 1])) d = std::nextafter(out.depth[i - 1], 3.0e38f);
    out.depth[i] = d;
  }
}

// The GLSL side (shaders/voxel_common.glsl) spells out the same operations under `precise`, so
// no fused multiply-add or reassociation changes a bit.
glm::vec3 voxelPixelRay(const VoxelView& view, int x, int y) {
  const float ndc_x = (static_cast<float>(x) + 0.5f) / static_cast<float>(view.width) * 2.0f - 1.0f;
  const float ndc_y = (static_cast<float>(y) + 0.5f) / static_cast<float>(view.height) * 2.0f - 1.0f;
  // Perspective: ndc = (P00 x + P20 z) / (−z), so at view depth d = −z, x / d = (ndc + P20) / P00.
  return {(ndc_x + view.projection[2][0]) / view.projection[0][0],
          (ndc_y + view.projection[2][1]) / view.projection[1][1], -1.0f};
}

int voxelLayerOf(std::span<const float> depth, float d) {
  const int count = static_cast<int>(depth.size()) - 1;
  if (!(d >= depth[0])) return -1;
  if (d >= depth[static_cast<std::size_t>(count)]) return count;
  int lo = 0, hi = count;
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (depth[static_cast<std::size_t>(mid)] <= d)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

bool voxelSphereLayers(glm::vec3 ray, glm::vec3 c, float radius, std::span<const float> depth, int& first, int& last) {
  // |d·ray − c|² = r²: d² |ray|² − 2 d (ray·c) + |c|² − r² = 0, roots are view depths directly.
  const float rc = ray.x * c.x + ray.y * c.y + ray.z * c.z;
  const float rr = ray.x * ray.x + ray.y * ray.y + ray.z * ray.z;
  const float cc = c.x * c.x + c.y * c.y + c.z * c.z;
  const float disc = rc * rc - rr * (cc - radius * radius);
  if (!(disc > 0.0f)) return false;
  const float s = std::sqrt(disc);
  const float z0 = (rc - s) / rr, z1 = (rc + s) / rr;
  const int count = static_cast<int>(depth.size()) - 1;
  first = voxelLayerOf(depth, z0);
  last = voxelLayerOf(depth, z1);
  if (last < 0 || first >= count) return false;
  first = std::max(first, 0);  // the near plane cuts the sphere: the grid starts at layer 0
  last = std::min(last, count - 1);
  return true;
}

glm::mat3 voxelKernelMatrix(const glm::mat4& v, const glm::mat3& g) {
  // R(i, k) = v[k][i]. D = g − I (exactly 0 for a sphere), T = D Rᵀ, M = I + R T.
  float t[3][3];  // t[k][j] = T(k, j)
  for (int k = 0; k < 3; ++k) {
    const float d0 = g[0][k] - (k == 0 ? 1.0f : 0.0f), d1 = g[1][k] - (k == 1 ? 1.0f : 0.0f),
                d2 = g[2][k] - (k == 2 ? 1.0f : 0.0f);
    for (int j = 0; j < 3; ++j) t[k][j] = (d0 * v[0][j] + d1 * v[1][j]) + d2 * v[2][j];
  }
  glm::mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      m[j][i] = (i == j ? 1.0f : 0.0f) + ((v[0][i] * t[0][j] + v[1][i] * t[1][j]) + v[2][i] * t[2][j]);
  return m;
}

namespace {
glm::vec3 toView(const glm::mat4& v, glm::vec3 p) {
  return {((v[0][0] * p.x + v[1][0] * p.y) + v[2][0] * p.z) + v[3][0],
          ((v[0][1] * p.x + v[1][1] * p.y) + v[2][1] * p.z) + v[3][1],
          ((v[0][2] * p.x + v[1][2] * p.y) + v[2][2] * p.z) + v[3][2]};
}
glm::vec3 mapped(const glm::mat3& m, glm::vec3 p) {
  return {(m[0][0] * p.x + m[1][0] * p.y) + m[2][0] * p.z, (m[0][1] * p.x + m[1][1] * p.y) + m[2][1] * p.z,
          (m[0][2] * p.x + m[1][2] * p.y) + m[2][2] * p.z};
}

// ORs layers [first, last] into one column's words.
void setLayers(std::uint32_t* column, int first, int last) {
  for (int w = first >> 5; w <= last >> 5; ++w) {
    const int lo = std::max(first - 32 * w, 0), hi = std::min(last - 32 * w, 31);
    const std::uint32_t upper = hi == 31 ? 0xffffffffu : ((1u << (hi + 1)) - 1u);
    column[w] |= upper & ~((1u << lo) - 1u);
  }
}

// Every particle against every pixel of the tile; `layersOf(i, ray, first, last)` tests particle i.
template <class LayersOf>
void voxelizeTile(std::size_t count, const VoxelView& view, const VoxelLayers& layers, VoxelTile tile,
                  std::vector<std::uint32_t>& words, LayersOf&& layersOf) {
  const std::size_t per_column = static_cast<std::size_t>(layers.words);
  words.assign(static_cast<std::size_t>(tile.width) * static_cast<std::size_t>(tile.height) * per_column, 0u);
  for (std::size_t i = 0; i < count; ++i) {
    for (int ly = 0; ly < tile.height; ++ly) {
      for (int lx = 0; lx < tile.width; ++lx) {
        int first = 0, last = 0;
        if (!layersOf(i, voxelPixelRay(view, tile.x + lx, tile.y + ly), first, last)) continue;
        setLayers(&words[(static_cast<std::size_t>(ly) * tile.width + lx) * per_column], first, last);
      }
    }
  }
}
}  // namespace

bool voxelEllipsoidLayers(glm::vec3 ray, glm::vec3 c, const glm::mat3& m, float radius, std::span<const float> depth,
                          int& first, int& last) {
  // |m (d·ray − c)| = radius is |d·(m ray) − m c| = radius: the sphere's quadratic in d.
  return voxelSphereLayers(mapped(m, ray), mapped(m, c), radius, depth, first, last);
}

void voxelizeReference(std::span<const glm::vec3> centres, float radius, const VoxelView& view,
                       const VoxelLayers& layers, VoxelTile tile, std::vector<std::uint32_t>& words) {
  std::vector<glm::vec3> c(centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) c[i] = toView(view.view, centres[i]);
  voxelizeTile(centres.size(), view, layers, tile, words, [&](std::size_t i, glm::vec3 ray, int& first, int& last) {
    return voxelSphereLayers(ray, c[i], radius, layers.depth, first, last);
  });
}

void voxelizeReference(std::span<const glm::vec3> centres, std::span<const glm::mat3> g, float radius,
                       const VoxelView& view, const VoxelLayers& layers, VoxelTile tile,
                       std::vector<std::uint32_t>& words) {
  const std::size_t n = std::min(centres.size(), g.size());
  std::vector<glm::vec3> c(n);
  std::vector<glm::mat3> m(n);
  for (std::size_t i = 0; i < n; ++i) {
    m[i] = voxelKernelMatrix(view.view, g[i]);
    c[i] = mapped(m[i], toView(view.view, centres[i]));
  }
  voxelizeTile(n, view, layers, tile, words, [&](std::size_t i, glm::vec3 ray, int& first, int& last) {
    return voxelSphereLayers(mapped(m[i], ray), c[i], radius, layers.depth, first, last);
  });
}

void compressColumnReference(std::span<const std::uint32_t> column, const VoxelLayers& layers, float min_gap,
                             float ray_length, int max_spans, VoxelSpan* spans, VoxelColumn& meta) {
  meta = VoxelColumn{};
  const float* depth = layers.depth.data();
  bool have = false;
  VoxelSpan current;
  auto emit = [&](VoxelSpan s) {
    if (static_cast<int>(meta.stored) < max_spans) {
      spans[meta.stored++] = s;
    } else {  // §3.1: past the stored spans, extend the last one and remember the empty depth inside
      VoxelSpan& back = spans[max_spans - 1];
      meta.hidden_gap += depth[s.entry] - depth[back.exit];
      back.exit = s.exit;
    }
    ++meta.total;
  };
  auto run = [&](std::uint32_t start, std::uint32_t end) {
    if (have) {
      // §3.2 / §4.4: a gap shorter than min_gap along the ray joins the runs into one span.
      const float gap = (depth[start] - depth[current.exit]) * ray_length;
      if (gap < min_gap) {
        current.exit = end;
        return;
      }
      emit(current);
    }
    current = {start, end};
    have = true;
  };
  bool inside = false;
  std::uint32_t start = 0;
  for (int w = 0; w < layers.words; ++w) {
    const std::uint32_t bits = column[static_cast<std::size_t>(w)];
    if (bits == (inside ? 0xffffffffu : 0u)) continue;  // §4.3: whole words without a transition
    int pos = 0;
    while (pos < 32) {
      const std::uint32_t rest = (inside ? ~bits : bits) & (0xffffffffu << pos);
      if (rest == 0u) break;
      const int b = __builtin_ctz(rest);
      const std::uint32_t layer = static_cast<std::uint32_t>(32 * w + b);
      if (inside)
        run(start, layer);
      else
        start = layer;
      inside = !inside;
      pos = b;
    }
  }
  if (inside) run(start, static_cast<std::uint32_t>(layers.count));
  if (have) emit(current);
}

void dropInnerCellParticles(std::span<const glm::vec3> positions, float cell, int full_count,
                            std::vector<std::uint32_t>& kept, std::vector<glm::vec3>& inner_cells) {
  if (!(cell > 0.0f)) {
    for (std::size_t i = 0; i < positions.size(); ++i) kept.push_back(static_cast<std::uint32_t>(i));
    return;
  }
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x & 0x1fffff) << 42) | (static_cast<std::uint64_t>(y & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(z & 0x1fffff);
  };
  auto cellOf = [cell](float v) {
    return static_cast<std::int64_t>(std::floor(std::clamp(static_cast<double>(v) / cell, -1e6, 1e6)));
  };
  std::unordered_map<std::uint64_t, int> counts;
  counts.reserve(positions.size() / 4 + 16);
  for (const glm::vec3& p : positions) ++counts[key(cellOf(p.x), cellOf(p.y), cellOf(p.z))];
  if (full_count <= 0 && !counts.empty()) {
    std::vector<int> occupied;
    occupied.reserve(counts.size());
    for (const auto& [k, n] : counts) occupied.push_back(n);
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    full_count = std::max(2, occupied[occupied.size() / 2] / 2);
  }
  std::unordered_map<std::uint64_t, bool> inner;
  inner.reserve(counts.size());
  auto isInner = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    const std::uint64_t k = key(x, y, z);
    if (const auto found = inner.find(k); found != inner.end()) return found->second;
    bool all = true;
    for (int dz = -1; dz <= 1 && all; ++dz)
      for (int dy = -1; dy <= 1 && all; ++dy)
        for (int dx = -1; dx <= 1 && all; ++dx) {
          const auto c = counts.find(key(x + dx, y + dy, z + dz));
          all = c != counts.end() && c->second >= full_count;
        }
    inner.emplace(k, all);
    return all;
  };
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const glm::vec3& p = positions[i];
    if (!isInner(cellOf(p.x), cellOf(p.y), cellOf(p.z))) kept.push_back(static_cast<std::uint32_t>(i));
  }
  // One sphere per inner cell, in a fixed order (the map's order is not).
  std::vector<std::uint64_t> cells;
  for (const auto& [k, is_inner] : inner)
    if (is_inner) cells.push_back(k);
  std::sort(cells.begin(), cells.end());
  auto unpack = [](std::uint64_t v) {  // 21-bit two's complement fields back to integers
    const std::int64_t f = static_cast<std::int64_t>(v & 0x1fffff);
    return f >= 0x100000 ? f - 0x200000 : f;
  };
  for (std::uint64_t k : cells)
    inner_cells.push_back(glm::vec3(static_cast<float>(unpack(k >> 42)) + 0.5f,
                                    static_cast<float>(unpack(k >> 21)) + 0.5f, static_cast<float>(unpack(k)) + 0.5f) *
                          cell);
}

}  // namespace fluid
