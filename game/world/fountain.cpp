#include "game/world/fountain.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace game {
namespace {

// Capped vertical cylinder around the y axis, y in [bottom, top].
float cappedCylinder(glm::vec3 p, float radius, float bottom, float top) {
  const float half = 0.5f * (top - bottom);
  const glm::vec2 d(std::sqrt(p.x * p.x + p.z * p.z) - radius, std::abs(p.y - (bottom + half)) - half);
  return std::min(std::max(d.x, d.y), 0.0f) + glm::length(glm::max(d, glm::vec2(0.0f)));
}

}  // namespace

float FountainShape::distance(glm::vec3 p) const {
  const float ground = p.y;
  // Basin: solid ring cylinder minus its water volume above the floor.
  const float basin_solid = cappedCylinder(p, g_.basin_outer_radius, -1.0f, g_.basin_wall_top);
  const float basin_hole = cappedCylinder(p, g_.basin_inner_radius, g_.basin_floor, g_.basin_wall_top + 10.0f);
  const float basin = std::max(basin_solid, -basin_hole);
  const float column = std::min(cappedCylinder(p, g_.column_radius, -1.0f, g_.column_top),
                                cappedCylinder(p, g_.plinth_radius, -1.0f, g_.plinth_top));
  const float dish = std::max(cappedCylinder(p, g_.dish_radius, g_.dish_bottom, g_.dish_rim_top),
                              -cappedCylinder(p, g_.dish_inner_radius, g_.dish_floor, g_.dish_rim_top + 10.0f));
  const float spire = cappedCylinder(p, g_.spire_radius, g_.dish_bottom, g_.spire_top);
  return std::min({ground, basin, column, dish, spire});
}

void FountainShape::query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const {
  assert(local_points.size() == out.size());
  constexpr float h = 1e-3f;
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    const glm::vec3 p = local_points[i];
    fluid::ColliderSample& sample = out[i];
    sample.distance = distance(p);
    sample.valid = std::isfinite(sample.distance);
    // The normal matters only near the surface (the reaction uses it when the distance is
    // negative); far away the field is smooth and the same differences are still correct.
    const glm::vec3 gradient(distance(p + glm::vec3(h, 0, 0)) - distance(p - glm::vec3(h, 0, 0)),
                             distance(p + glm::vec3(0, h, 0)) - distance(p - glm::vec3(0, h, 0)),
                             distance(p + glm::vec3(0, 0, h)) - distance(p - glm::vec3(0, 0, h)));
    const float length = glm::length(gradient);
    sample.normal = length > 1e-12f ? gradient / length : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

}  // namespace game
