#pragma once
// Internal to fluid/sph: colliders as a continuous SPH boundary. The collider side of a
// particle's kernel support is treated as a filled half-space at the sampled signed distance
// (Koschier & Bender 2017, "Density maps for improved SPH boundary handling", with the collider
// locally approximated by its tangent plane); the volume V and its gradient enter the density and
// pressure terms like Akinci et al. 2012 boundary particles.
#include "fluid/sph/step_context.hpp"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <span>
#include <vector>

namespace fluid::sph_step {

constexpr int kWallTable = 1024;
// Boundary pressure mirroring: the wall takes the particle's pressure (p_b = p_i, rho_b = rho_i),
// so its term in the symmetric pressure force has weight 2.
constexpr float kMirror = 2.0f;

// (Re)builds the kernel, the particle mass and the calibrated wall tables when the particle
// radius or the rest density changed (once per world otherwise).
void ensureStepTables(SphWorld& world);

// Linear lookup of a wall table (V or A) at signed distance s in [-H, H].
inline float lookupWallTable(const std::vector<float>& table, float s, float support) {
  const float t = (s + support) / (2.0f * support) * kWallTable;
  if (!(t > 0.0f)) return table.front();
  if (t >= static_cast<float>(kWallTable)) return table.back();
  const int i = static_cast<int>(t);
  const float f = t - static_cast<float>(i);
  return table[i] + f * (table[i + 1] - table[i]);
}

// Whether a sample can give a boundary volume: valid and closer than the support H (beyond it
// the collider misses the particle's kernel support; V_c = 0 and grad V_c = 0).
inline bool withinSupport(const ColliderSample& sample, float support) {
  return sample.valid && !(sample.distance >= support);
}

// 1 - V_c: the part of a particle's support that collider c leaves to fluid (V_c = its boundary
// volume from the wall table at that distance; 1 when c does not push back or is out of reach).
// Several colliders combine by the union rule of sampleBoundary: the product over colliders.
// The planar (tangent-plane) volume of any collider; the step itself uses colliderVolume, which
// is exact for solid boxes.
inline float openFraction(const SphScratch& scratch, const SphCollider& collider, const ColliderSample& sample) {
  const float support = scratch.kernel.support;
  if (!collider.boundary_pressure || !withinSupport(sample, support)) return 1.0f;
  return 1.0f - lookupWallTable(scratch.wall_volume, sample.distance + scratch.wall_shift, support);
}

// Boundary volume V_c of one collider at a particle and its gradient grad V_c = -area * normal
// (world space; normal points out of the solid).
struct BoundaryVolume {
  float volume = 0.0f;
  float area = 0.0f;
  glm::vec3 normal{0.0f, 0.0f, 1.0f};
};

// Side of the octant table: (kOctantCells + 1)^3 nodes over [-H, H]^3 (node spacing H / 24 = r / 6).
constexpr int kOctantCells = 48;

// Exact V and grad V of a solid box at world point x (`half`: its half extents less the wall
// calibration shift, scaled like the wall tables; boundary.cpp says why a box needs this).
BoundaryVolume boxBoundaryVolume(const SphScratch& scratch, glm::vec3 half, const ColliderPose& pose, glm::vec3 x);

// V_c and grad V_c of collider c at particle position x with its step-start sample: exact for a
// solid box at least H/2 thick (scratch.collider_box[c].w != 0), the calibrated tangent-plane
// wall otherwise.
inline BoundaryVolume colliderVolume(const SphScratch& scratch, const SphCollider& collider, std::size_t c,
                                     const ColliderSample& sample, glm::vec3 x) {
  const float support = scratch.kernel.support;
  if (!collider.boundary_pressure || !withinSupport(sample, support)) return {};
  const glm::vec4 box = scratch.collider_box[c];
  if (box.w != 0.0f) return boxBoundaryVolume(scratch, glm::vec3(box), collider.pose, x);
  const float s = sample.distance + scratch.wall_shift;
  return {lookupWallTable(scratch.wall_volume, s, support), lookupWallTable(scratch.wall_area, s, support),
          sample.normal};  // grad V_c = -A(s) n
}

// Collider c's share of grad V at a particle (the union rule of sampleBoundary):
// grad V_c prod_{c' != c} (1 - V_c'), with product = prod_c (1 - V_c).
inline glm::vec3 boundaryShare(const BoundaryVolume& term, float product) {
  const float others = product / std::max(1.0f - term.volume, 1e-6f);
  return (-term.area * others) * term.normal;
}

// Queries one collider at chosen particles, in chunks: which[0 .. q) are particle indices whose
// world points are transformed to collider space, queried as one batch and written (normals back in
// world space, a non-finite distance marked invalid) to out[which[k]]. At most kGrain points.
struct ColliderQuery {
  const SphCollider& collider;
  ColliderPose pose;
  glm::quat inverse_rotation;
  bool rotated;
  bool identity;  // no rotation and a translation of +0 bits: x - translation == x, bit for bit
  ColliderQuery(const SphCollider& c, const ColliderPose& p)
      : collider(c),
        pose(p),
        inverse_rotation(glm::inverse(p.rotation)),
        rotated(!(p.rotation.w == 1.0f && p.rotation.x == 0.0f && p.rotation.y == 0.0f && p.rotation.z == 0.0f)),
        identity(!rotated && isPositiveZero(p.translation)) {}
  // The sample at one world point (the spray's drops, queried one by one).
  ColliderSample at(glm::vec3 point) const {
    const glm::vec3 local = toLocal(point);
    ColliderSample sample;
    collider.shape->query(std::span<const glm::vec3>(&local, 1), std::span<ColliderSample>(&sample, 1));
    finishSample(sample);
    return sample;
  }
  // `which` ascends (the callers list particles in index order).
  void run(const std::vector<glm::vec3>& points, const std::uint32_t* which, std::uint32_t q,
           std::vector<ColliderSample>& out) const {
    if (q == 0) return;
    if (which[q - 1] - which[0] == q - 1) {
      // A run of consecutive particles (every particle of the chunk, the usual case): the shape
      // writes straight into `out`, and a still collider at the origin (a level baked in world
      // coordinates) reads the positions in place. The same samples, without the copies.
      const std::uint32_t first = which[0];
      ColliderSample* o = out.data() + first;
      if (identity) {
        collider.shape->query(std::span<const glm::vec3>(points.data() + first, q), std::span<ColliderSample>(o, q));
      } else {
        glm::vec3 local[kGrain];
        for (std::uint32_t k = 0; k < q; ++k) local[k] = toLocal(points[first + k]);
        collider.shape->query(std::span<const glm::vec3>(local, q), std::span<ColliderSample>(o, q));
      }
      for (std::uint32_t k = 0; k < q; ++k) finishSample(o[k]);
      return;
    }
    glm::vec3 local[kGrain];
    ColliderSample samples[kGrain];
    for (std::uint32_t k = 0; k < q; ++k) local[k] = toLocal(points[which[k]]);
    collider.shape->query(std::span<const glm::vec3>(local, q), std::span<ColliderSample>(samples, q));
    for (std::uint32_t k = 0; k < q; ++k) {
      finishSample(samples[k]);
      out[which[k]] = samples[k];
    }
  }

