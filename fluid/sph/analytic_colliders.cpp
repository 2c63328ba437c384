#include "fluid/sph/analytic_colliders.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace fluid {

PlaneShape::PlaneShape(glm::vec3 normal, float offset) : normal_(0.0f, 1.0f, 0.0f), offset_(offset) {
  const float len = glm::length(normal);
  if (len > 0.0f && std::isfinite(len)) normal_ = normal / len;
}

void PlaneShape::query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const {
  assert(out.size() == local_points.size());
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    out[i].distance = glm::dot(normal_, local_points[i]) - offset_;
    out[i].normal = normal_;
    out[i].valid = true;
  }
}

BoxShape::BoxShape(glm::vec3 half_extents, bool inverted)
    : half_(glm::max(half_extents, glm::vec3(1e-6f))), inverted_(inverted) {}

namespace {

// Signed distance of a solid axis-aligned box (Quilez' box SDF), with the outward normal.
ColliderSample boxSample(glm::vec3 p, glm::vec3 half) {
  const glm::vec3 q = glm::abs(p) - half;
  const glm::vec3 sign(p.x < 0.0f ? -1.0f : 1.0f, p.y < 0.0f ? -1.0f : 1.0f, p.z < 0.0f ? -1.0f : 1.0f);
  ColliderSample s;
  s.valid = true;
  const glm::vec3 outside = glm::max(q, glm::vec3(0.0f));
  const float out_len = glm::length(outside);
  if (out_len > 0.0f) {
    s.distance = out_len;
    s.normal = sign * outside / out_len;
    return s;
  }
  // Inside: the nearest face is the axis with the largest (least negative) q.
  int axis = 0;
  if (q.y > q[axis]) axis = 1;
  if (q.z > q[axis]) axis = 2;
  s.distance = q[axis];
  s.normal = glm::vec3(0.0f);
  s.normal[axis] = sign[axis];
  return s;
}

}  // namespace

void BoxShape::query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const {
  assert(out.size() == local_points.size());
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    ColliderSample s = boxSample(local_points[i], half_);
    if (inverted_) {
      s.distance = -s.distance;
      s.normal = -s.normal;
    }
    out[i] = s;
  }
}

SphereShape::SphereShape(float radius, bool inverted) : radius_(std::max(radius, 1e-6f)), inverted_(inverted) {}

void SphereShape::query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const {
  assert(out.size() == local_points.size());
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    const glm::vec3 p = local_points[i];
    const float len = glm::length(p);
    ColliderSample s;
    s.valid = true;
    s.distance = len - radius_;
    s.normal = len > 1e-12f ? p / len : glm::vec3(0.0f, 1.0f, 0.0f);
    if (inverted_) {
      s.distance = -s.distance;
      s.normal = -s.normal;
    }
    out[i] = s;
  }
}

}  // namespace fluid
