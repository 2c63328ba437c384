#pragma once
// The fountain assembly's dimensions and the collision shape the sprite particles bounce on.
// The same numbers drive scripts/generate_content.py (basin.obj, statue.obj): keep them in sync.
// Units: metres, y up, fountain centred on the origin.

#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <span>

namespace game {

struct FountainGeometry {
  float basin_outer_radius = 3.2f;
  float basin_inner_radius = 2.9f;
  float basin_wall_top = 0.7f;
  float basin_floor = 0.2f;
  // Statue (a column with a dish and a spire), as capped cylinders.
  float plinth_radius = 0.6f;
  float plinth_top = 0.4f;
  float column_radius = 0.45f;  // plinth to dish
  float column_top = 1.42f;
  float dish_radius = 1.05f;
  float dish_bottom = 1.32f;
  float dish_rim_top = 1.62f;
  float dish_inner_radius = 0.92f;
  float dish_floor = 1.55f;
  float spire_radius = 0.2f;
  float spire_top = 2.45f;
  glm::vec3 nozzle{0.0f, 2.5f, 0.0f};  // where the jet leaves the spire
};

// Signed distance to ground (y = 0 half-space) ∪ basin ∪ statue. Exact inside each primitive,
// a bound across the CSG joins; normals are the deciding primitive's analytic gradient.
// The shape is static: collider space = world space.
class FountainShape final : public fluid::SignedDistanceShape {
 public:
  FountainShape() = default;
  explicit FountainShape(const FountainGeometry& geometry) : g_(geometry) {}
  void query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const override;
  float distance(glm::vec3 p) const;
  const FountainGeometry& geometry() const { return g_; }
  // Testing aid: answer queries with the scalar code even where the CPU has AVX2 (the eight-wide
  // path gives bit-identical samples).
  void setPortable(bool portable) { portable_ = portable; }

 private:
  FountainGeometry g_;
  bool portable_ = false;
};

}  // namespace game
