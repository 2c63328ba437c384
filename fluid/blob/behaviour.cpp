// Blob behaviours (targets for the body) and the state machine. See fluid/blob/behaviour.hpp.
#include "fluid/blob/behaviour.hpp"

#include "fluid/core/finite.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numeric>
#include <sstream>

namespace fluid {
namespace {

constexpr float kPi = 3.14159265358979f;

struct Names {
  BlobBehaviourKind kind;
  const char* name;
};
constexpr Names kBehaviours[] = {{BlobBehaviourKind::idle, "idle"},
                                 {BlobBehaviourKind::emerge, "emerge"},
                                 {BlobBehaviourKind::ball, "ball"},
                                 {BlobBehaviourKind::tentacles, "tentacles"},
                                 {BlobBehaviourKind::coat_wall, "coat_wall"},
                                 {BlobBehaviourKind::chase, "chase"},
                                 {BlobBehaviourKind::reassemble, "reassemble"}};
struct TriggerNames {
  BlobTriggerKind kind;
  const char* name;
};
constexpr TriggerNames kTriggers[] = {{BlobTriggerKind::after_seconds, "after_seconds"},
                                      {BlobTriggerKind::goal_reached, "goal_reached"},
                                      {BlobTriggerKind::target_within, "target_within"},
                                      {BlobTriggerKind::target_beyond, "target_beyond"},
                                      {BlobTriggerKind::blasted, "blasted"},
                                      {BlobTriggerKind::event, "event"}};

// Matches particles to goal slots so that paths rarely cross: both sets are sorted by y and cut
// into equal layers, each layer by x into equal rows, each row by z, and equal ranks are paired
// (a monotone map, like sorting in 1D). Ties break by index, so it is deterministic. With all z
// equal it is the 2D version (a wall layer). slot_of[k] = slot of particles[k].
void rankMatch(std::span<const glm::vec3> particle_pos, std::span<const glm::vec3> slot_pos,
               std::vector<std::uint32_t>& slot_of) {
  const std::size_t m = particle_pos.size();
  std::vector<std::uint32_t> pi(m), si(m);
  std::iota(pi.begin(), pi.end(), 0u);
  std::iota(si.begin(), si.end(), 0u);
  auto by = [](std::span<const glm::vec3> pos, int axis) {
    return [pos, axis](std::uint32_t a, std::uint32_t b) {
      return pos[a][axis] < pos[b][axis] || (pos[a][axis] == pos[b][axis] && a < b);
    };
  };
  std::sort(pi.begin(), pi.end(), by(particle_pos, 1));
  std::sort(si.begin(), si.end(), by(slot_pos, 1));
  const std::size_t layers = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(std::cbrt(double(m)))));
  for (std::size_t l = 0; l < layers; ++l) {
    const std::size_t b = l * m / layers, e = (l + 1) * m / layers;
    std::sort(pi.begin() + b, pi.begin() + e, by(particle_pos, 0));
    std::sort(si.begin() + b, si.begin() + e, by(slot_pos, 0));
    const std::size_t rows = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(std::sqrt(double(e - b)))));
    for (std::size_t r = 0; r < rows; ++r) {
      const std::size_t rb = b + r * (e - b) / rows, re = b + (r + 1) * (e - b) / rows;
      std::sort(pi.begin() + rb, pi.begin() + re, by(particle_pos, 2));
      std::sort(si.begin() + rb, si.begin() + re, by(slot_pos, 2));
    }
  }
  slot_of.resize(m);
  for (std::size_t k = 0; k < m; ++k) slot_of[pi[k]] = si[k];
}

// Nearest surface among the wall collider(s) at a world point (world-space normal).
ColliderSample sampleWalls(const BlobWorld& world, int wall, glm::vec3 point) {
  ColliderSample best;
  best.distance = FLT_MAX;
  for (std::size_t c = 0; c < world.colliders.size(); ++c) {
    if (wall >= 0 && static_cast<std::size_t>(wall) != c) continue;
    const BlobCollider& col = world.colliders[c];
    if (!col.shape) continue;
    const glm::vec3 local = toColliderSpace(col.pose, point);
    ColliderSample s;
    col.shape->query({&local, 1}, {&s, 1});
    if (!s.valid || !std::isfinite(s.distance)) continue;
    if (!best.valid || s.distance < best.distance) {
      best = s;
      best.normal = toWorldDirection(col.pose, s.normal);
    }
  }
  return best;
}

