#pragma once
// The fountain as analytic CSG (ground half-space ∪ basin ∪ statue, capped cylinders of
// game::FountainGeometry): the reference the baked depth-map colliders of content/colliders are
// measured against (tests/collide, bench_collide_fountain, the soak checks' tests). The game
// itself collides with the baked colliders (game/world/fountain.hpp, loadLevelColliders).

#include "fluid/core/collider.hpp"
#include "game/world/fountain.hpp"

#include <span>

namespace fountainref {

// Signed distance to ground (y = 0 half-space) ∪ basin ∪ statue. Exact inside each primitive,
// a bound across the CSG joins (1-Lipschitz); normals are the deciding primitive's analytic
// gradient. The shape is static: collider space = world space.
class FountainShape final : public fluid::SignedDistanceShape {
 public:
  FountainShape() = default;
  explicit FountainShape(const game::FountainGeometry& geometry) : g_(geometry) {}
  void query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const override;
  float distance(glm::vec3 p) const;
  const game::FountainGeometry& geometry() const { return g_; }
  // Testing aid: answer queries with the scalar code even where the CPU has AVX2 (the eight-wide
  // path gives bit-identical samples).
  void setPortable(bool portable) { portable_ = portable; }

 private:
  game::FountainGeometry g_;
  bool portable_ = false;
};

}  // namespace fountainref
