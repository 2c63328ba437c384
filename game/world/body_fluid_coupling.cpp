#include "game/world/body_fluid_coupling.hpp"

#include "fluid/sph/analytic_colliders.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace game {

bool capWrench(const WrenchCap& cap, glm::vec3& force, glm::vec3& torque) {
  const float f = glm::length(force), t = glm::length(torque);
  const bool cap_force = f > cap.max_force, cap_torque = t > cap.max_torque;
  if (cap_force) force *= cap.max_force / f;
  if (cap_torque) torque *= cap.max_torque / t;
  return cap_force || cap_torque;
}

void grownBounds(std::span<const glm::vec3> points, glm::vec3 grow, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(std::numeric_limits<float>::max());
  hi = glm::vec3(-std::numeric_limits<float>::max());
  for (const glm::vec3& x : points) {
    lo = glm::min(lo, x);
    hi = glm::max(hi, x);
  }
  lo -= grow;
  hi += grow;
}

void initBodyFluidCoupling(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, glm::vec3 half_extents,
                           glm::vec3 region_min, glm::vec3 region_max) {
  coupling = BodyFluidCoupling{};
  coupling.box_shape = std::make_shared<fluid::BoxShape>(half_extents);
  // Water slides along wood and does not bounce off it (Kolb 2004 §3.3.2: ε = 0, small friction).
  coupling.material.resilience = 0.0f;
  coupling.material.friction = 0.05f;
  coupling.region_min = region_min;
  coupling.region_max = region_max;
  coupling.first_collider = sph.colliders.size();
  coupling.half_extents = half_extents;
  const float volume = 8.0f * half_extents.x * half_extents.y * half_extents.z;
  coupling.cap.max_force = coupling.force_limit * sph.params.rest_density * glm::length(sph.params.gravity) * volume;
  coupling.reach = glm::length(half_extents);
  coupling.cap.max_torque = coupling.cap.max_force * coupling.reach;
}

void collidersFromBodies(BodyFluidCoupling& coupling, const engine::PhysicsWorld& physics,
                         std::span<const engine::BodyId> bodies, fluid::SphWorld& sph) {
  sph.colliders.resize(coupling.first_collider);
  coupling.coupled.clear();
  // Bounds of the water, grown by what can reach it this step: a box's half diagonal and the
  // kernel support (boundary terms act within it). A box outside costs the SPH step nothing.
  glm::vec3 lo, hi;
  grownBounds(sph.particles.position, glm::vec3(coupling.reach + 4.0f * sph.params.particle_radius), lo, hi);
  lo = glm::max(lo, coupling.region_min);
  hi = glm::min(hi, coupling.region_max);
  for (const engine::BodyId id : bodies) {
    const engine::BodyState state = engine::bodyState(physics, id);
    if (glm::any(glm::lessThan(state.position, lo)) || glm::any(glm::greaterThan(state.position, hi))) continue;
    fluid::SphCollider collider;
    collider.shape = coupling.box_shape;
    collider.pose = engine::colliderPoseOf(state);  // box centre = centre of mass
    collider.material = coupling.material;
    collider.integrate_pose = true;          // moves with its velocities through the SPH sub-steps
    collider.surface_pressure_force = coupling.surface_pressure_force;
    // Water in a film between the box and the scene's colliders pushes the box through filmForce.
    collider.film_gap = fluid::sphSpacing(sph.params);
    collider.film_partner_count = coupling.first_collider;
    sph.colliders.push_back(collider);
    coupling.coupled.push_back(id);
  }
}

