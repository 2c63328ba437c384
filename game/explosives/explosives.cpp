#include "game/explosives/explosives.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace game {

std::string validateExplosiveParams(const ExplosiveParams& p) {
  auto positive = [](float v) { return std::isfinite(v) && v > 0.0f; };
  if (!positive(p.fuse_seconds)) return "explosives.fuse_seconds = " + std::to_string(p.fuse_seconds) + " (need > 0)";
  if (!(std::isfinite(p.throw_speed) && p.throw_speed >= 0.0f))
    return "explosives.throw_speed = " + std::to_string(p.throw_speed) + " (need >= 0)";
  if (!(std::isfinite(p.lob_degrees) && std::abs(p.lob_degrees) <= 80.0f))
    return "explosives.lob_degrees = " + std::to_string(p.lob_degrees) + " (need a value in [-80, 80])";
  if (!positive(p.radius)) return "explosives.radius = " + std::to_string(p.radius) + " (need > 0)";
  if (!positive(p.mass)) return "explosives.mass = " + std::to_string(p.mass) + " (need > 0)";
  if (!(std::isfinite(p.impact_speed_change) && p.impact_speed_change >= 0.0f))
    return "explosives.impact_speed_change = " + std::to_string(p.impact_speed_change) + " (need >= 0)";
  if (p.max_live < 1) return "explosives.max_live = " + std::to_string(p.max_live) + " (need >= 1)";
  if (std::string error = fluid::validateBlast(blastOf(p, glm::vec3(0.0f))); !error.empty())
    return "explosives: " + error;
  return {};
}

fluid::Blast blastOf(const ExplosiveParams& params, glm::vec3 centre) {
  fluid::Blast blast;
  blast.centre = centre;
  blast.impulse_at_1m = params.impulse_at_1m;
  blast.core_radius = params.core_radius;
  blast.reach = params.reach;
  return blast;
}

namespace {

// The charge to (re)use for a throw: a parked one, else a new body while under max_live, else the
// live charge that detonates soonest (the oldest throw), which is defused and thrown again.
Charge& chargeForThrow(Explosives& e, engine::PhysicsWorld& physics) {
  for (Charge& c : e.charges)
    if (!c.live) return c;
  if (static_cast<int>(e.charges.size()) < e.params.max_live) {
    engine::BodyDesc desc;
    desc.mass = e.params.mass;
    desc.friction = 0.7f;
    desc.restitution = 0.3f;
    Charge charge;
    charge.body = engine::addSphere(physics, desc, e.params.radius);
    engine::setBodyEnabled(physics, charge.body, false);
    e.charges.push_back(charge);
    return e.charges.back();
  }
  return *std::min_element(e.charges.begin(), e.charges.end(),
                           [](const Charge& a, const Charge& b) { return a.detonates_at < b.detonates_at; });
}

}  // namespace

glm::vec3 throwOrigin(glm::vec3 eye, glm::vec3 view_dir) {
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  const glm::vec3 side = glm::cross(view_dir, up);
  const float length = glm::length(side);
  const glm::vec3 right = length > 1e-4f && std::isfinite(length) ? side / length : glm::vec3(1.0f, 0.0f, 0.0f);
  return eye + 0.25f * right - 0.2f * up;
}

glm::vec3 throwVelocity(const ExplosiveParams& params, glm::vec3 direction) {
  const float length = glm::length(direction);
  glm::vec3 along = length > 1e-6f && std::isfinite(length) ? direction / length : glm::vec3(0, 0, -1);
  // Raise the aim by the lob angle in the vertical plane of the throw (straight up stays up).
  const float horizontal = std::sqrt(along.x * along.x + along.z * along.z);
  if (horizontal > 1e-4f && params.lob_degrees != 0.0f) {
    const float pitch = std::atan2(along.y, horizontal) + glm::radians(params.lob_degrees);
    const float clamped = std::clamp(pitch, -1.55f, 1.55f);
    along = glm::vec3(along.x / horizontal * std::cos(clamped), std::sin(clamped), along.z / horizontal * std::cos(clamped));
  }
  return along * params.throw_speed;
}

namespace {

// The nearest collider surface to the charge's centre: its distance minus the charge's radius
// (negative: touching), and the surface normal there. Parts that have no sample there are skipped.
float clearance(std::span<const fluid::CachedCollider> colliders, glm::vec3 centre, float radius, glm::vec3& normal) {
  float best = std::numeric_limits<float>::max();
  for (const fluid::CachedCollider& part : colliders) {
    const fluid::ColliderSample sample = part.collider.sample(centre);  // the level's parts sit at the origin
    if (sample.valid && sample.distance - radius < best) {
      best = sample.distance - radius;
      normal = sample.normal;
    }
  }
  return best;
}

}  // namespace

