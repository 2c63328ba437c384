// Exact signed distance to a closed triangle mesh: the reference the depth maps are measured
// against (accuracy table, tests, benchmark). Closest point per triangle (Voronoi-region
// method), a median-split BVH for the nearest search, and the inside test by crossing parity
// of three fixed rays (majority vote, so one ray grazing an edge cannot flip the sign).
#include "fluid/collide/collide.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <numeric>

namespace fluid {

namespace {

glm::vec3 closestOnTriangle(glm::vec3 p, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float denom = d1 - d3;
    return denom != 0.0f ? a + ab * (d1 / denom) : a;
  }
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float denom = d2 - d6;
    return denom != 0.0f ? a + ac * (d2 / denom) : a;
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float denom = (d4 - d3) + (d5 - d6);
    return denom != 0.0f ? b + (c - b) * ((d4 - d3) / denom) : b;
  }
  const float sum = va + vb + vc;
  if (sum == 0.0f) return a;  // degenerate triangle: handled by the edge cases above mostly
  const float v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

float boxDistance2(glm::vec3 p, glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 d = glm::max(glm::max(lo - p, p - hi), glm::vec3(0.0f));
  return glm::dot(d, d);
}

bool rayHitsBox(glm::vec3 o, glm::vec3 inv_dir, glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 t0 = (lo - o) * inv_dir, t1 = (hi - o) * inv_dir;
  const glm::vec3 tmin = glm::min(t0, t1), tmax = glm::max(t0, t1);
  const float enter = std::max({tmin.x, tmin.y, tmin.z, 0.0f});
  const float leave = std::min({tmax.x, tmax.y, tmax.z});
  return enter <= leave;
}

// Ray (o, d) against triangle, counting hits with t > 0 (double precision).
bool rayHitsTriangle(glm::vec3 of, glm::vec3 df, glm::vec3 af, glm::vec3 bf, glm::vec3 cf) {
  const glm::dvec3 o(of), d(df), a(af), b(bf), c(cf);
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 pv = glm::cross(d, e2);
  const double det = glm::dot(e1, pv);
  if (det == 0.0) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 tv = o - a;
  const double u = glm::dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const glm::dvec3 qv = glm::cross(tv, e1);
  const double v = glm::dot(d, qv) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  return glm::dot(e2, qv) * inv > 0.0;
}

// The ray parameter t > 0 of the hit of (o, d) with the triangle, or +inf (double precision).
double rayTriangleT(glm::vec3 of, glm::vec3 df, glm::vec3 af, glm::vec3 bf, glm::vec3 cf) {
  const glm::dvec3 o(of), d(df), a(af), b(bf), c(cf);
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 pv = glm::cross(d, e2);
  const double det = glm::dot(e1, pv);
  constexpr double kMiss = std::numeric_limits<double>::infinity();
  if (det == 0.0) return kMiss;
  const double inv = 1.0 / det;
  const glm::dvec3 tv = o - a;
  const double u = glm::dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) return kMiss;
  const glm::dvec3 qv = glm::cross(tv, e1);
  const double v = glm::dot(d, qv) * inv;
  if (v < 0.0 || u + v > 1.0) return kMiss;
  const double t = glm::dot(e2, qv) * inv;
  return t > 0.0 ? t : kMiss;
}

// Entry parameter of the ray into the box (0 when it starts inside), +inf when it misses.
float rayBoxEntry(glm::vec3 o, glm::vec3 inv_dir, glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 t0 = (lo - o) * inv_dir, t1 = (hi - o) * inv_dir;
  const glm::vec3 tmin = glm::min(t0, t1), tmax = glm::max(t0, t1);
  const float enter = std::max({tmin.x, tmin.y, tmin.z, 0.0f});
  const float leave = std::min({tmax.x, tmax.y, tmax.z});
  return enter <= leave ? enter : std::numeric_limits<float>::infinity();
}

}  // namespace

MeshDistance::MeshDistance(const MeshView& mesh) {
  const std::size_t tris = mesh.indices.size() / 3;
  std::vector<std::uint32_t> order(tris);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<glm::vec3> centroid(tris);
  for (std::size_t t = 0; t < tris; ++t) {
    centroid[t] = (mesh.positions[mesh.indices[3 * t]] + mesh.positions[mesh.indices[3 * t + 1]] +
                   mesh.positions[mesh.indices[3 * t + 2]]) /
                  3.0f;
  }
  // Recursive median split on the longest axis; leaves of up to 4 triangles.
  struct Job {
    std::uint32_t node, first, count;
  };
  if (tris > 0) {
    nodes_.push_back({});
    std::vector<Job> stack{{0, 0, static_cast<std::uint32_t>(tris)}};
    while (!stack.empty()) {
      const Job job = stack.back();
      stack.pop_back();
      glm::vec3 lo(FLT_MAX), hi(-FLT_MAX), clo(FLT_MAX), chi(-FLT_MAX);
      for (std::uint32_t k = job.first; k < job.first + job.count; ++k) {
        const std::uint32_t t = order[k];
        for (int v = 0; v < 3; ++v) {
          lo = glm::min(lo, mesh.positions[mesh.indices[3 * t + v]]);
          hi = glm::max(hi, mesh.positions[mesh.indices[3 * t + v]]);
        }
        clo = glm::min(clo, centroid[t]);
        chi = glm::max(chi, centroid[t]);
      }
      nodes_[job.node].lo = lo;
      nodes_[job.node].hi = hi;
      if (job.count <= 4) {
        nodes_[job.node].first = job.first;
        nodes_[job.node].count = job.count;
        continue;
      }
      const glm::vec3 ext = chi - clo;
      const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
      const std::uint32_t half = job.count / 2;
      std::nth_element(order.begin() + job.first, order.begin() + job.first + half,
                       order.begin() + job.first + job.count,
                       [&](std::uint32_t x, std::uint32_t y) { return centroid[x][axis] < centroid[y][axis]; });
      const std::uint32_t left = static_cast<std::uint32_t>(nodes_.size());
      nodes_.push_back({});
      nodes_.push_back({});
      nodes_[job.node].first = left;  // left child; right child = left + 1
      nodes_[job.node].count = 0;
      stack.push_back({left, job.first, half});
      stack.push_back({left + 1, job.first + half, job.count - half});
    }
  }
  a_.resize(tris);
  b_.resize(tris);
  c_.resize(tris);
  for (std::size_t k = 0; k < tris; ++k) {
    const std::uint32_t t = order[k];
    a_[k] = mesh.positions[mesh.indices[3 * t]];
    b_[k] = mesh.positions[mesh.indices[3 * t + 1]];
    c_[k] = mesh.positions[mesh.indices[3 * t + 2]];
  }
}