glm::vec3 anyPerpendicular(glm::vec3 n) {
  const glm::vec3 a = std::abs(n.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
  return glm::normalize(a - glm::dot(a, n) * n);
}

void clearTexturing(BlobParticles& p) {
  std::fill(p.tangent.begin(), p.tangent.end(), glm::vec3(0.0f, 1.0f, 0.0f));
  std::fill(p.normal.begin(), p.normal.end(), glm::vec3(1.0f, 0.0f, 0.0f));
  std::fill(p.length_coord.begin(), p.length_coord.end(), -1.0f);
  std::fill(p.strength.begin(), p.strength.end(), 1.0f);
  std::fill(p.radius_scale.begin(), p.radius_scale.end(), 1.0f);
  std::fill(p.tentacle.begin(), p.tentacle.end(), -1);
}

// Goal offsets = `shape` slots matched to the particles (shape centred on the origin).
void matchShape(BlobWorld& world, std::span<const std::uint32_t> who, std::span<const glm::vec3> shape) {
  std::vector<glm::vec3> pos(who.size());
  const glm::vec3 c = blobCentroid(world.particles.position);
  for (std::size_t k = 0; k < who.size(); ++k) pos[k] = world.particles.position[who[k]] - c;
  std::vector<std::uint32_t> slot_of;
  rankMatch(pos, shape, slot_of);
  for (std::size_t k = 0; k < who.size(); ++k) world.target.offset[who[k]] = shape[slot_of[k]];
}

int tentacleParticles(const BlobBehaviour& b, const BlobParams& p) {
  if (b.tentacle_particles > 0) return b.tentacle_particles;
  const float mean_spacing = p.spacing * 0.5f * (1.0f + b.tip_radius_scale);
  return std::clamp(static_cast<int>(std::lround(b.tentacle_length / mean_spacing)), 2, 256);
}

// Where tentacle k leaves the core: fanned across the side of the body that faces the target
// (azimuths about the horizontal heading to it) and raised 30 or 45 degrees, so that seen from the
// target the tentacles rise from the body and arc toward it. Pointed straight at the target from a
// cone, they read from there as a star of spikes (issue 35: "a sea mine, not a creature").
glm::vec3 tentacleRoot(glm::vec3 aim, int k, int count) {
  glm::vec3 h(aim.x, 0.0f, aim.z);
  h = glm::length(h) > 1e-3f ? glm::normalize(h) : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  const glm::vec3 side = glm::cross(up, h);
  const float step = std::min(0.9f, 4.2f / static_cast<float>(std::max(count, 1)));
  const float azimuth = (static_cast<float>(k) - 0.5f * static_cast<float>(count - 1)) * step;
  const float elevation = 0.52f + 0.26f * static_cast<float>(k % 2);
  return glm::normalize(std::cos(elevation) * (std::cos(azimuth) * h + std::sin(azimuth) * side) +
                        std::sin(elevation) * up);
}

// Where its tip goes: toward the target, turned by half the spread angle toward its root's side,
// so the tips close around the target from all sides rather than meeting in one point.
glm::vec3 tentacleTipDirection(glm::vec3 to_target, glm::vec3 root, float spread) {
  glm::vec3 side = root - glm::dot(root, to_target) * to_target;
  side = glm::length(side) > 1e-4f ? glm::normalize(side) : anyPerpendicular(to_target);
  return glm::normalize(std::cos(0.5f * spread) * to_target + std::sin(0.5f * spread) * side);
}

glm::vec3 aimAt(glm::vec3 from, glm::vec3 target) {
  const glm::vec3 d = target - from;
  const float len = glm::length(d);
  return len > 1e-6f && std::isfinite(len) ? d / len : glm::vec3(1.0f, 0.0f, 0.0f);
}

// Re-aims the tentacles at the target and places their goal slots; recomputes each particle's
// texturing frame from the chain (paper §7: per-particle basis vectors and length coordinates).
// Paper §7's tentacles reach for the player: each one's visible length (tentacle_extent) grows
// toward the target while it is within reach_range and retracts to a stub beyond, at grow_speed
// (staggered per tentacle, so they do not move as one). The chain slides out of the core: the
// particles not yet out wait compressed on the axis inside the core. The centreline bends aside by
// `curl` (a quadratic bend, strongest when retracted: a tentacle curls up, and straightens to reach)
// in a plane that turns about the axis, plus a travelling sway, so no two frames are alike.
void layTentacles(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target, float dt) {
  BlobTarget& t = world.target;
  BlobParticles& parts = world.particles;
  const float d = world.params.spacing;
  const glm::vec3 aim = aimAt(t.anchor, target);
  const float core_radius = blobBodyRadius(world.params) *
                            std::cbrt(1.0f - static_cast<float>(b.tentacles * tentacleParticles(b, world.params)) /
                                                 static_cast<float>(parts.size()));
  const float time = static_cast<float>(world.time);
  const bool in_range = b.reach_range <= 0.0f || glm::length(target - t.anchor) <= b.reach_range;
  if (t.tentacle_extent.size() != t.tentacle_particles.size())
    t.tentacle_extent.assign(t.tentacle_particles.size(), 0.0f);
  for (std::size_t k = 0; k < t.tentacle_particles.size(); ++k) {
    const auto& chain = t.tentacle_particles[k];
    const glm::vec3 root = tentacleRoot(aim, static_cast<int>(k), b.tentacles);
    const glm::vec3 base = t.anchor + root * (0.85f * core_radius);
    const glm::vec3 dir = tentacleTipDirection(aimAt(base, target), root, b.tentacle_spread);
    // The tip stops short of the target (kShort): it grabs at the player's face, it does not fill the view.
    constexpr float kShort = 0.3f;
    const float full = std::min(b.tentacle_length, std::max(glm::length(target - base) - kShort, 2.0f * d));
    const float stub = std::min(full, std::max(2.0f * d, 0.15f * b.tentacle_length));
    const float want = in_range ? full : stub;
    const float rate = b.grow_speed * (1.0f - 0.12f * static_cast<float>(k % 3)) * dt;
    float& ext = t.tentacle_extent[k];
    ext = std::min(full, ext + std::clamp(want - ext, -rate, rate));
    const std::size_t m = chain.size();
    float natural = 0.0f;
    for (std::size_t j = 0; j < m; ++j)
      natural += d * glm::mix(1.0f, b.tip_radius_scale, static_cast<float>(j) / static_cast<float>(m - 1));
    const float stretch = full / natural;
    const float hidden = full - ext, inner = 0.7f * core_radius;
    const glm::vec3 side = anyPerpendicular(dir), side2 = glm::cross(dir, side);
    const float phase = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(std::max(b.tentacles, 1)) + 0.6f * time;
    const glm::vec3 bend = std::cos(phase) * side + std::sin(phase) * side2;
    const float bend_amp = b.curl * ext * (1.0f - 0.8f * ext / std::max(full, 1e-6f));
    // The visible part is a quadratic Bezier from the base, leaving along the root (up and out of the
    // body), ending `ext` out along `dir`: an arm that rises and reaches, the same shape at any length.
    const glm::vec3 p1 = base + root * (0.4f * ext), p2 = base + dir * ext;
    float along = 0.0f;
    for (std::size_t j = 0; j < m; ++j) {
      const float s = static_cast<float>(j) / static_cast<float>(m - 1);
      along += stretch * d * glm::mix(1.0f, b.tip_radius_scale, s);
      const float out = along - hidden;  // distance out of the core along the tentacle
      glm::vec3 goal;
      if (out <= 0.0f) {
        goal = base + root * (out * inner / std::max(hidden, 1e-6f));
      } else {
        const float u = out / std::max(ext, 1e-6f);  // 0 at the base, 1 at the tip
        const float sway =
            0.04f * ext * u * std::sin(2.0f * kPi * 0.4f * time - 3.0f * u + 1.7f * static_cast<float>(k));
        const glm::vec3 curve = (1.0f - u) * (1.0f - u) * base + 2.0f * u * (1.0f - u) * p1 + u * u * p2;
        goal = curve + bend * (bend_amp * u * u) + side * sway;
      }
      t.offset[chain[j]] = goal - t.anchor;
    }
    t.tentacle_base[k] = base;
    t.tentacle_dir[k] = dir;
    t.tentacle_length[k] = full;
    for (std::size_t j = 0; j < m; ++j) {
      const std::uint32_t i = chain[j];
      const glm::vec3 a = parts.position[chain[j > 0 ? j - 1 : 0]];
      const glm::vec3 c = parts.position[chain[j + 1 < m ? j + 1 : m - 1]];
      const glm::vec3 tan = glm::length(c - a) > 1e-9f ? glm::normalize(c - a) : dir;
      glm::vec3 nrm = side - glm::dot(side, tan) * tan;
      nrm = glm::length(nrm) > 1e-6f ? glm::normalize(nrm) : anyPerpendicular(tan);
      parts.tangent[i] = tan;
      parts.normal[i] = nrm;
    }
  }
}

// Picks the tentacles' particles (those furthest out toward each tentacle's root), gives the
// rest `core_ratios`' lattice shape, and lays the tentacles (retracted: they grow from the core).
void startTentacles(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target, glm::vec3 core_ratios) {
  BlobTarget& t = world.target;
  BlobParticles& parts = world.particles;
  const std::size_t n = parts.size();
  const int m = tentacleParticles(b, world.params);
  const glm::vec3 c = blobCentroid(parts.position);
  t.anchor = c;
  t.anchor_at_centroid = false;
  t.rotate = false;
  const glm::vec3 aim = aimAt(c, target);
  std::vector<std::uint8_t> used(n, 0);
  t.tentacle_particles.assign(b.tentacles, {});
  t.tentacle_base.assign(b.tentacles, c);
  t.tentacle_dir.assign(b.tentacles, aim);
  t.tentacle_length.assign(b.tentacles, 0.0f);
  t.tentacle_extent.assign(b.tentacles, 0.0f);
  std::vector<std::uint32_t> order(n);
  std::vector<float> score(n), along(n);
  for (int k = 0; k < b.tentacles; ++k) {
    // The particles furthest out toward the tentacle become it, ordered base (inner) to tip.
    const glm::vec3 dir = tentacleRoot(aim, k, b.tentacles);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3 r = parts.position[i] - c;
      along[i] = glm::dot(r, dir);
      score[i] = along[i] - 0.5f * glm::length(r - along[i] * dir);
    }
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t bb) { return score[a] > score[bb]; });
    auto& chain = t.tentacle_particles[k];
    for (std::uint32_t i : order) {
      if (used[i]) continue;
      chain.push_back(i);
      used[i] = 1;
      if (static_cast<int>(chain.size()) == m) break;
    }
    std::stable_sort(chain.begin(), chain.end(),
                     [&](std::uint32_t a, std::uint32_t bb) { return along[a] < along[bb]; });
    for (std::size_t j = 0; j < chain.size(); ++j) {
      const std::uint32_t i = chain[j];
      const float s = chain.size() > 1 ? static_cast<float>(j) / static_cast<float>(chain.size() - 1) : 0.0f;
      parts.tentacle[i] = k;
      parts.length_coord[i] = s;
      // Paper §7: the tentacle's radius along its length set by the field strength (and cutoff).
      parts.strength[i] = glm::mix(1.0f, b.tip_strength, s);
      parts.radius_scale[i] = glm::mix(1.0f, b.tip_radius_scale, s);
      t.weight[i] = 2.0f * b.weight;  // stiffer than the core: a tentacle holds its reach
    }
  }
  std::vector<std::uint32_t> core;
  for (std::size_t i = 0; i < n; ++i)
    if (!used[i]) core.push_back(static_cast<std::uint32_t>(i));
  const std::vector<glm::vec3> shape = blobLatticeShape(core.size(), world.params.spacing, core_ratios);
  matchShape(world, core, shape);
  layTentacles(world, b, target, 0.0f);
}

