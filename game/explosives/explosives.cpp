#include "game/explosives/explosives.hpp"

#include <algorithm>
#include <cmath>

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

void throwExplosive(Explosives& e, engine::PhysicsWorld& physics, glm::vec3 origin, glm::vec3 direction,
                    glm::vec3 initial_velocity) {
  const float length = glm::length(direction);
  glm::vec3 along = length > 1e-6f && std::isfinite(length) ? direction / length : glm::vec3(0, 0, -1);
  // Raise the aim by the lob angle in the vertical plane of the throw (straight up stays up).
  const float horizontal = std::sqrt(along.x * along.x + along.z * along.z);
  if (horizontal > 1e-4f) {
    const float pitch = std::atan2(along.y, horizontal) + glm::radians(e.params.lob_degrees);
    const float clamped = std::clamp(pitch, -1.55f, 1.55f);
    along = glm::vec3(along.x / horizontal * std::cos(clamped), std::sin(clamped), along.z / horizontal * std::cos(clamped));
  }
  Charge& charge = chargeForThrow(e, physics);
  engine::BodyState state;
  state.position = origin;
  state.linear_velocity = initial_velocity + along * e.params.throw_speed;
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