namespace {

// One face of the box in its own frame: the axis it is normal to, the side (+1/-1) and the two
// axes u, v that span it.
struct BoxFace {
  int axis = 0, u = 1, v = 2;
  float side = 1.0f;
};

// Whether a point given in the box's frame lies in the film in front of `face`: within d of the
// face's plane (either side: water pushed a little into the box is still the film's) and inside
// its outline.
bool inFaceFilm(glm::vec3 in_box, const BoxFace& face, glm::vec3 half, float d) {
  const float ahead = face.side * in_box[face.axis] - half[face.axis];
  return std::abs(ahead) < d && std::abs(in_box[face.u]) < half[face.u] && std::abs(in_box[face.v]) < half[face.v];
}

// The water near a box: particles within reach of its centre, with their positions in its frame.
struct NearbyWater {
  const std::vector<std::size_t>& index;
  const std::vector<glm::vec3>& in_box;
};

// What filmPressureAt reads, fixed for one box and step: its half extents, the spacing d, the
// reach R of the extrapolation and the hydrostatic gradient rho_0 |g| along `down`.
struct FilmReading {
  glm::vec3 half{0.0f};
  float d = 0.0f, R = 0.0f, rho_g = 0.0f;
  glm::vec3 down{0.0f};
};

// The film's pressure at face point x: the surrounding water's, from the particles within R
// outside the film (squeezed, a film particle's pressure is the SPH's reading of a gap it does
// not resolve), each shifted hydrostatically by rho_0 |g| (y_j - y) to the point's height, a
// smooth-weighted mean; 0 where no such water is within R.
float filmPressureAt(glm::vec3 x, const BoxFace& face, const fluid::SphWorld& sph, const NearbyWater& water,
                     const FilmReading& reading) {
  const float R = reading.R;
  double weight = 0.0, weighted = 0.0;
  for (std::size_t n = 0; n < water.index.size(); ++n) {
    const std::size_t i = water.index[n];
    const glm::vec3 rel = sph.particles.position[i] - x;
    const float dist2 = glm::dot(rel, rel);
    if (dist2 >= R * R || inFaceFilm(water.in_box[n], face, reading.half, reading.d)) continue;
    const float q = 1.0f - std::sqrt(dist2) / R;
    const float w = q * q;  // a smooth weight that falls to 0 at R
    const float p = sph.particles.pressure[i] + reading.rho_g * glm::dot(x - sph.particles.position[i], reading.down);
    weight += w;
    weighted += w * p;
  }
  if (!(weight > 0.0)) return 0.0f;
  const float pressure = static_cast<float>(weighted / weight);
  return std::isfinite(pressure) ? std::max(0.0f, pressure) : 0.0f;
}

}  // namespace