// Squash and stretch (chase): the core's goal shape is stretched along the body's horizontal
// motion and squashed across it by the same volume, following the mean velocity of the particles
// (the anchor moves in spurts; the body's own motion is smooth), smoothed over 0.15 s.
void stretchCore(BlobWorld& world, const BlobBehaviour& b, float dt) {
  BlobTarget& t = world.target;
  const BlobParticles& parts = world.particles;
  glm::vec3 v(0.0f);
  for (const glm::vec3& u : parts.velocity) v += u;
  v /= static_cast<float>(std::max<std::size_t>(parts.size(), 1));
  v.y = 0.0f;
  const float speed = glm::length(v);
  if (speed > 1e-3f && std::isfinite(speed)) t.stretch_dir = v / speed;
  const float want = 1.0f + b.stretch * std::min(speed / b.speed, 1.5f);
  t.stretch += (want - t.stretch) * std::min(1.0f, dt / 0.15f);
  const float f = t.stretch, across = 1.0f / std::sqrt(f);
  const glm::vec3 h = t.stretch_dir;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (parts.tentacle[i] >= 0) continue;
    const glm::vec3 q = t.shape_offset[i];
    t.offset[i] = across * q + (f - across) * glm::dot(q, h) * h;
  }
}

void startCoatWall(BlobWorld& world, const BlobBehaviour& b) {
  BlobTarget& t = world.target;
  const BlobParams& p = world.params;
  const std::size_t n = world.particles.size();
  const float d = p.spacing;
  const float layer = 0.5f * d;  // particle centres one radius off the wall
  t.anchor = glm::vec3(0.0f);
  t.anchor_at_centroid = false;
  t.rotate = false;
  const ColliderSample at = sampleWalls(world, b.wall_collider, b.point);
  if (!at.valid) {  // no wall there: hold the current shape where it is (never NaN goals)
    t.offset = world.particles.position;
    return;
  }
  const glm::vec3 nrm = at.normal;
  const glm::vec3 surface = b.point - nrm * at.distance;
  const glm::vec3 up = anyPerpendicular(nrm);
  const glm::vec3 right = glm::cross(up, nrm);
  // Square lattice slots on the wall's tangent plane, nearest the centre first, each projected
  // onto the actual surface with the collider's distance and normal.
  const int k = static_cast<int>(std::ceil(std::sqrt(static_cast<float>(n)) * 0.6f)) + 2;
  std::vector<glm::vec2> uv;
  for (int j = -k; j <= k; ++j)
    for (int i = -k; i <= k; ++i) uv.push_back(glm::vec2(i, j) * d);
  std::stable_sort(uv.begin(), uv.end(), [](glm::vec2 a, glm::vec2 c) { return glm::length(a) < glm::length(c); });
  uv.resize(n);
  std::vector<glm::vec3> slots(n), slot_uv(n), part_uv(n);
  for (std::size_t s = 0; s < n; ++s) {
    const glm::vec3 q = surface + nrm * layer + right * uv[s].x + up * uv[s].y;
    const ColliderSample hit = sampleWalls(world, b.wall_collider, q);
    slots[s] = hit.valid ? q - hit.normal * (hit.distance - layer) : q;
    slot_uv[s] = glm::vec3(uv[s].x, uv[s].y, 0.0f);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 r = world.particles.position[i] - surface;
    part_uv[i] = glm::vec3(glm::dot(r, right), glm::dot(r, up), 0.0f);
  }
  std::vector<std::uint32_t> slot_of;
  rankMatch(part_uv, slot_uv, slot_of);
  for (std::size_t i = 0; i < n; ++i) t.offset[i] = slots[slot_of[i]];
}