float MeshDistance::closest(glm::vec3 p, glm::vec3& best_point, float best) const {
  if (nodes_.empty()) return best;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (boxDistance2(p, node.lo, node.hi) >= best) continue;
    if (node.count > 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
        const glm::vec3 q = closestOnTriangle(p, a_[k], b_[k], c_[k]);
        const float d2 = glm::dot(p - q, p - q);
        if (d2 < best) {
          best = d2;
          best_point = q;
        }
      }
      continue;
    }
    // Visit the nearer child first.
    const std::uint32_t l = node.first, r = node.first + 1;
    const float dl = boxDistance2(p, nodes_[l].lo, nodes_[l].hi), dr = boxDistance2(p, nodes_[r].lo, nodes_[r].hi);
    if (dl < dr) {
      stack[top++] = r;
      stack[top++] = l;
    } else {
      stack[top++] = l;
      stack[top++] = r;
    }
  }
  return best;
}

int MeshDistance::crossings(glm::vec3 o, glm::vec3 d) const {
  if (nodes_.empty()) return 0;
  const glm::vec3 inv = 1.0f / d;
  int hits = 0;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!rayHitsBox(o, inv, node.lo, node.hi)) continue;
    if (node.count > 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k)
        hits += rayHitsTriangle(o, d, a_[k], b_[k], c_[k]);
      continue;
    }
    stack[top++] = node.first;
    stack[top++] = node.first + 1;
  }
  return hits;
}

float MeshDistance::firstHit(glm::vec3 origin, glm::vec3 dir) const {
  double best = std::numeric_limits<double>::infinity();
  if (nodes_.empty() || !(glm::dot(dir, dir) > 0.0f)) return static_cast<float>(best);
  const glm::vec3 inv = 1.0f / dir;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!(rayBoxEntry(origin, inv, node.lo, node.hi) <= best)) continue;
    if (node.count > 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k)
        best = std::min(best, rayTriangleT(origin, dir, a_[k], b_[k], c_[k]));
      continue;
    }
    stack[top++] = node.first;
    stack[top++] = node.first + 1;
  }
  return static_cast<float>(best);
}

bool MeshDistance::inside(glm::vec3 p) const {
  // Directions with no simple rational relation to mesh axes.
  static constexpr glm::vec3 kDirs[3] = {{0.5773503f, 0.5773503f, 0.5773503f},
                                         {-0.2672612f, 0.8017837f, -0.5345225f},
                                         {0.7071068f, -0.3015113f, 0.6396021f}};
  int votes = 0;
  for (const glm::vec3& d : kDirs) votes += crossings(p, d) & 1;
  return votes >= 2;
}

ColliderSample MeshDistance::sample(glm::vec3 p) const {
  ColliderSample s{FLT_MAX, {0.0f, 0.0f, 1.0f}, false};
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) || nodes_.empty()) return s;
  glm::vec3 q(0.0f);
  const float d = std::sqrt(closest(p, q));
  const bool in = inside(p);
  s.valid = true;
  s.distance = in ? -d : d;
  if (d > 0.0f) s.normal = (in ? q - p : p - q) / d;  // outward direction of the distance gradient
  return s;
}

float MeshDistance::unsignedDistance(glm::vec3 p, float limit) const {
  glm::vec3 q(0.0f);
  if (!(limit > 0.0f)) return 0.0f;
  const float limit2 = limit < 1e18f ? limit * limit : FLT_MAX;
  return std::sqrt(std::min(closest(p, q, limit2), limit2));
}

ColliderSample MeshDistance::sampleBruteForce(glm::vec3 p) const {
  ColliderSample s{FLT_MAX, {0.0f, 0.0f, 1.0f}, false};
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) || a_.empty()) return s;
  float best = FLT_MAX;
  glm::vec3 best_point(0.0f);
  for (std::size_t k = 0; k < a_.size(); ++k) {
    const glm::vec3 q = closestOnTriangle(p, a_[k], b_[k], c_[k]);
    const float d2 = glm::dot(p - q, p - q);
    if (d2 < best) {
      best = d2;
      best_point = q;
    }
  }
  int hits = 0;
  const glm::vec3 dir{0.5773503f, 0.5773503f, 0.5773503f};
  for (std::size_t k = 0; k < a_.size(); ++k) hits += rayHitsTriangle(p, dir, a_[k], b_[k], c_[k]);
  const float d = std::sqrt(best);
  const bool in = (hits & 1) != 0;
  s.valid = true;
  s.distance = in ? -d : d;
  if (d > 0.0f) s.normal = (in ? best_point - p : p - best_point) / d;
  return s;
}

void MeshDistance::query(std::span<const glm::vec3> points, std::span<ColliderSample> out) const {
  for (std::size_t k = 0; k < points.size(); ++k) out[k] = sample(points[k]);
}

}  // namespace fluid
