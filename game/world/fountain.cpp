#include "game/world/fountain.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace game {
namespace {

// Signed distance with its gradient (unit length almost everywhere).
struct Field {
  float d;
  glm::vec3 g;
};

// Capped vertical cylinder around the y axis, y in [bottom, top]: exact distance and gradient.
Field cappedCylinder(glm::vec3 p, float radius, float bottom, float top) {
  const float half = 0.5f * (top - bottom);
  const float centre = bottom + half;
  const float rho = std::sqrt(p.x * p.x + p.z * p.z);
  const glm::vec3 radial = rho > 1e-7f ? glm::vec3(p.x / rho, 0.0f, p.z / rho) : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 axial(0.0f, p.y >= centre ? 1.0f : -1.0f, 0.0f);
  const float qr = rho - radius;                   // > 0 outside the side
  const float qy = std::abs(p.y - centre) - half;  // > 0 above the top / below the bottom
  if (qr <= 0.0f && qy <= 0.0f) {
    // Inside: the nearest face is the one with the larger (less negative) offset.
    return qr > qy ? Field{qr, radial} : Field{qy, axial};
  }
  const float er = std::max(qr, 0.0f), ey = std::max(qy, 0.0f);
  const float d = std::sqrt(er * er + ey * ey);
  return {d, (radial * er + axial * ey) / d};
}

Field unite(const Field& a, const Field& b) { return a.d <= b.d ? a : b; }
Field subtract(const Field& a, const Field& b) { return a.d >= -b.d ? a : Field{-b.d, -b.g}; }

Field evaluate(const FountainGeometry& g, glm::vec3 p) {
  const Field ground{p.y, {0.0f, 1.0f, 0.0f}};
  // Basin: solid ring cylinder minus its water volume above the floor.
  const Field basin = subtract(cappedCylinder(p, g.basin_outer_radius, -1.0f, g.basin_wall_top),
                               cappedCylinder(p, g.basin_inner_radius, g.basin_floor, g.basin_wall_top + 10.0f));
  const Field column = unite(cappedCylinder(p, g.column_radius, -1.0f, g.column_top),
                             cappedCylinder(p, g.plinth_radius, -1.0f, g.plinth_top));
  const Field dish = subtract(cappedCylinder(p, g.dish_radius, g.dish_bottom, g.dish_rim_top),
                              cappedCylinder(p, g.dish_inner_radius, g.dish_floor, g.dish_rim_top + 10.0f));
  const Field spire = cappedCylinder(p, g.spire_radius, g.dish_bottom, g.spire_top);
  return unite(unite(ground, basin), unite(column, unite(dish, spire)));
}

}  // namespace

float FountainShape::distance(glm::vec3 p) const { return evaluate(g_, p).d; }

void FountainShape::query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const {
  assert(local_points.size() == out.size());
  for (std::size_t i = 0; i < local_points.size(); ++i) {
    const Field field = evaluate(g_, local_points[i]);
    out[i].distance = field.d;
    // The gradient of a CSG union/difference is the gradient of the primitive that decides
    // the value; exact inside each primitive, a direction to the nearest face across joins.
    out[i].normal = field.g;
    out[i].valid = std::isfinite(field.d);
  }
}

}  // namespace game