// Chase around obstacles (a "bug" algorithm: Lumelsky & Stepanov 1987): probe one body radius
// ahead; where a wall (normal within 45 degrees of horizontal, so the ground does not count) is
// nearer than the body radius, drop the part of the heading that goes into it and slide along it
// until the way to the target is free. The side is chosen at the first wall and kept for the whole
// chase: re-choosing it at every wall flipped it back and forth in front of a wall straight across
// the way (the probe is free for a step, then blocked again).
glm::vec3 steerAroundWalls(BlobWorld& world, glm::vec3 anchor, glm::vec3 heading, float radius) {
  BlobTarget& t = world.target;
  const ColliderSample s = sampleWalls(world, -1, anchor + heading * radius);
  if (!s.valid || s.distance >= radius || std::abs(s.normal.y) > 0.7f) return heading;
  glm::vec3 n(s.normal.x, 0.0f, s.normal.z);
  n = glm::normalize(n);
  const float into = glm::dot(heading, n);
  if (into >= 0.0f) return heading;
  const glm::vec3 along = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), n);  // horizontal, along the wall
  if (t.steer_side == 0.0f) t.steer_side = glm::dot(heading, along) >= 0.0f ? 1.0f : -1.0f;
  return t.steer_side * along;
}

template <class T>
void checkRange(std::ostringstream& err, const std::string& where, const char* key, T value, T lo, T hi) {
  if (!err.str().empty()) return;
  if (!(value >= lo && value <= hi))
    err << "blob: " << where << ": " << key << " = " << value << " is outside [" << lo << ", " << hi << "]";
}

}  // namespace

