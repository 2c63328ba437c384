#pragma once
// Analytic collider shapes for fluid/sph, behind the shared fluid::SignedDistanceShape contract
// (fluid/core/collider.hpp). All work in collider space; place them with a ColliderPose.
// Distances are exact Euclidean signed distances (negative inside the solid), normals point out
// of the solid. Thread-safe: queries only read the shape.

#include "fluid/core/collider.hpp"

namespace fluid {

// Solid half-space { x : dot(normal, x) < offset }; the fluid lives where dot(normal, x) > offset.
// normal is normalised on construction (a zero normal becomes +y).
class PlaneShape final : public SignedDistanceShape {
 public:
  PlaneShape(glm::vec3 normal, float offset);
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;
  glm::vec3 normal() const { return normal_; }
  float offset() const { return offset_; }

 private:
  glm::vec3 normal_;
  float offset_;
};

// Axis-aligned box centred at the collider-space origin with half extents > 0.
// inverted == false: a solid box. inverted == true: a closed container, the solid is everything
// outside the box and the fluid lives inside (distance > 0 inside the box).
class BoxShape final : public SignedDistanceShape {
 public:
  BoxShape(glm::vec3 half_extents, bool inverted = false);
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;
  glm::vec3 halfExtents() const { return half_; }
  bool inverted() const { return inverted_; }

 private:
  glm::vec3 half_;
  bool inverted_;
};

// Sphere of radius > 0 centred at the collider-space origin; inverted == true makes a spherical
// container (solid outside).
class SphereShape final : public SignedDistanceShape {
 public:
  SphereShape(float radius, bool inverted = false);
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;

 private:
  float radius_;
  bool inverted_;
};

}  // namespace fluid