 private:
  static bool isPositiveZero(glm::vec3 v) {
    const glm::vec3 zero(0.0f);
    return std::memcmp(&v, &zero, sizeof(glm::vec3)) == 0;
  }
  glm::vec3 toLocal(glm::vec3 x) const {
    return rotated ? inverse_rotation * (x - pose.translation) : x - pose.translation;
  }
  void finishSample(ColliderSample& s) const {
    if (rotated) s.normal = pose.rotation * s.normal;
    if (!std::isfinite(s.distance)) s.valid = false;  // never let a bad shape spread NaN
  }
};

// Collider samples at the step-start positions; per particle the boundary volume, its gradient
// (and each collider's share of it), its flux (wall velocity . grad V) and prod_c (1 - V_c); sets
// context.wall_approach_speed.
void sampleBoundary(StepContext& context);

// Whether particle i lies in a film of collider c (SphCollider::film_gap): its step-start
// distances to c and to one of c's film partners that faces c there add up to less than film_gap.
inline bool inFilmOf(const StepContext& context, std::size_t c, std::size_t i) {
  const SphCollider& collider = context.world.colliders[c];
  if (!(collider.film_gap > 0.0f)) return false;
  const ColliderSample& own = context.scratch.start_samples[c][i];
  if (!own.valid) return false;
  const float room = collider.film_gap - std::max(own.distance, 0.0f);
  if (!(room > 0.0f)) return false;
  const std::size_t partners = std::min(collider.film_partner_count, context.collider_count);
  for (std::size_t p = 0; p < partners; ++p) {
    const ColliderSample& other = context.scratch.start_samples[p][i];
    if (p != c && other.valid && std::max(other.distance, 0.0f) < room && facesAcrossAFilm(own.normal, other.normal))
      return true;
  }
  return false;
}

// surface_pressure_force: the pair's pressure terms (p_i + p_b) / rho_i^2 take
// p_b = p_i + rho_i g . (x_b - x_i) at the mirror point x_b = x_i - 2 s n (Adami et al. 2012
// eq. 27), which adds -2 s (g . n) / rho_i to the mirror's 2 p_i / rho_i^2: less under a body's
// bottom, more on its top, nothing on its sides.
inline float surfacePressureShift(const StepContext& context, const ColliderSample& sample, std::size_t i) {
  const float s = std::clamp(sample.distance, 0.0f, context.support);
  return -2.0f * s * glm::dot(context.params.gravity, sample.normal) / context.particles.density[i];
}

// Boundary-pressure coupling of collider c (one with boundary_pressure) with particle i,
// F_c = -m dv_ic / dt where the boundary term changed i's velocity by dv_ic = -2 kappa_i rho_0
// grad V_ic over the step (scratch.kappa holds the impulse kappa_i; old_position the step-start
// positions; boundary_share the grad V_ic that sampleBoundary found there). With
// surface_pressure_force the body instead feels the pressure at its surface (the sum kept >= 0:
// it never pulls), and only the body: extrapolating in the water's own boundary term too (Newton's
// third law pair by pair) leaves the body where the mirror puts it, since the density solve raises
// p_i by what the boundary stops pushing. The two forces differ by O(rho g r A) per face, which
// vanishes with the particle radius.
inline void addCouplingTerm(const StepContext& context, std::size_t c, std::size_t i, ForceTorque& acc) {
  const SphScratch& scratch = context.scratch;
  const ColliderSample& sample = scratch.start_samples[c][i];
  if (!withinSupport(sample, context.support) || inFilmOf(context, c, i)) return;
  const SphCollider& collider = context.world.colliders[c];
  const glm::vec3 grad = scratch.boundary_share[c][i];
  glm::vec3 f;
  if (collider.surface_pressure_force) {
    // (p_i + p_b) / rho_i^2: the mirror's 2 kappa_i / dt and the shift to the surface.
    const float terms =
        std::max(0.0f, kMirror * scratch.kappa[i] / context.dt + surfacePressureShift(context, sample, i));
    f = (context.mass * context.rest_density * terms) * grad;
  } else {  // the mirror alone, in its own float order (the committed replays' hashes)
    f = (kMirror * context.mass * scratch.kappa[i] * context.rest_density / context.dt) * grad;
  }
  acc.force += f;
  acc.torque += glm::cross(scratch.old_position[i] - collider.pose.translation, f);
}

}  // namespace fluid::sph_step