bool parseBlobBehaviour(const std::string& name, BlobBehaviourKind& out) {
  for (const Names& e : kBehaviours)
    if (name == e.name) {
      out = e.kind;
      return true;
    }
  return false;
}
const char* blobBehaviourName(BlobBehaviourKind kind) {
  for (const Names& e : kBehaviours)
    if (kind == e.kind) return e.name;
  return "?";
}
bool parseBlobTrigger(const std::string& name, BlobTriggerKind& out) {
  for (const TriggerNames& e : kTriggers)
    if (name == e.name) {
      out = e.kind;
      return true;
    }
  return false;
}
const char* blobTriggerName(BlobTriggerKind kind) {
  for (const TriggerNames& e : kTriggers)
    if (kind == e.kind) return e.name;
  return "?";
}

BlobStatus validateBlobProgram(BlobProgram& program, const BlobParams& params) {
  std::ostringstream err;
  if (program.states.empty()) return {"blob: the program has no states"};
  auto find = [&](const std::string& name) {
    for (std::size_t s = 0; s < program.states.size(); ++s)
      if (program.states[s].name == name) return static_cast<int>(s);
    return -1;
  };
  for (std::size_t s = 0; s < program.states.size(); ++s) {
    BlobState& st = program.states[s];
    const std::string where = "state '" + st.name + "'";
    if (st.name.empty()) return {"blob: state " + std::to_string(s) + " has no name"};
    if (find(st.name) != static_cast<int>(s)) return {"blob: " + where + " is defined twice"};
    const BlobBehaviour& b = st.behaviour;
    if (!isFinite(b.point)) return {"blob: " + where + ": point is not finite"};
    checkRange(err, where, "height", b.height, 0.0f, 100.0f);
    checkRange(err, where, "speed", b.speed, 1e-3f, 100.0f);
    checkRange(err, where, "weight", b.weight, 0.0f, 4.0f);
    checkRange(err, where, "tentacles", b.tentacles, 1, 16);
    checkRange(err, where, "tentacle_particles", b.tentacle_particles, 0, 256);
    checkRange(err, where, "tentacle_length", b.tentacle_length, 0.01f, 50.0f);
    checkRange(err, where, "tentacle_spread", b.tentacle_spread, 0.0f, 1.5f);
    checkRange(err, where, "tip_strength", b.tip_strength, 0.05f, 1.0f);
    checkRange(err, where, "tip_radius_scale", b.tip_radius_scale, 0.1f, 1.0f);
    checkRange(err, where, "wall_collider", b.wall_collider, -1, 1 << 20);
    checkRange(err, where, "catch_distance", b.catch_distance, 0.0f, 100.0f);
    checkRange(err, where, "reach_range", b.reach_range, 0.0f, 100.0f);
    checkRange(err, where, "grow_speed", b.grow_speed, 1e-3f, 100.0f);
    checkRange(err, where, "curl", b.curl, 0.0f, 1.0f);
    checkRange(err, where, "stretch", b.stretch, 0.0f, 2.0f);
    if (!err.str().empty()) return {err.str()};
    const bool has_tentacles =
        b.kind == BlobBehaviourKind::tentacles || (b.kind == BlobBehaviourKind::chase && b.reach_range > 0.0f);
    if (has_tentacles &&
        static_cast<std::size_t>(b.tentacles * tentacleParticles(b, params)) * 2 > params.particle_count)
      return {"blob: " + where +
              ": tentacles x tentacle particles = " + std::to_string(b.tentacles * tentacleParticles(b, params)) +
              " is more than half of particle_count = " + std::to_string(params.particle_count)};
    for (std::size_t k = 0; k < st.triggers.size(); ++k) {
      BlobTrigger& tr = st.triggers[k];
      const std::string twhere = where + " trigger " + std::to_string(k) + " (" + blobTriggerName(tr.kind) + ")";
      tr.next_index = find(tr.next);
      if (tr.next_index < 0) return {"blob: " + twhere + ": next = '" + tr.next + "' names no state"};
      checkRange(err, twhere, "value", tr.value, 0.0f, 1e6f);
      if (!err.str().empty()) return {err.str()};
      if (tr.kind == BlobTriggerKind::event && tr.event.empty()) return {"blob: " + twhere + ": event is empty"};
    }
  }
  program.initial_index = program.initial.empty() ? 0 : find(program.initial);
  if (program.initial_index < 0) return {"blob: initial = '" + program.initial + "' names no state"};
  return {};
}