FilmWrench filmForce(const BodyFluidCoupling& coupling, const fluid::SphWorld& sph, const fluid::ColliderPose& pose,
                     FilmScratch& scratch) {
  FilmWrench out;
  const float d = fluid::sphSpacing(sph.params);
  // The film's pressure is the surrounding water's, so it is read from the particles around the
  // face's rim: within twice the kernel support, which reaches the middle of a face up to about
  // 8 d wide (the game's 0.6 m crate at d = 8 cm) from the water beside it.
  const float R = 2.0f * fluid::sphSupport(sph.params);
  // The water that can reach a face point: particles within the box's half diagonal plus R,
  // gathered at the first face point in a film (most boxes have none, and skip the scan).
  const glm::quat inverse_rotation = glm::inverse(pose.rotation);
  bool gathered = false;
  const auto gatherNearby = [&] {
    const float reach = coupling.reach + R;
    scratch.nearby.clear();
    scratch.nearby_in_box.clear();
    for (std::size_t i = 0; i < sph.particles.sphCount(); ++i) {
      const glm::vec3 from_centre = sph.particles.position[i] - pose.translation;
      if (glm::dot(from_centre, from_centre) >= reach * reach) continue;
      scratch.nearby.push_back(i);
      scratch.nearby_in_box.push_back(inverse_rotation * from_centre);
    }
    gathered = true;
  };
  const NearbyWater water{scratch.nearby, scratch.nearby_in_box};
  const glm::vec3 half = coupling.half_extents;
  const float g = glm::length(sph.params.gravity);
  const FilmReading reading{half, d, R, sph.params.rest_density * g,
                            g > 0.0f ? glm::normalize(sph.params.gravity) : glm::vec3(0.0f)};
  std::vector<glm::vec3>&points = scratch.points, &local = scratch.local;
  std::vector<fluid::ColliderSample>& samples = scratch.samples;
  std::vector<float>& gap = scratch.gap;
  for (int axis = 0; axis < 3; ++axis)
    for (const float side : {-1.0f, 1.0f}) {
      const BoxFace face{axis, (axis + 1) % 3, (axis + 2) % 3, side};
      const int nu = std::max(1, static_cast<int>(std::ceil(2.0f * half[face.u] / d)));
      const int nv = std::max(1, static_cast<int>(std::ceil(2.0f * half[face.v] / d)));
      const float area = 4.0f * half[face.u] * half[face.v] / static_cast<float>(nu * nv);
      glm::vec3 normal_local(0.0f);
      normal_local[axis] = side;
      const glm::vec3 normal = pose.rotation * normal_local;
      points.clear();
      for (int a = 0; a < nu; ++a)
        for (int b = 0; b < nv; ++b) {
          glm::vec3 q(0.0f);
          q[axis] = side * half[axis];
          q[face.u] = half[face.u] * (2.0f * (static_cast<float>(a) + 0.5f) / static_cast<float>(nu) - 1.0f);
          q[face.v] = half[face.v] * (2.0f * (static_cast<float>(b) + 0.5f) / static_cast<float>(nv) - 1.0f);
          points.push_back(pose.rotation * q + pose.translation);
        }
      // Gap to the scene's colliders that face this face (fluid::facesAcrossAFilm): the film
      // exists only where it is thinner than d.
      gap.assign(points.size(), std::numeric_limits<float>::max());
      for (std::size_t c = 0; c < coupling.first_collider && c < sph.colliders.size(); ++c) {
        const fluid::SphCollider& collider = sph.colliders[c];
        local.resize(points.size());
        samples.assign(points.size(), fluid::ColliderSample{});
        for (std::size_t k = 0; k < points.size(); ++k) local[k] = fluid::toColliderSpace(collider.pose, points[k]);
        collider.shape->query(local, samples);
        for (std::size_t k = 0; k < points.size(); ++k) {
          const glm::vec3 collider_normal = collider.pose.rotation * samples[k].normal;
          if (samples[k].valid && fluid::facesAcrossAFilm(normal, collider_normal))
            gap[k] = std::min(gap[k], samples[k].distance);
        }
      }
      for (std::size_t k = 0; k < points.size(); ++k) {
        if (!(gap[k] < d)) continue;
        if (!gathered) gatherNearby();
        const float pressure = filmPressureAt(points[k], face, sph, water, reading);
        if (!(pressure > 0.0f)) continue;
        const glm::vec3 f = -pressure * area * normal;
        out.force += f;
        out.torque += glm::cross(points[k] - pose.translation, f);
        ++out.points;
      }
    }
  return out;
}

std::string forcesToBodies(BodyFluidCoupling& coupling, const fluid::SphWorld& sph, engine::PhysicsWorld& physics) {
  std::string bad;
  for (std::size_t k = 0; k < coupling.coupled.size(); ++k) {
    const fluid::SphCollider& collider = sph.colliders[coupling.first_collider + k];
    // fluid/sph reports the torque about pose.translation, the box centre: Bullet's centre of mass.
    glm::vec3 force = collider.force, torque = collider.torque;
    const FilmWrench film = filmForce(coupling, sph, collider.pose, coupling.film_scratch);
    force += film.force;
    torque += film.torque;
    coupling.film_points += static_cast<std::uint64_t>(film.points);
    const bool capped = capWrench(coupling.cap, force, torque);
    if (!engine::setExternalForce(physics, coupling.coupled[k], force, torque)) {
      if (bad.empty()) bad = "fluid force on body " + std::to_string(coupling.coupled[k]) + " is not finite";
      continue;
    }
    ++coupling.forces_applied;
    coupling.clamped += capped ? 1u : 0u;
  }
  return bad;
}

}  // namespace game
