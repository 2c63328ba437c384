// CPU rasterizer baking depth maps from a triangle mesh (Kolb et al. 2004 §4.1, §4.3):
// orthographic maps with depth compare LESS (front) / GREATER (back), front-back pairs in one
// texture, and perspective depth cubes from the view-volume centre. Ortho maps are rasterized
// conservatively (every texel the triangle touches; depth at the texel centre or the nearest
// point of the triangle), cube texels by the ray through the texel centre; double precision, triangles in index order,
// strict compare: the result is deterministic and independent of the thread count.
#include "fluid/collide/collide.hpp"
#include "fluid/collide/mesh_checks.hpp"
#include "fluid/core/parallel.hpp"

#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <string_view>
#include <thread>
#include <unordered_map>

namespace fluid {

namespace {

using dvec3 = glm::dvec3;

struct Frame {
  glm::vec3 right, up, forward;
};

Frame orthoFrame(const OrthoView& v) {
  const glm::vec3 f = glm::normalize(v.forward);
  const glm::vec3 r = glm::normalize(glm::cross(v.up, f));
  return {r, glm::cross(f, r), f};
}

glm::mat4 orthoMatrix(const OrthoView& v) {
  const Frame fr = orthoFrame(v);
  const glm::vec3 inv = 0.5f / v.half_extent;
  glm::mat4 m(0.0f);
  // Rows of T: axis / (2h); translation maps the box onto [0,1]³.
  for (int c = 0; c < 3; ++c) {
    m[c][0] = fr.right[c] * inv.x;
    m[c][1] = fr.up[c] * inv.y;
    m[c][2] = fr.forward[c] * inv.z;
  }
  m[3][0] = 0.5f - glm::dot(fr.right, v.center) * inv.x;
  m[3][1] = 0.5f - glm::dot(fr.up, v.center) * inv.y;
  m[3][2] = 0.5f - glm::dot(fr.forward, v.center) * inv.z;
  m[3][3] = 1.0f;
  return m;
}

glm::mat4 cubeMatrix(const CubeView& v) {
  glm::mat4 m(0.0f);
  for (int c = 0; c < 3; ++c) {
    m[c][c] = 1.0f / v.half_extent[c];
    m[3][c] = -v.center[c] / v.half_extent[c];
  }
  m[3][3] = 1.0f;
  return m;
}

dvec3 apply(const glm::mat4& m, glm::vec3 p) { return dvec3(glm::dvec4(m * glm::vec4(p, 1.0f))); }

// Per-texel result of the depth test: depth and the winning triangle.
struct Buffer {
  std::vector<double> depth;
  std::vector<std::int32_t> triangle;
  void reset(std::size_t n, double init) {
    depth.assign(n, init);
    triangle.assign(n, -1);
  }
};

// Cube face (sc, tc, ma) basis in the OpenGL table order: direction = ma·A + sc·S + tc·T.
struct FaceBasis {
  dvec3 major, s, t;
};
constexpr int kFaces = 6;
const FaceBasis kFaceBasis[kFaces] = {
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},   // +X: sc = −z, tc = −y
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},   // −X: sc = z, tc = −y
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},     // +Y: sc = x, tc = z
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},   // −Y: sc = x, tc = −z
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},    // +Z: sc = x, tc = −y
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}},  // −Z: sc = −x, tc = −y
};

struct TexelBox {
  int i0 = 1, j0 = 1, i1 = 0, j1 = 0;  // inclusive; empty when i0 > i1
};