void predictThrow(const ExplosiveParams& params, glm::vec3 origin, glm::vec3 direction, glm::vec3 gravity,
                  std::span<const fluid::CachedCollider> colliders, AimArc& out) {
  out.path.clear();
  out.lands = false;
  // Bullet's triangle meshes collide with a skin of 4 cm around their faces (the default margin),
  // so a charge touches the level that much before its sphere does.
  constexpr float kBulletMeshMargin = 0.04f;
  const float radius = params.radius + kBulletMeshMargin;
  const glm::vec3 velocity = throwVelocity(params, direction);
  const auto at = [&](float t) { return origin + velocity * t + 0.5f * gravity * t * t; };
  const float dt = AimArc::kSampleSeconds;
  const int samples = static_cast<int>(std::ceil(params.fuse_seconds / dt));
  glm::vec3 normal{0.0f, 1.0f, 0.0f};
  // The throw starts inside the thrower: contacts count only once the charge has left its own
  // starting clearance (a throw from within a collider's band would otherwise land at once).
  bool free = clearance(colliders, origin, radius, normal) > 0.0f;
  float t_end = params.fuse_seconds;
  for (int k = 0; k <= samples; ++k) {
    const float t = std::min(static_cast<float>(k) * dt, params.fuse_seconds);
    const glm::vec3 p = at(t);
    out.path.push_back(p);
    const float c = clearance(colliders, p, radius, normal);
    if (!free) {
      free = c > 0.0f;
      continue;
    }
    if (c > 0.0f || k == 0) continue;
    // Contact between the last two samples: bisect for the time the clearance crosses zero.
    float lo = t - dt, hi = t;
    for (int i = 0; i < 12; ++i) {
      const float mid = 0.5f * (lo + hi);
      (clearance(colliders, at(mid), radius, normal) > 0.0f ? lo : hi) = mid;
    }
    clearance(colliders, at(hi), radius, normal);
    t_end = hi;
    out.path.back() = at(hi);
    out.lands = true;
    break;
  }
  out.end = at(t_end);
  out.end_normal = normal;
  out.flight_seconds = t_end;
}

void throwExplosive(Explosives& e, engine::PhysicsWorld& physics, glm::vec3 origin, glm::vec3 direction,
                    glm::vec3 initial_velocity) {
  const glm::vec3 along = throwVelocity(e.params, direction);
  Charge& charge = chargeForThrow(e, physics);
  engine::BodyState state;
  state.position = origin;
  state.linear_velocity = initial_velocity + along;
  state.angular_velocity = glm::vec3(0.0f);
  engine::setBodyEnabled(physics, charge.body, true);
  engine::resetBody(physics, charge.body, state);
  charge.live = true;
  charge.detonates_at = e.time + e.params.fuse_seconds;
  charge.last_velocity = state.linear_velocity;
  ++e.thrown;
}

void stepExplosives(Explosives& e, engine::PhysicsWorld& physics, double dt) {
  e.time += dt;
  e.detonations.clear();
  for (Charge& charge : e.charges) {
    if (!charge.live) continue;
    const engine::BodyState state = engine::bodyState(physics, charge.body);
    const float change = glm::length(state.linear_velocity - charge.last_velocity);
    charge.last_velocity = state.linear_velocity;
    const bool impact = e.params.impact_speed_change > 0.0f && change > e.params.impact_speed_change;
    if (e.time + 1e-9 < charge.detonates_at && !impact) continue;
    const fluid::Blast blast = blastOf(e.params, state.position);
    charge.live = false;
    engine::setBodyEnabled(physics, charge.body, false);
    if (!fluid::validateBlast(blast).empty()) continue;  // a non-finite charge position: no blast
    e.detonations.push_back(blast);
    ++e.detonated;
  }
  // Blasts push the bodies after every fuse is decided, so the order of the charges does not
  // matter; a live charge thrown by a blast keeps its own fuse.
  for (const fluid::Blast& blast : e.detonations) e.bodies_pushed += static_cast<std::uint64_t>(engine::applyBlast(physics, blast));
}

int liveCharges(const Explosives& e) {
  return static_cast<int>(std::count_if(e.charges.begin(), e.charges.end(), [](const Charge& c) { return c.live; }));
}

}  // namespace game