void startBlobBehaviour(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target) {
  BlobTarget& t = world.target;
  BlobParticles& parts = world.particles;
  const std::size_t n = parts.size();
  const glm::quat keep_rotation = t.rotation;
  t = BlobTarget{};
  t.offset = parts.rest;
  t.weight.assign(n, b.weight);
  t.anchor = blobCentroid(parts.position);
  clearTexturing(parts);
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  switch (b.kind) {
    case BlobBehaviourKind::idle:
      // Müller 2005 as published: the original shape, best rotation, translation to the centroid.
      t.rotation = keep_rotation;
      break;
    case BlobBehaviourKind::reassemble:
      // As idle, but after a blast each particle is given the rest slot that matches where it is
      // now (rankMatch), not the one it had: a droplet that landed on the far side fills the far
      // side, and no particle has to push through the body to reach its old place.
      matchShape(world, all, parts.rest);
      break;
    case BlobBehaviourKind::ball: {
      const std::vector<glm::vec3> ball = blobLatticeShape(n, world.params.spacing, glm::vec3(1.0f));
      matchShape(world, all, ball);
      // Stand the ball on the body's lowest point: centred on the centroid of a flattened body
      // resting on the ground it would start half sunk into the ground and stay squashed.
      float low = 1e30f, bottom = 0.0f;
      for (const glm::vec3& x : parts.position) low = std::min(low, x.y);
      for (const glm::vec3& q : ball) bottom = std::min(bottom, q.y);
      t.anchor.y = std::max(t.anchor.y, low - bottom);
      t.anchor_at_centroid = false;
      break;
    }
    case BlobBehaviourKind::emerge:
      matchShape(world, all, parts.rest);
      t.anchor_at_centroid = false;
      t.rotate = false;
      break;
    case BlobBehaviourKind::chase:
      // Hunting: the core keeps the rest shape's proportions (the flattened ellipsoid of initBlob)
      // while tentacles reach out of it.
      if (b.reach_range > 0.0f)
        startTentacles(world, b, target, glm::vec3(1.2f, 0.75f, 1.2f));
      else
        matchShape(world, all, parts.rest);
      t.anchor_at_centroid = false;
      t.rotate = false;
      t.shape_offset = t.offset;
      break;
    case BlobBehaviourKind::tentacles:
      startTentacles(world, b, target, glm::vec3(1.0f));
      break;
    case BlobBehaviourKind::coat_wall:
      startCoatWall(world, b);
      break;
  }
}

