#pragma once
// Helpers for the surface tests: welding by lattice edge, watertightness, orientation, and a
// canonical triangle list for comparing meshes from different extractors.

#include <glm/glm.hpp>
#include <stdexcept>
#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace surface_test {

using Tri = std::array<std::uint64_t, 3>;

// Triangles as edge-key triples, rotated so the smallest key is first (winding kept), sorted.
inline std::vector<Tri> canonicalTriangles(const fluid::SurfaceMesh& m) {
  std::vector<Tri> out;
  out.reserve(m.indices.size() / 3);
  for (std::size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    Tri t = {m.edgeKeys[m.indices[i]], m.edgeKeys[m.indices[i + 1]], m.edgeKeys[m.indices[i + 2]]};
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct Topology {
  std::size_t triangles = 0;
  std::size_t degenerate = 0;           // triangles with a repeated welded vertex
  std::size_t badEdges = 0;             // directed edges not matched by exactly one opposite edge
  std::size_t keyPositionMismatch = 0;  // same edge key, different position
  double signedVolume = 0;              // > 0 for outward winding
  double area = 0;
  std::size_t normalsAgainstFaces = 0;  // vertex normal opposite to its triangle's normal
};

inline Topology checkTopology(const fluid::SurfaceMesh& m) {
  Topology t;
  t.triangles = m.indices.size() / 3;
  std::unordered_map<std::uint64_t, glm::vec3> pos;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    auto [it, fresh] = pos.emplace(m.edgeKeys[v], m.positions[v]);
    if (!fresh && it->second != m.positions[v]) ++t.keyPositionMismatch;
  }
  std::map<std::pair<std::uint64_t, std::uint64_t>, int> directed;
  for (std::size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    const std::uint64_t k[3] = {m.edgeKeys[m.indices[i]], m.edgeKeys[m.indices[i + 1]], m.edgeKeys[m.indices[i + 2]]};
    if (k[0] == k[1] || k[1] == k[2] || k[0] == k[2]) ++t.degenerate;
    for (int e = 0; e < 3; ++e) ++directed[{k[e], k[(e + 1) % 3]}];
    const glm::dvec3 a = m.positions[m.indices[i]], b = m.positions[m.indices[i + 1]],
                     c = m.positions[m.indices[i + 2]];
    t.signedVolume += glm::dot(a, glm::cross(b, c)) / 6.0;
    const glm::dvec3 fn = glm::cross(b - a, c - a);
    t.area += 0.5 * glm::length(fn);
    for (int e = 0; e < 3; ++e)
      if (glm::dot(fn, glm::dvec3(m.normals[m.indices[i + e]])) < 0) ++t.normalsAgainstFaces;
  }
  for (const auto& [edge, count] : directed) {
    auto opp = directed.find({edge.second, edge.first});
    if (count != 1 || opp == directed.end() || opp->second != 1) ++t.badEdges;
  }
  return t;
}

// The four shipped test sets with the lattice cube S each is meshed at (bench_surface's, too).
struct TestSet {
  const char* name;
  float cube;
};
inline constexpr TestSet kTestSets[] = {
    {"fountain.xyz", 1.0f}, {"blob.xyz", 0.3f}, {"explosion.xyz", 0.6f}, {"spray.xyz", 1.0f}};

inline fluid::ParticlePositions loadSet(const std::string& name) {
  fluid::ParticlePositions p;
  const fluid::IoStatus st = fluid::readParticleFile(std::string(FLUIDDEMO_TEST_DATA_DIR) + "/" + name, p);
  if (!st.ok()) throw std::runtime_error(st.error);
  return p;
}

inline fluid::SurfaceInput inputOf(const fluid::ParticlePositions& p) { return {fluid::pointView(p)}; }

// Points made from per-axis coordinate lists (test data written axis by axis), packed as the
// mesher's input layout.
inline std::vector<glm::vec3> packPoints(const std::vector<float>& x, const std::vector<float>& y,
                                         const std::vector<float>& z) {
  std::vector<glm::vec3> out(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = {x[i], y[i], z[i]};
  return out;
}

// Hidden-style case (paper Fig. 4b): a thin hemispherical bowl of radius 8 open at the top, whose
// inner surface has local minima that no particle's downward step reaches. With S = 0.5 one block
// of 64 cubes holds it whole (block seams through its axis would close it off early).
inline fluid::ParticlePositions uprightBowl() {
  fluid::ParticlePositions p;
  for (float th = 0.0f; th < 1.55f; th += 0.09f)
    for (float ph = 0.0f; ph < 6.28f; ph += 0.09f / std::max(0.09f, std::sin(th))) {
      p.push_back({16.0f + 8.0f * std::sin(th) * std::cos(ph), 16.0f + 8.0f * std::sin(th) * std::sin(ph),
                   -16.0f - 8.0f * std::cos(th)});
    }
  return p;
}

// Hidden-style case: the blob set moved 1e5 from the origin, with the origin put beside it so
// float vertices keep their precision.
inline fluid::ParticlePositions blobOffsetBy1e5(fluid::SurfaceParams& params) {
  fluid::ParticlePositions p = loadSet("blob.xyz");
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i].x += 1e5f;
    p[i].y -= 1e5f;
    p[i].z += 1e5f;
  }
  params.cube = 0.3f;
  params.originX = 1e5;
  params.originY = -1e5;
  params.originZ = 1e5;
  return p;
}

// `in` meshed by a fresh extractor with `p` on `route`; a failed extraction throws (the test fails
// with the extractor's message).
inline fluid::SurfaceMesh meshWith(const fluid::SurfaceInput& in, fluid::SurfaceParams p, fluid::SurfaceFieldRoute route) {
  p.fieldRoute = route;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(in, p, m);
  if (!st.ok()) throw std::runtime_error(st.error);
  return m;
}

// One triangle as its three vertices' edge keys, position bits and normal bits, rotated to start
// at its smallest key (the winding kept).
using VertexBits = std::array<std::uint32_t, 8>;  // key (2 words), position (3), normal (3)
using TriangleBits = std::array<VertexBits, 3>;

// The triangles of index range [first, first + count) (all of them by default) with their
// vertex bits, sorted: equal lists mean the same triangles with the same vertex bits, in any order.
inline std::vector<TriangleBits> trianglesWithVertexBits(const fluid::SurfaceMesh& m, std::size_t first = 0,
                                                         std::size_t count = std::numeric_limits<std::size_t>::max()) {
  count = std::min(count, m.indices.size() - first);
  std::vector<TriangleBits> out;
  for (std::size_t i = first; i + 3 <= first + count; i += 3) {
    TriangleBits t;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = m.indices[i + std::size_t(c)];
      std::memcpy(&t[std::size_t(c)][0], &m.edgeKeys[v], 8);
      std::memcpy(&t[std::size_t(c)][2], &m.positions[v], 12);
      std::memcpy(&t[std::size_t(c)][5], &m.normals[v], 12);
    }
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace surface_test
