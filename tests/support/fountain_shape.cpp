#include "tests/support/fountain_shape.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace fountainref {
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
  const float qr = rho - c.radius;                          // > 0 outside the side
  const float qy = std::abs(y - (c.bottom + half)) - half;  // > 0 above the top / below the bottom
  if (qr <= 0.0f && qy <= 0.0f) return std::max(qr, qy);    // inside: the nearest face
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

Cylinders cylindersOf(const game::FountainGeometry& g) {
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

// The sample for a pick: the gradient of a CSG union/difference is the gradient of the primitive
// that decides the value; exact inside each primitive, a direction to the nearest face across joins.
fluid::ColliderSample finish(const Cylinders& s, glm::vec3 p, float rho, const Pick& pick) {
  fluid::ColliderSample out;
  out.distance = pick.d;
  const glm::vec3 g = pick.primitive < 0 ? glm::vec3(0.0f, 1.0f, 0.0f) : cylinderGradient(rho, p, s.c[pick.primitive]);
  out.normal = pick.negated ? -g : g;
  out.valid = std::isfinite(pick.d);
  return out;
}

fluid::ColliderSample sampleAt(const Cylinders& s, glm::vec3 p) {
  const float rho = std::sqrt(p.x * p.x + p.z * p.z);
  return finish(s, p, rho, evaluate(s, rho, p.y));
}

#if defined(__x86_64__) && defined(__GNUC__)
#define FOUNTAIN_AVX2 1
// evaluate() for eight points at once where the CPU has AVX2 (checked at run time): every
// primitive is computed for every lane and the branches become selects, in the same IEEE
// operations (no FMA: the target does not enable it) and with the same tie rules, so the picks
// and distances are bit-identical to the scalar code; the gradient of the picked primitive is
// then computed per point by the scalar code (finish).
#define FOUNTAIN_TARGET __attribute__((target("avx2")))
struct PickV {
  __m256 d, primitive, negated;  // primitive as a float (-1 .. 6), negated as an all-ones mask
};
FOUNTAIN_TARGET inline PickV uniteV(const PickV& a, const PickV& b) {
  const __m256 keep_a = _mm256_cmp_ps(a.d, b.d, _CMP_LE_OQ);  // a.d <= b.d ? a : b
  return {_mm256_blendv_ps(b.d, a.d, keep_a), _mm256_blendv_ps(b.primitive, a.primitive, keep_a),
          _mm256_blendv_ps(b.negated, a.negated, keep_a)};
}
FOUNTAIN_TARGET inline PickV subtractV(const PickV& a, const PickV& b) {
  const __m256 minus_b = _mm256_xor_ps(b.d, _mm256_set1_ps(-0.0f));
  const __m256 keep_a = _mm256_cmp_ps(a.d, minus_b, _CMP_GE_OQ);  // a.d >= -b.d ? a : {-b.d, b, negated}
  const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  return {_mm256_blendv_ps(minus_b, a.d, keep_a), _mm256_blendv_ps(b.primitive, a.primitive, keep_a),
          _mm256_blendv_ps(all, a.negated, keep_a)};
}
// cylinderDistance with its four cases as selects (same precedence; NaN ends in the sqrt case).
FOUNTAIN_TARGET inline __m256 cylinderDistanceV(__m256 rho, __m256 y, const Cylinder& c) {
  const float half = 0.5f * (c.top - c.bottom);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 qr = _mm256_sub_ps(rho, _mm256_set1_ps(c.radius));
  const __m256 dy = _mm256_sub_ps(y, _mm256_set1_ps(c.bottom + half));
  const __m256 qy = _mm256_sub_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), dy), _mm256_set1_ps(half));
  const __m256 in_r = _mm256_cmp_ps(qr, zero, _CMP_LE_OQ), in_y = _mm256_cmp_ps(qy, zero, _CMP_LE_OQ);
  __m256 d = _mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(qr, qr), _mm256_mul_ps(qy, qy)));
  d = _mm256_blendv_ps(d, qy, in_r);
  d = _mm256_blendv_ps(d, qr, in_y);
  const __m256 max_ry = _mm256_blendv_ps(qr, qy, _mm256_cmp_ps(qr, qy, _CMP_LT_OQ));  // std::max(qr, qy)
  return _mm256_blendv_ps(d, max_ry, _mm256_and_ps(in_r, in_y));
}
FOUNTAIN_TARGET inline PickV primitiveV(__m256 rho, __m256 y, const Cylinders& s, int k) {
  return PickV{cylinderDistanceV(rho, y, s.c[k]), _mm256_set1_ps(static_cast<float>(k)), _mm256_setzero_ps()};
}
FOUNTAIN_TARGET void queryAvx2(const Cylinders& s, const glm::vec3* points, std::size_t count,
                               fluid::ColliderSample* out) {
  for (std::size_t b = 0; b < count; b += 8) {
    const std::size_t lanes = std::min<std::size_t>(8, count - b);
    alignas(32) float xs[8], ys[8], zs[8];
    for (std::size_t l = 0; l < 8; ++l) {
      const glm::vec3 p = points[b + (l < lanes ? l : 0)];  // spare lanes repeat a valid point
      xs[l] = p.x;
      ys[l] = p.y;
      zs[l] = p.z;
    }
    const __m256 x = _mm256_load_ps(xs), y = _mm256_load_ps(ys), z = _mm256_load_ps(zs);
    const __m256 rho = _mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(z, z)));
    const __m256 none = _mm256_setzero_ps();
    const PickV near = uniteV(PickV{y, _mm256_set1_ps(-1.0f), none},
                              subtractV(primitiveV(rho, y, s, kBasinOuter), primitiveV(rho, y, s, kBasinInner)));
    const PickV column = uniteV(primitiveV(rho, y, s, kColumn), primitiveV(rho, y, s, kPlinth));
    const PickV dish = subtractV(primitiveV(rho, y, s, kDish), primitiveV(rho, y, s, kDishInner));
    const PickV all = uniteV(near, uniteV(column, uniteV(dish, primitiveV(rho, y, s, kSpire))));
    // evaluate()'s shortcut returns `near` when rho - statue_radius > near.d: the same selection.
    const __m256 shortcut = _mm256_cmp_ps(_mm256_sub_ps(rho, _mm256_set1_ps(s.statue_radius)), near.d, _CMP_GT_OQ);
    alignas(32) float d[8], pr[8], r[8];
    _mm256_store_ps(d, _mm256_blendv_ps(all.d, near.d, shortcut));
    _mm256_store_ps(pr, _mm256_blendv_ps(all.primitive, near.primitive, shortcut));
    const int negated = _mm256_movemask_ps(_mm256_blendv_ps(all.negated, near.negated, shortcut));
    _mm256_store_ps(r, rho);
    for (std::size_t l = 0; l < lanes; ++l)
      out[b + l] = finish(s, points[b + l], r[l], Pick{d[l], static_cast<int>(pr[l]), ((negated >> l) & 1) != 0});
  }
}
#undef FOUNTAIN_TARGET
#endif

}  // namespace

float FountainShape::distance(glm::vec3 p) const {
  return evaluate(cylindersOf(g_), std::sqrt(p.x * p.x + p.z * p.z), p.y).d;  // no gradient needed
}

void FountainShape::query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const {
  assert(local_points.size() == out.size());
  const Cylinders s = cylindersOf(g_);
#if defined(FOUNTAIN_AVX2)
  if (!portable_ && __builtin_cpu_supports("avx2")) {
    queryAvx2(s, local_points.data(), local_points.size(), out.data());
    return;
  }
#endif
  for (std::size_t i = 0; i < local_points.size(); ++i) out[i] = sampleAt(s, local_points[i]);
}

}  // namespace fountainref