void updateBlobBehaviour(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target, float dt) {
  BlobTarget& t = world.target;
  const glm::vec3 c = blobCentroid(world.particles.position);
  t.anchor_velocity = glm::vec3(0.0f);
  const float radius = blobBodyRadius(world.params);
  if (b.kind == BlobBehaviourKind::emerge) {
    // Rise straight up over the grate at `speed`, at most one body radius ahead of the body.
    const float height = b.height > 0.0f ? b.height : radius;
    const glm::vec3 goal = b.point + glm::vec3(0.0f, height, 0.0f);
    glm::vec3 next = glm::vec3(goal.x, t.anchor.y, goal.z);
    if (next.y < goal.y && t.anchor.y - c.y < radius) next.y = std::min(goal.y, next.y + b.speed * dt);
    t.anchor_velocity = (next - t.anchor) / dt;
    t.anchor = next;
  } else if (b.kind == BlobBehaviourKind::chase) {
    // Over the ground toward the target: the anchor leads the body horizontally by at most a
    // quarter radius along the heading, so the body's own speed is `speed`; vertically it rests on
    // the ground.
    glm::vec3 to = target - t.anchor;
    to.y = 0.0f;
    const float dist = glm::length(to);
    glm::vec3 lead = t.anchor - c;
    lead.y = 0.0f;
    glm::vec3 next = t.anchor;
    // The lead is measured along the heading only: reaching tentacles carry mass toward the target and
    // put the centroid ahead of the anchor, which must not read as the body lagging behind it.
    if (dist > 1e-6f && std::isfinite(dist) && glm::dot(lead, to / dist) < 0.25f * radius)
      next += steerAroundWalls(world, t.anchor, to / dist, radius) * std::min(dist, b.speed * dt);
    // The street's edges: the anchor stays a body radius inside the keep box, so the body follows
    // the player to the edge of the street and no further.
    for (int axis : {0, 2})
      if (world.keep_min[axis] + radius <= world.keep_max[axis] - radius)
        next[axis] = std::clamp(next[axis], world.keep_min[axis] + radius, world.keep_max[axis] - radius);
    // Vertically the anchor follows the core (the tentacles reaching up for the player's eye would
    // otherwise lift the centroid, the anchor with it, and the body would float up at the player),
    // rising at most kClimb: enough to get onto a kerb, not to levitate.
    constexpr float kClimb = 0.2f;  // m/s
    glm::vec3 core(0.0f);
    std::size_t core_count = 0;
    for (std::size_t i = 0; i < world.particles.size(); ++i)
      if (world.particles.tentacle[i] < 0) core += world.particles.position[i], ++core_count;
    const float core_y = core_count > 0 ? core.y / static_cast<float>(core_count) : c.y;
    next.y = std::min(core_y, t.anchor.y + kClimb * dt);
    t.anchor_velocity = (next - t.anchor) / dt;
    t.anchor_velocity.y = 0.0f;
    t.anchor = next;
    if (b.stretch > 0.0f && t.shape_offset.size() == world.particles.size()) stretchCore(world, b, dt);
    if (!t.tentacle_particles.empty()) layTentacles(world, b, target, dt);
  } else if (b.kind == BlobBehaviourKind::tentacles) {
    layTentacles(world, b, target, dt);
  }
}

std::vector<float> blobTentacleReach(const BlobWorld& world) {
  const BlobTarget& t = world.target;
  std::vector<float> out;
  for (std::size_t k = 0; k < t.tentacle_particles.size(); ++k) {
    const auto& chain = t.tentacle_particles[k];
    out.push_back(chain.empty() ? 0.0f : glm::length(world.particles.position[chain.back()] - t.tentacle_base[k]));
  }
  return out;
}

std::vector<float> blobTentacleAimAngles(const BlobWorld& world, glm::vec3 target) {
  const BlobTarget& t = world.target;
  std::vector<float> out;
  for (std::size_t k = 0; k < t.tentacle_particles.size(); ++k) {
    const auto& chain = t.tentacle_particles[k];
    if (chain.empty()) continue;
    const glm::vec3 axis = world.particles.position[chain.back()] - t.tentacle_base[k];
    const glm::vec3 to = target - t.tentacle_base[k];
    const float la = glm::length(axis), lt = glm::length(to);
    const float cosine = la > 1e-9f && lt > 1e-9f ? glm::dot(axis, to) / (la * lt) : 1.0f;
    out.push_back(std::acos(std::clamp(cosine, -1.0f, 1.0f)));
  }
  return out;
}