int threadCount(int requested) {
  return requested > 0 ? requested : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// One ortho map (both compares when front_back).
// `margin` (map units per axis) widens every triangle's cover beyond the texel square (see
// MapSpec::margin): a texel no triangle covers but one within the margin (the ring) gets, in
// both the LESS and the GREATER buffer, the depth of the laterally nearest triangle's nearest
// outline point. Equal front and back depths make one of the two eq. (1) votes >= 0 at any
// depth, so a ring texel never calls a point inside (a point beside the silhouette is outside).
void rasterOrtho(const MeshView& mesh, const std::vector<char>& skip, const glm::mat4& t_map, int n, glm::dvec2 margin,
                 bool want_less, bool want_greater, Buffer& less, Buffer& greater) {
  const std::size_t tris = mesh.indices.size() / 3;
  std::vector<dvec3> v(mesh.positions.size());
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = apply(t_map, mesh.positions[k]);
  // Texel bounds per triangle; the outer ring of texels is the invalid border (§4.1).
  std::vector<TexelBox> boxes(tris);
  for (std::size_t tri = 0; tri < tris; ++tri) {
    if (skip[tri]) continue;
    const dvec3 a = v[mesh.indices[3 * tri]], b = v[mesh.indices[3 * tri + 1]], c = v[mesh.indices[3 * tri + 2]];
    const double lo_x = std::min({a.x, b.x, c.x}), hi_x = std::max({a.x, b.x, c.x});
    const double lo_y = std::min({a.y, b.y, c.y}), hi_y = std::max({a.y, b.y, c.y});
    TexelBox box;
    // Texels whose square [centre ± half a texel] can overlap the triangle's bounds.
    box.i0 = std::max(1, static_cast<int>(std::ceil((lo_x - margin.x) * n - 1.0)));
    box.i1 = std::min(n - 2, static_cast<int>(std::floor((hi_x + margin.x) * n)));
    box.j0 = std::max(1, static_cast<int>(std::ceil((lo_y - margin.y) * n - 1.0)));
    box.j1 = std::min(n - 2, static_cast<int>(std::floor((hi_y + margin.y) * n)));
    boxes[tri] = box;
  }
  const std::size_t texels = static_cast<std::size_t>(n) * n;
  if (want_less) less.reset(texels, std::numeric_limits<double>::infinity());
  if (want_greater) greater.reset(texels, -std::numeric_limits<double>::infinity());
  const double h = 0.5 / n;  // half a texel in map coordinates
  const bool with_ring = margin.x > 0.0 || margin.y > 0.0;
  Buffer ring;  // ring texels: depth, triangle, and the lateral distance² (map units) deciding them
  std::vector<double> ring_d2;
  if (with_ring) {
    ring.reset(texels, 0.0);
    ring_d2.assign(texels, std::numeric_limits<double>::infinity());
  }
  const int band = 8;
  auto raster_band = [&](int b) {
    const int row0 = b * band, row1 = std::min(n - 1, row0 + band - 1);
    for (std::size_t tri = 0; tri < tris; ++tri) {
      const TexelBox& box = boxes[tri];
      if (skip[tri] || box.i0 > box.i1 || box.j1 < row0 || box.j0 > row1) continue;
      const dvec3 p[3] = {v[mesh.indices[3 * tri]], v[mesh.indices[3 * tri + 1]], v[mesh.indices[3 * tri + 2]]};
      const double area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x);
      if (area == 0.0) continue;  // edge-on: its neighbours cover the silhouette
      const double inv_area = 1.0 / area;
      for (int j = std::max(row0, box.j0); j <= std::min(row1, box.j1); ++j) {
        const double y = (j + 0.5) / n;
        for (int i = box.i0; i <= box.i1; ++i) {
          const double x = (i + 0.5) / n;
          // Conservative coverage: the texel square overlaps the projected triangle
          // (separating axes: the bounding box, done by the loop bounds, and the three edge
          // normals). A point inside the collider therefore never lands on a background texel,
          // which makes "invalid vote = far outside" safe for enclosing maps (§4.1).
          // The ring (with a margin): the same test with the square widened by the margin.
          bool separated = false, in_ring = false;
          for (int e = 0; e < 3 && !separated; ++e) {
            const dvec3 a = p[e], c = p[(e + 1) % 3], o = p[(e + 2) % 3];
            const double mx = -(c.y - a.y), my = c.x - a.x;
            const double ta = mx * a.x + my * a.y, to = mx * o.x + my * o.y;
            const double centre = mx * x + my * y, reach = h * (std::fabs(mx) + std::fabs(my));
            const double wide = reach + margin.x * std::fabs(mx) + margin.y * std::fabs(my);
            separated = centre + wide < std::min(ta, to) || centre - wide > std::max(ta, to);
            in_ring = in_ring || centre + reach < std::min(ta, to) || centre - reach > std::max(ta, to);
          }
          if (separated) continue;
          // Depth at the texel centre when it is inside (inclusive edges: no cracks), otherwise
          // at the nearest point of the triangle's outline.
          const double w0 = ((p[1].x - x) * (p[2].y - y) - (p[1].y - y) * (p[2].x - x)) * inv_area;
          const double w1 = ((p[2].x - x) * (p[0].y - y) - (p[2].y - y) * (p[0].x - x)) * inv_area;
          const double w2 = 1.0 - w0 - w1;
          double z, best = 0.0;
          if (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0) {
            z = w0 * p[0].z + w1 * p[1].z + w2 * p[2].z;
          } else {
            best = std::numeric_limits<double>::infinity();
            z = p[0].z;
            for (int e = 0; e < 3; ++e) {
              const dvec3 a = p[e], c = p[(e + 1) % 3];
              const double ex = c.x - a.x, ey = c.y - a.y, len2 = ex * ex + ey * ey;
              const double t = len2 > 0.0 ? std::clamp(((x - a.x) * ex + (y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
              const double dx = a.x + t * ex - x, dy = a.y + t * ey - y, d2 = dx * dx + dy * dy;
              if (d2 < best) {
                best = d2;
                z = a.z + t * (c.z - a.z);
              }
            }
          }
          if (z < 0.0 || z > 1.0) continue;  // clipped by near/far planes
          const std::size_t k = static_cast<std::size_t>(j) * n + i;
          if (in_ring) {
            if (best < ring_d2[k]) {
              ring_d2[k] = best;
              ring.depth[k] = z;
              ring.triangle[k] = static_cast<std::int32_t>(tri);
            }
            continue;
          }
          if (want_less && z < less.depth[k]) {
            less.depth[k] = z;
            less.triangle[k] = static_cast<std::int32_t>(tri);
          }
          if (want_greater && z > greater.depth[k]) {
            greater.depth[k] = z;
            greater.triangle[k] = static_cast<std::int32_t>(tri);
          }
        }
      }
    }
  };
  par::parallelFor(par::Range<int>(0, (n + band - 1) / band, 1), [&](const par::Range<int>& r) {
    for (int b = r.begin(); b != r.end(); ++b) raster_band(b);
  });
  if (!with_ring) return;
  for (std::size_t k = 0; k < texels; ++k) {
    if (ring.triangle[k] < 0) continue;
    const bool covered = want_less ? less.triangle[k] >= 0 : greater.triangle[k] >= 0;
    if (covered) continue;
    for (Buffer* b : {want_less ? &less : nullptr, want_greater ? &greater : nullptr}) {
      if (b == nullptr) continue;
      b->depth[k] = ring.depth[k];
      b->triangle[k] = ring.triangle[k];
    }
  }
}

// Depth cube: rays from the centre of the normalised volume through each texel centre.
void rasterCube(const MeshView& mesh, const std::vector<char>& skip, const glm::mat4& t_map, int n, bool less_compare,
                Buffer& out) {
  const std::size_t tris = mesh.indices.size() / 3;
  std::vector<dvec3> v(mesh.positions.size());
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = apply(t_map, mesh.positions[k]);
  out.reset(static_cast<std::size_t>(kFaces) * n * n,
            less_compare ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity());
  std::vector<TexelBox> boxes(tris * kFaces);
  for (std::size_t tri = 0; tri < tris; ++tri) {
    if (skip[tri]) continue;
    const dvec3 p[3] = {v[mesh.indices[3 * tri]], v[mesh.indices[3 * tri + 1]], v[mesh.indices[3 * tri + 2]]};
    for (int f = 0; f < kFaces; ++f) {
      const FaceBasis& fb = kFaceBasis[f];
      // Clip the triangle to the half space in front of the face (ma >= eps), then project.
      constexpr double kEps = 1e-9;
      dvec3 poly[4];
      int count = 0;
      for (int e = 0; e < 3; ++e) {
        const dvec3 a = p[e], b = p[(e + 1) % 3];
        const double da = glm::dot(a, fb.major) - kEps, db = glm::dot(b, fb.major) - kEps;
        if (da >= 0.0) poly[count++] = a;
        if ((da >= 0.0) != (db >= 0.0) && count < 4) poly[count++] = a + (b - a) * (da / (da - db));
      }
      TexelBox& box = boxes[tri * kFaces + f];
      if (count == 0) continue;
      double lo_s = DBL_MAX, hi_s = -DBL_MAX, lo_t = DBL_MAX, hi_t = -DBL_MAX;
      for (int k = 0; k < count; ++k) {
        const double ma = glm::dot(poly[k], fb.major);
        const double s = (glm::dot(poly[k], fb.s) / ma + 1.0) * 0.5, t = (glm::dot(poly[k], fb.t) / ma + 1.0) * 0.5;
        lo_s = std::min(lo_s, s);
        hi_s = std::max(hi_s, s);
        lo_t = std::min(lo_t, t);
        hi_t = std::max(hi_t, t);
      }
      if (hi_s < 0.0 || lo_s > 1.0 || hi_t < 0.0 || lo_t > 1.0) continue;
      box.i0 = std::max(0, static_cast<int>(std::ceil(std::max(lo_s, -1.0) * n - 0.5)) - 1);
      box.i1 = std::min(n - 1, static_cast<int>(std::floor(std::min(hi_s, 2.0) * n - 0.5)) + 1);
      box.j0 = std::max(0, static_cast<int>(std::ceil(std::max(lo_t, -1.0) * n - 0.5)) - 1);
      box.j1 = std::min(n - 1, static_cast<int>(std::floor(std::min(hi_t, 2.0) * n - 0.5)) + 1);
    }
  }
  const int band = 8;
  const int bands = (n + band - 1) / band;
  auto raster_job = [&](int job) {
    const int f = job / bands;
    const int row0 = (job % bands) * band, row1 = std::min(n - 1, row0 + band - 1);
    const FaceBasis& fb = kFaceBasis[f];
    for (std::size_t tri = 0; tri < tris; ++tri) {
      const TexelBox& box = boxes[tri * kFaces + f];
      if (skip[tri] || box.i0 > box.i1 || box.j1 < row0 || box.j0 > row1) continue;
      const dvec3 a = v[mesh.indices[3 * tri]], b = v[mesh.indices[3 * tri + 1]], c = v[mesh.indices[3 * tri + 2]];
      const dvec3 e1 = b - a, e2 = c - a;
      for (int j = std::max(row0, box.j0); j <= std::min(row1, box.j1); ++j) {
        const double tc = 2.0 * (j + 0.5) / n - 1.0;
        for (int i = box.i0; i <= box.i1; ++i) {
          const double sc = 2.0 * (i + 0.5) / n - 1.0;
          const dvec3 d = fb.major + sc * fb.s + tc * fb.t;
          // Möller–Trumbore from the origin (the view-volume centre, §4.3).
          const dvec3 pv = glm::cross(d, e2);
          const double det = glm::dot(e1, pv);
          if (det == 0.0) continue;
          const double inv = 1.0 / det;
          const dvec3 tv = -a;
          const double u = glm::dot(tv, pv) * inv;
          if (u < 0.0 || u > 1.0) continue;
          const dvec3 qv = glm::cross(tv, e1);
          const double w = glm::dot(d, qv) * inv;
          if (w < 0.0 || u + w > 1.0) continue;
          const double hit = glm::dot(e2, qv) * inv;
          if (hit <= 0.0) continue;
          const dvec3 h = hit * d;
          if (std::fabs(h.x) > 1.0 || std::fabs(h.y) > 1.0 || std::fabs(h.z) > 1.0) continue;  // outside the volume
          const double r = hit * glm::length(d);
          const std::size_t k = static_cast<std::size_t>(f) * n * n + static_cast<std::size_t>(j) * n + i;
          if (less_compare ? r < out.depth[k] : r > out.depth[k]) {
            out.depth[k] = r;
            out.triangle[k] = static_cast<std::int32_t>(tri);
          }
        }
      }
    }
  };
  par::parallelFor(par::Range<int>(0, kFaces * bands, 1), [&](const par::Range<int>& r) {
    for (int job = r.begin(); job != r.end(); ++job) raster_job(job);
  });
}

void storeU16(std::uint8_t* p, std::uint16_t v) { std::memcpy(p, &v, 2); }

void storeFixed(std::uint8_t* t, std::uint32_t normal_ij, std::uint16_t q) {
  t[0] = static_cast<std::uint8_t>(normal_ij & 0xFFu);
  t[1] = static_cast<std::uint8_t>(normal_ij >> 8);
  t[2] = static_cast<std::uint8_t>(q >> 8);
  t[3] = static_cast<std::uint8_t>(q & 0xFFu);
}

bool finite(glm::vec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

}  // namespace

std::int64_t firstBadVertex(std::span<const glm::vec3> positions, float limit) {
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const glm::vec3 p = positions[k];
    if (!finite(p) || std::fabs(p.x) > limit || std::fabs(p.y) > limit || std::fabs(p.z) > limit) {
      return static_cast<std::int64_t>(k);
    }
  }
  return -1;
}

ClosedMeshReport checkClosed(const MeshView& mesh) {
  ClosedMeshReport report;
  // Weld: one id per distinct position (+0.0f added so -0 and +0 share their bits).
  auto bits = [](float v) { return std::bit_cast<std::uint32_t>(v + 0.0f); };
  struct KeyHash {
    std::size_t operator()(const std::array<std::uint32_t, 3>& k) const {
      return (std::size_t{k[0]} * 0x9E3779B97F4A7C15ull) ^ (std::size_t{k[1]} * 0xC2B2AE3D27D4EB4Full) ^ k[2];
    }
  };
  std::unordered_map<std::array<std::uint32_t, 3>, std::uint32_t, KeyHash> ids;
  std::vector<std::uint32_t> weld(mesh.positions.size());
  for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
    const glm::vec3 p = mesh.positions[k];
    weld[k] = ids.try_emplace({bits(p.x), bits(p.y), bits(p.z)}, static_cast<std::uint32_t>(ids.size())).first->second;
  }
  report.welded_vertices = ids.size();
  // Undirected edge -> use count and the first triangle's endpoints (for the message).
  struct EdgeUse {
    std::uint32_t count = 0;
    std::size_t first = 0;  // order of first use, so the reported edge does not depend on hashing
    glm::vec3 from{0.0f}, to{0.0f};
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  std::size_t order = 0;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const std::uint32_t v[3] = {weld[mesh.indices[t]], weld[mesh.indices[t + 1]], weld[mesh.indices[t + 2]]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;  // collapsed by the weld
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = v[e], b = v[(e + 1) % 3];
      const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      EdgeUse& use = edges[key];
      if (use.count++ == 0) {
        use.first = order++;
        use.from = mesh.positions[mesh.indices[t + static_cast<std::size_t>(e)]];
        use.to = mesh.positions[mesh.indices[t + static_cast<std::size_t>((e + 1) % 3)]];
      }
    }
  }
  std::size_t first = SIZE_MAX;
  for (const auto& [key, use] : edges) {
    if (use.count % 2 == 0) continue;
    ++report.boundary_edges;
    if (use.first < first) {
      first = use.first;
      report.edge_from = use.from;
      report.edge_to = use.to;
    }
  }
  return report;
}

Bounds meshBounds(const MeshView& mesh) {
  Bounds b{glm::vec3(FLT_MAX), glm::vec3(-FLT_MAX)};
  for (std::uint32_t index : mesh.indices) {
    if (index >= mesh.positions.size()) continue;
    b.lo = glm::min(b.lo, mesh.positions[index]);
    b.hi = glm::max(b.hi, mesh.positions[index]);
  }
  if (mesh.indices.empty()) b = Bounds{};
  return b;
}

std::vector<MapSpec> defaultMapSpecs(const Bounds& bounds, int resolution, DepthMapFormat format, bool with_cube,
                                     float padding) {
  std::vector<MapSpec> specs;
  const glm::vec3 center = (bounds.lo + bounds.hi) * 0.5f;
  const glm::vec3 half = (bounds.hi - bounds.lo) * 0.5f;
  const float pad = padding * 2.0f * std::max({half.x, half.y, half.z, 1e-6f});
  const glm::vec3 padded = half + glm::vec3(pad);
  // Two texels of margin on each side so the mesh never touches the one-texel border.
  const float margin = static_cast<float>(resolution) / static_cast<float>(std::max(resolution - 4, 1));
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const glm::vec3 ups[3] = {{0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
  for (int a = 0; a < 3; ++a) {
    MapSpec s;
    s.kind = MapKind::ortho;
    s.resolution = resolution;
    s.ortho.center = center;
    s.ortho.forward = axes[a];
    s.ortho.up = ups[a];
    const int u = (a + 1) % 3, w = (a + 2) % 3;
    const float side = std::max(padded[u], padded[w]) * margin;
    s.ortho.half_extent = {side, side, padded[a] * 1.01f};
    if (format == DepthMapFormat::front_back16) {
      s.format = format;
      specs.push_back(s);
    } else {
      s.format = format == DepthMapFormat::cube8 ? DepthMapFormat::fixed8 : format;
      s.compare = DepthCompare::less;
      specs.push_back(s);
      s.compare = DepthCompare::greater;
      specs.push_back(s);
    }
  }
  if (with_cube) specs.push_back(cubeMapSpec(center, padded * 1.01f, resolution, DepthCompare::greater));
  return specs;
}

MapSpec cubeMapSpec(glm::vec3 center, glm::vec3 half_extent, int resolution, DepthCompare compare) {
  MapSpec c;
  c.kind = MapKind::cube;
  c.format = DepthMapFormat::cube8;
  c.compare = compare;
  c.resolution = resolution;
  c.cube.center = center;
  c.cube.half_extent = half_extent;
  return c;
}

namespace {

// "X:Y:Z:H" or "X:Y:Z:H:N", every field a whole number token (nothing before, between or after).
bool parseCubeItem(std::string_view text, float& x, float& y, float& z, float& h, int& n) {
  float* const values[4] = {&x, &y, &z, &h};
  for (int field = 0; field < 5; ++field) {
    const std::size_t colon = text.find(':');
    const std::string_view part = text.substr(0, colon);
    const char* const end = part.data() + part.size();
    const auto result =
        field < 4 ? std::from_chars(part.data(), end, *values[field]) : std::from_chars(part.data(), end, n);
    if (part.empty() || result.ec != std::errc() || result.ptr != end) return false;
    if (colon == std::string_view::npos) return field >= 3;
    text.remove_prefix(colon + 1);
  }
  return false;  // a sixth field
}

}  // namespace

bool parseMapSpec(const std::string& spec, const Bounds& bounds, int resolution, DepthMapFormat format,
                  std::vector<MapSpec>& out, std::string& error) {
  out.clear();
  const DepthMapFormat ortho_format = format == DepthMapFormat::cube8 ? DepthMapFormat::fixed8 : format;
  const std::vector<MapSpec> axes = defaultMapSpecs(bounds, resolution, ortho_format, true);
  const std::size_t per_axis = ortho_format == DepthMapFormat::front_back16 ? 1 : 2;
  std::stringstream items(spec);
  std::string item;
  bool any = false;
  while (std::getline(items, item, ',')) {
    any = true;
    if (item == "axes") {
      out.insert(out.end(), axes.begin(), axes.end() - 1);
    } else if (item == "x" || item == "y" || item == "z") {
      const std::size_t a = static_cast<std::size_t>(item[0] - 'x');
      out.insert(out.end(), axes.begin() + a * per_axis, axes.begin() + (a + 1) * per_axis);
    } else if (item == "cube" || item == "cube-less") {
      MapSpec c = axes.back();
      if (item == "cube-less") c.compare = DepthCompare::less;
      out.push_back(c);
    } else if (item.rfind("cube@", 0) == 0) {
      // An optional fifth field is the cube's own resolution: the automatic map choice
      // (coverage.cpp) sizes a cube's texels to the ortho maps' at the surface it sees, so a
      // cube near its surface costs fewer bytes than one at the collider's resolution.
      float x = 0.0f, y = 0.0f, z = 0.0f, h = 0.0f;
      int n = resolution;
      if (!parseCubeItem(std::string_view(item).substr(5), x, y, z, h, n) || !(h > 0.0f) ||
          !std::isfinite(x + y + z + h) || n < 4 || n > 4096) {
        error = "--maps: bad item '" + item + "' (expected cube@X:Y:Z:H or cube@X:Y:Z:H:N with H > 0, N in 4..4096)";
        return false;
      }
      out.push_back(cubeMapSpec({x, y, z}, glm::vec3(h), n, DepthCompare::less));
    } else {
      error = "--maps: unknown item '" + item +
              "' (expected axes, x, y, z, cube, cube-less or cube@X:Y:Z:H[:N]; auto only alone, in bake-collider)";
      return false;
    }
  }
  if (!any) {
    error = "--maps: empty list";
    return false;
  }
  return true;
}

BakeStatus bakeDepthMaps(const MeshView& mesh, std::span<const MapSpec> specs, const BakeDesc& desc,
                         DepthMapCollider& out) {
  BakeStatus status;
  if (mesh.indices.empty() || mesh.positions.empty()) {
    status.error = "mesh is empty (no triangles): nothing to bake";
    return status;
  }
  if (mesh.indices.size() % 3 != 0) {
    status.error = "mesh index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3";
    return status;
  }
  for (std::size_t k = 0; k < mesh.indices.size(); ++k) {
    if (mesh.indices[k] >= mesh.positions.size()) {
      status.error = "triangle " + std::to_string(k / 3) + ": vertex index " + std::to_string(mesh.indices[k]) +
                     " out of range (" + std::to_string(mesh.positions.size()) + " vertices)";
      return status;
    }
    const glm::vec3 p = mesh.positions[mesh.indices[k]];
    if (!finite(p)) {
      status.error = "vertex " + std::to_string(mesh.indices[k]) + " has a non-finite coordinate";
      return status;
    }
    if (firstBadVertex(std::span(&p, 1)) >= 0) {
      char text[160];
      std::snprintf(text, sizeof text, "vertex %u at (%g, %g, %g) is beyond the collider coordinate limit +-%g",
                    mesh.indices[k], p.x, p.y, p.z, static_cast<double>(kMaxColliderCoordinate));
      status.error = text;
      return status;
    }
  }
  if (desc.normal_resolution < 2 || desc.normal_resolution > 256) {
    status.error = "normal_resolution " + std::to_string(desc.normal_resolution) + " out of range 2..256";
    return status;
  }
  if (specs.empty()) {
    status.error = "no depth maps requested";
    return status;
  }
  for (std::size_t s = 0; s < specs.size(); ++s) {
    const MapSpec& spec = specs[s];
    const std::string where = "map " + std::to_string(s) + ": ";
    if (spec.resolution < 4 || spec.resolution > 4096) {
      status.error = where + "resolution " + std::to_string(spec.resolution) + " out of range 4..4096";
      return status;
    }
    if (spec.kind == MapKind::cube && spec.format != DepthMapFormat::cube8) {
      status.error = where + "a depth cube must use format cube8";
      return status;
    }
    if (spec.kind == MapKind::ortho && spec.format == DepthMapFormat::cube8) {
      status.error = where + "format cube8 needs kind cube";
      return status;
    }
    const glm::vec3 h = spec.kind == MapKind::cube ? spec.cube.half_extent : spec.ortho.half_extent;
    if (!(h.x > 0.0f && h.y > 0.0f && h.z > 0.0f) || !finite(h)) {
      status.error = where + "view volume half extents must be positive and finite";
      return status;
    }
    if (!(spec.margin >= 0.0f && spec.margin <= 1e5f)) {
      status.error = where + "margin must be finite and >= 0";
      return status;
    }
    if (spec.kind == MapKind::ortho) {
      const glm::vec3 c = glm::cross(spec.ortho.up, spec.ortho.forward);
      if (!(glm::dot(c, c) > 1e-12f) || !finite(c)) {
        status.error = where + "forward and up must be non-zero and not parallel";
        return status;
      }
    }
  }

  // Zero-area triangles have no normal; skip them (their neighbours cover the surface).
  const std::size_t tris = mesh.indices.size() / 3;
  std::vector<char> skip(tris, 0);
  std::vector<glm::vec3> normals(tris);
  for (std::size_t t = 0; t < tris; ++t) {
    const dvec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                c = mesh.positions[mesh.indices[3 * t + 2]];
    const dvec3 n = glm::cross(b - a, c - a);
    const double scale = std::max({glm::dot(b - a, b - a), glm::dot(c - a, c - a), glm::dot(c - b, c - b)});
    if (!(glm::length(n) > 1e-12 * scale) || scale == 0.0) {
      skip[t] = 1;
      ++status.degenerate_triangles;
      continue;
    }
    normals[t] = glm::vec3(glm::normalize(n));
  }
  // Outward = counter-clockwise; a mesh whose signed volume is negative is wound clockwise
  // throughout, so flip every normal. (Orienting per texel by the view direction instead
  // fails for back-facing triangles caught at silhouettes.)
  double volume6 = 0.0;
  for (std::size_t t = 0; t < tris; ++t) {
    const dvec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                c = mesh.positions[mesh.indices[3 * t + 2]];
    volume6 += glm::dot(a, glm::cross(b, c));
  }
  if (volume6 < 0.0) {
    for (glm::vec3& nn : normals) nn = -nn;
  }
  if (status.degenerate_triangles == tris) {
    status.error = "all " + std::to_string(tris) + " triangles are degenerate (zero area): nothing to bake";
    return status;
  }

  const Bounds bounds = meshBounds(mesh);
  const int rn = desc.normal_resolution;
  std::vector<DepthMap> maps;
  tbb::task_arena arena(threadCount(desc.threads));
  arena.execute([&] {
    Buffer less, greater;
    for (const MapSpec& spec : specs) {
      DepthMap map;
      map.format = spec.format;
      map.compare = spec.compare;
      map.resolution = static_cast<std::uint32_t>(spec.resolution);
      const int n = spec.resolution;
      if (spec.kind == MapKind::ortho) {
        map.collider_to_map = orthoMatrix(spec.ortho);
        map.z_scale = 2.0f * spec.ortho.half_extent.z;
        const bool both = spec.format == DepthMapFormat::front_back16;
        const bool want_less = both || spec.compare == DepthCompare::less;
        const bool want_greater = both || spec.compare == DepthCompare::greater;
        const glm::dvec2 margin(spec.margin / (2.0 * spec.ortho.half_extent.x),
                                spec.margin / (2.0 * spec.ortho.half_extent.y));
        rasterOrtho(mesh, skip, map.collider_to_map, n, margin, want_less, want_greater, less, greater);
        map.margin_ring = spec.margin > 0.0f && both;
        auto oriented = [&](std::int32_t tri, bool) { return normals[static_cast<std::size_t>(tri)]; };
        map.encloses_collider = true;
        for (int corner = 0; corner < 8; ++corner) {
          const glm::vec3 p{corner & 1 ? bounds.hi.x : bounds.lo.x, corner & 2 ? bounds.hi.y : bounds.lo.y,
                            corner & 4 ? bounds.hi.z : bounds.lo.z};
          const dvec3 q = apply(map.collider_to_map, p);
          const double lo = 1.0 / n, hi = 1.0 - 1.0 / n;
          if (!(q.x >= lo && q.x <= hi && q.y >= lo && q.y <= hi && q.z >= 0.0 && q.z <= 1.0)) {
            map.encloses_collider = false;
          }
        }
        const std::size_t count = static_cast<std::size_t>(n) * n;
        map.texels.assign(count * texelBytes(spec.format), 0);
        for (std::size_t k = 0; k < count; ++k) {
          std::uint8_t* t = map.texels.data() + k * texelBytes(spec.format);
          const Buffer& one = want_less ? less : greater;
          switch (spec.format) {
            case DepthMapFormat::float32: {
              float v[4] = {0.0f, 0.0f, 0.0f, -1.0f};
              if (one.triangle[k] >= 0) {
                const glm::vec3 nn = oriented(one.triangle[k], want_less);
                v[0] = nn.x;
                v[1] = nn.y;
                v[2] = nn.z;
                v[3] = static_cast<float>(one.depth[k]);
              }
              std::memcpy(t, v, 16);
              break;
            }
            case DepthMapFormat::fixed8: {
              if (one.triangle[k] < 0) {
                storeFixed(t, 0xFFFFu, kFixedBackground);
              } else {
                const glm::ivec2 ij = l1Texel(oriented(one.triangle[k], want_less), rn);
                storeFixed(t, static_cast<std::uint32_t>(ij.x | (ij.y << 8)),
                           encodeFixedDepth(static_cast<float>(one.depth[k])));
              }
              break;
            }
            case DepthMapFormat::front_back16: {
              const Buffer* layer[2] = {&less, &greater};
              for (int l = 0; l < 2; ++l) {
                std::uint16_t index = 0xFFFFu, depth = kHalfBackground;
                if (layer[l]->triangle[k] >= 0) {
                  const glm::ivec2 ij = l1Texel(oriented(layer[l]->triangle[k], l == 0), rn);
                  index = static_cast<std::uint16_t>(ij.x | (ij.y << 8));
                  depth = floatToHalf(static_cast<float>(layer[l]->depth[k]));
                }
                storeU16(t + 2 * l, index);
                storeU16(t + 4 + 2 * l, depth);
              }
              break;
            }
            case DepthMapFormat::cube8:
              break;
          }
        }
      } else {
        map.collider_to_map = cubeMatrix(spec.cube);
        map.cube_scale = spec.cube.half_extent;
        const bool is_less = spec.compare == DepthCompare::less;
        rasterCube(mesh, skip, map.collider_to_map, n, is_less, less);
        map.encloses_collider = true;
        for (int corner = 0; corner < 8; ++corner) {
          const glm::vec3 p{corner & 1 ? bounds.hi.x : bounds.lo.x, corner & 2 ? bounds.hi.y : bounds.lo.y,
                            corner & 4 ? bounds.hi.z : bounds.lo.z};
          const dvec3 q = apply(map.collider_to_map, p);
          if (!(std::fabs(q.x) <= 1.0 && std::fabs(q.y) <= 1.0 && std::fabs(q.z) <= 1.0)) map.encloses_collider = false;
        }
        const std::size_t count = static_cast<std::size_t>(kFaces) * n * n;
        map.texels.assign(count * 4, 0);
        for (std::size_t k = 0; k < count; ++k) {
          std::uint8_t* t = map.texels.data() + k * 4;
          const std::int32_t tri = less.triangle[k];
          if (tri < 0) {
            storeFixed(t, 0xFFFFu, kFixedBackground);
            continue;
          }
          const glm::vec3 nn = normals[static_cast<std::size_t>(tri)];
          const glm::ivec2 ij = l1Texel(nn, rn);
          const double depth01 = less.depth[k] / 1.7320508075688772;
          storeFixed(t, static_cast<std::uint32_t>(ij.x | (ij.y << 8)), encodeFixedDepth(static_cast<float>(depth01)));
        }
      }
      maps.push_back(std::move(map));
    }
  });
  out = DepthMapCollider(std::move(maps), rn);
  return status;
}

}  // namespace fluid
