#include "game/world/fountain.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace game {
namespace {

// Every primitive is a capped cylinder around the y axis (plus the ground plane), so a query
// first computes the signed distances alone, with the point's distance from the axis shared by
// all of them, and then the gradient of the one primitive that decides the CSG value.
struct Cylinder {
  float radius, bottom, top;
};

// Signed distance to a capped vertical cylinder, exact. Outside the side (rho > radius) it is at
// least rho - radius.
float cylinderDistance(float rho, float y, const Cylinder& c) {
  const float half = 0.5f * (c.top - c.bottom);
  const float qr = rho - c.radius;                        // > 0 outside the side
  const float qy = std::abs(y - (c.bottom + half)) - half;  // > 0 above the top / below the bottom
  if (qr <= 0.0f && qy <= 0.0f) return std::max(qr, qy);  // inside: the nearest face
  // Outside: beside the side or above/below a cap the distance is the one positive offset;
  // only off a rim edge does it need the square root.
  if (qy <= 0.0f) return qr;
  if (qr <= 0.0f) return qy;
  return std::sqrt(qr * qr + qy * qy);
}

// Gradient of cylinderDistance (unit length; the nearest face's normal inside).
glm::vec3 cylinderGradient(float rho, glm::vec3 p, const Cylinder& c) {
  const float half = 0.5f * (c.top - c.bottom);
  const float centre = c.bottom + half;
  const glm::vec3 radial = rho > 1e-7f ? glm::vec3(p.x / rho, 0.0f, p.z / rho) : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 axial(0.0f, p.y >= centre ? 1.0f : -1.0f, 0.0f);
  const float qr = rho - c.radius;
  const float qy = std::abs(p.y - centre) - half;
  if (qr <= 0.0f && qy <= 0.0f) return qr > qy ? radial : axial;
  if (qy <= 0.0f) return radial;
  if (qr <= 0.0f) return axial;
  return (radial * qr + axial * qy) / std::sqrt(qr * qr + qy * qy);
}

// The CSG value so far: distance, deciding primitive (-1 = ground) and whether its gradient is
// negated (the inside of a subtracted volume).
struct Pick {
  float d;
  int primitive;
  bool negated;
};

Pick unite(const Pick& a, const Pick& b) { return a.d <= b.d ? a : b; }
Pick subtract(const Pick& a, const Pick& b) { return a.d >= -b.d ? a : Pick{-b.d, b.primitive, true}; }

// Primitives, in the order evaluate() indexes them.
enum : int { kBasinOuter, kBasinInner, kColumn, kPlinth, kDish, kDishInner, kSpire, kPrimitives };

struct Cylinders {
  Cylinder c[kPrimitives];
  float statue_radius;  // the statue lies within this distance of the axis
};

Cylinders cylindersOf(const FountainGeometry& g) {
  Cylinders out{{{g.basin_outer_radius, -1.0f, g.basin_wall_top},
                 {g.basin_inner_radius, g.basin_floor, g.basin_wall_top + 10.0f},  // the water volume
                 {g.column_radius, -1.0f, g.column_top},
                 {g.plinth_radius, -1.0f, g.plinth_top},
                 {g.dish_radius, g.dish_bottom, g.dish_rim_top},
                 {g.dish_inner_radius, g.dish_floor, g.dish_rim_top + 10.0f},
                 {g.spire_radius, g.dish_bottom, g.spire_top}},
                0.0f};
  out.statue_radius = std::max({g.column_radius, g.plinth_radius, g.dish_radius, g.spire_radius});
  return out;
}

// Ground (y = 0 half-space) ∪ (basin ring − its water volume) ∪ column ∪ plinth ∪ (dish − its
// bowl) ∪ spire.
Pick evaluate(const Cylinders& s, float rho, float y) {
  auto prim = [&](int k) { return Pick{cylinderDistance(rho, y, s.c[k]), k, false}; };
  const Pick near = unite(Pick{y, -1, false}, subtract(prim(kBasinOuter), prim(kBasinInner)));
  // Every statue primitive is at least rho - statue_radius away (a difference is never nearer
  // than its first operand): when that is already farther than the ground and basin, the union
  // would not pick it (same result, fewer evaluations).
  if (rho - s.statue_radius > near.d) return near;
  const Pick column = unite(prim(kColumn), prim(kPlinth));
  const Pick dish = subtract(prim(kDish), prim(kDishInner));
  return unite(near, unite(column, unite(dish, prim(kSpire))));
}

fluid::ColliderSample sampleAt(const Cylinders& s, glm::vec3 p) {
  const float rho = std::sqrt(p.x * p.x + p.z * p.z);
  const Pick pick = evaluate(s, rho, p.y);
  fluid::ColliderSample out;
  out.distance = pick.d;
  // The gradient of a CSG union/difference is the gradient of the primitive that decides the
  // value; exact inside each primitive, a direction to the nearest face across joins.
  const glm::vec3 g = pick.primitive < 0 ? glm::vec3(0.0f, 1.0f, 0.0f) : cylinderGradient(rho, p, s.c[pick.primitive]);
  out.normal = pick.negated ? -g : g;
  out.valid = std::isfinite(pick.d);
  return out;
}

}  // namespace

float FountainShape::distance(glm::vec3 p) const {
  return evaluate(cylindersOf(g_), std::sqrt(p.x * p.x + p.z * p.z), p.y).d;  // no gradient needed
}

void FountainShape::query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const {
  assert(local_points.size() == out.size());
  const Cylinders s = cylindersOf(g_);
  for (std::size_t i = 0; i < local_points.size(); ++i) out[i] = sampleAt(s, local_points[i]);
}

}  // namespace game