std::vector<float> blobTentacleTipDistances(const BlobWorld& world, glm::vec3 target) {
  std::vector<float> out;
  for (const auto& chain : world.target.tentacle_particles)
    if (!chain.empty()) out.push_back(glm::length(target - world.particles.position[chain.back()]));
  return out;
}

float blobCoreAspect(const BlobWorld& world, glm::vec3 heading) {
  const BlobParticles& p = world.particles;
  glm::dvec3 c(0.0);
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.tentacle[i] < 0) c += glm::dvec3(p.position[i]), ++n;
  if (n == 0) return 0.0f;
  c /= static_cast<double>(n);
  double along = 0.0, up = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.tentacle[i] >= 0) continue;
    const glm::dvec3 r = glm::dvec3(p.position[i]) - c;
    along += glm::dot(r, glm::dvec3(heading)) * glm::dot(r, glm::dvec3(heading));
    up += r.y * r.y;
  }
  return up > 0.0 ? static_cast<float>(std::sqrt(along / up)) : 0.0f;
}

float blobFractionNearWall(const BlobWorld& world, int wall_collider, float band) {
  const auto& x = world.particles.position;
  if (x.empty()) return 0.0f;
  std::size_t near = 0;
  for (const glm::vec3& p : x) {
    const ColliderSample s = sampleWalls(world, wall_collider, p);
    near += s.valid && std::abs(s.distance) <= band;
  }
  return static_cast<float>(near) / static_cast<float>(x.size());
}

bool blobGoalReached(const BlobWorld& world, const BlobBehaviour& b, glm::vec3 target) {
  const auto& x = world.particles.position;
  const glm::vec3 c = blobCentroid(x);
  const float radius = blobBodyRadius(world.params);
  switch (b.kind) {
    case BlobBehaviourKind::idle:
      return false;
    case BlobBehaviourKind::emerge:
      return c.y - b.point.y >= (b.height > 0.0f ? b.height : radius);
    case BlobBehaviourKind::ball:
      return blobSphericity(x) >= 0.9f;
    case BlobBehaviourKind::tentacles: {
      const std::vector<float> reach = blobTentacleReach(world);
      if (reach.empty()) return false;
      for (std::size_t k = 0; k < reach.size(); ++k)
        if (reach[k] < 0.8f * world.target.tentacle_length[k]) return false;
      return true;
    }
    case BlobBehaviourKind::coat_wall:
      return blobFractionNearWall(world, b.wall_collider, world.params.spacing) >= 0.8f;
    case BlobBehaviourKind::chase: {
      const glm::vec2 gap(target.x - c.x, target.z - c.z);  // the player's eye is above the goo
      return glm::length(gap) <= b.catch_distance;
    }
    case BlobBehaviourKind::reassemble:
      return blobShapeError(x, world.target.offset) <= 0.1f * radius;
  }
  return false;
}

void enterBlobState(const BlobProgram& program, BlobMachine& machine, BlobWorld& world, int index, glm::vec3 target) {
  if (index < 0 || index >= static_cast<int>(program.states.size())) return;
  machine.state = index;
  machine.time_in_state = 0.0f;
  ++machine.transitions;
  startBlobBehaviour(world, program.states[index].behaviour, target);
}

void stepBlobMachine(const BlobProgram& program, BlobMachine& machine, BlobWorld& world, const BlobInputs& inputs) {
  const float dt = world.params.step;
  auto enter = [&](int s) { enterBlobState(program, machine, world, s, inputs.target); };
  if (machine.state < 0) enter(std::max(program.initial_index, 0));
  const BlobState& st = program.states[machine.state];
  const glm::vec3 c = blobCentroid(world.particles.position);
  for (const BlobTrigger& tr : st.triggers) {
    bool fire = false;
    switch (tr.kind) {
      case BlobTriggerKind::after_seconds:
        fire = machine.time_in_state >= tr.value;
        break;
      case BlobTriggerKind::goal_reached:
        fire = blobGoalReached(world, st.behaviour, inputs.target);
        break;
      case BlobTriggerKind::target_within:
        fire = glm::length(inputs.target - c) < tr.value;
        break;
      case BlobTriggerKind::target_beyond:
        fire = glm::length(inputs.target - c) > tr.value;
        break;
      case BlobTriggerKind::blasted:
        fire = inputs.blasted;
        break;
      case BlobTriggerKind::event:
        fire = std::find(inputs.events.begin(), inputs.events.end(), tr.event) != inputs.events.end();
        break;
    }
    if (fire && tr.next_index >= 0) {
      enter(tr.next_index);
      break;
    }
  }
  updateBlobBehaviour(world, program.states[machine.state].behaviour, inputs.target, dt);
  machine.time_in_state += dt;
}

}  // namespace fluid
