// The blob's particle body: shape-matching goal springs + Akinci cohesion, collisions, blasts,
// and the measurements. See fluid/blob/blob.hpp for the model and the papers.
#include "fluid/blob/blob.hpp"

#include "fluid/core/finite.hpp"
#include "fluid/core/parallel.hpp"
#include "fluid/core/splitmix.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>
#include <sstream>

namespace fluid {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr std::size_t kGrain = 256;

glm::vec3 randomDirection(std::uint64_t seed, std::uint64_t key) {
  const float z = 2.0f * unitFloat(splitmix64(seed ^ (key * 2 + 1))) - 1.0f;
  const float a = 2.0f * kPi * unitFloat(splitmix64(seed ^ (key * 2 + 2)));
  const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {s * std::cos(a), s * std::sin(a), z};
}

void setIdleTarget(BlobWorld& world) {
  BlobTarget& t = world.target;
  t = BlobTarget{};
  t.offset = world.particles.rest;
  t.weight.assign(world.particles.size(), 0.6f);
  t.anchor_at_centroid = true;
  t.rotate = true;
}

void resetTexturing(BlobParticles& p) {
  const std::size_t n = p.size();
  p.tangent.assign(n, glm::vec3(0.0f, 1.0f, 0.0f));
  p.normal.assign(n, glm::vec3(1.0f, 0.0f, 0.0f));
  p.length_coord.assign(n, -1.0f);
  p.strength.assign(n, 1.0f);
  p.radius_scale.assign(n, 1.0f);
  p.tentacle.assign(n, -1);
}

// Goal of every particle for the current target (Müller 2005 shape matching, g_i = c + R q_i, with our anchor).
void computeGoals(BlobWorld& world, glm::vec3& goal_velocity) {
  BlobTarget& t = world.target;
  const auto& x = world.particles.position;
  const std::size_t n = x.size();
  auto& goal = world.scratch.goal;
  goal.resize(n);
  glm::vec3 centre = t.anchor;
  glm::vec3 offset_mean(0.0f);
  goal_velocity = t.anchor_velocity;
  if (t.anchor_at_centroid) {
    centre = blobCentroid(x);
    offset_mean = blobCentroid(t.offset);
    goal_velocity = blobCentroid(world.particles.velocity);
  }
  glm::mat3 rot(1.0f);
  if (t.rotate) {
    // The fit is about the centroid whatever the anchor: R only says how the body has turned.
    t.rotation = blobBestRotation(x, t.offset, t.rotation, 4);
    rot = glm::mat3_cast(t.rotation);
  }
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) goal[i] = centre + rot * (t.offset[i] - offset_mean);
  });
}

void computeAccelerations(BlobWorld& world, glm::vec3 goal_velocity) {
  const BlobParams& p = world.params;
  const BlobParticles& parts = world.particles;
  const BlobTarget& t = world.target;
  BlobScratch& s = world.scratch;
  const std::size_t n = parts.size();
  const float d = p.spacing;
  const float h = p.cohesion_radius * d;
  const float h2 = h * h;
  s.accel.resize(n);
  // Goal springs (Müller 2005), applied as forces.
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const float w = t.weight[i];
      glm::vec3 delta = s.goal[i] - parts.position[i];
      const float len = glm::length(delta);
      // Beyond goal_reach the pull is constant and the damping fades out (gone at twice the
      // reach): a droplet blown off flies ballistically and falls back, instead of being held
      // by a spring that would stop it at once and pull it back at any speed.
      const float fade = std::clamp(2.0f - len / p.goal_reach, 0.0f, 1.0f);
      if (len > p.goal_reach) delta *= p.goal_reach / len;
      s.accel[i] = w * (p.goal_stiffness * delta + fade * p.goal_damping * (goal_velocity - parts.velocity[i]));
    }
  });
  if (t.anchor_at_centroid) {
    // Shape matching about the centroid changes the shape, never the momentum: the linear goal
    // springs sum to zero by construction, the saturation and the fade do not, so their net
    // (serial, index order) is taken back from every particle. A crate's impulse is then exactly
    // what the body gains (tests/blob: CrateImpulseBalancesTheParticlesMomentum).
    glm::dvec3 net(0.0);
    for (std::size_t i = 0; i < n; ++i) net += glm::dvec3(s.accel[i]);
    const glm::vec3 mean(net / static_cast<double>(n));
    for (std::size_t i = 0; i < n; ++i) s.accel[i] -= mean;
  }
  // Pair forces. Positions with the radius scale and velocities as 16-byte records: one load
  // per neighbour and array (the pair loop is ~70 % of a step, bench_blob under perf).
  s.pos4.resize(n);
  s.vel4.resize(n);
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      s.pos4[i] = glm::vec4(parts.position[i], parts.radius_scale[i]);
      s.vel4[i] = glm::vec4(parts.velocity[i], 0.0f);
    }
  });
  // Akinci et al. 2013: the cohesion spline C(r) divided by its peak C(h/2) = h^6/64 (the
  // 32/(pi h^9) factor cancels), so BlobParams::cohesion is the peak acceleration between two
  // particles; below r ~ 0.27 h it turns into a weak repulsion, the contact spring does the rest.
  const float h6 = h2 * h2 * h2;
  const float c_scale = 64.0f / h6;
  const float c_offset = h6 / 64.0f;
  const float half_d = 0.5f * d;
  const float eps2 = 1e-12f * d * d;
  par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const glm::vec4 xi = s.pos4[i];
      const glm::vec4 vi = s.vel4[i];
      glm::vec3 a = s.accel[i] + p.gravity - p.drag * glm::vec3(vi);
      // The monster holds itself up where it follows a goal (external, like muscles on the ground).
      a -= std::min(t.weight[i], 1.0f) * p.support * p.gravity;
      for (std::uint32_t k = s.neighbors.offsets[i]; k < s.neighbors.offsets[i + 1]; ++k) {
        const std::uint32_t j = s.neighbors.indices[k];
        const glm::vec4 xj = s.pos4[j];
        const glm::vec3 rv = glm::vec3(xi) - glm::vec3(xj);
        const float r2 = glm::dot(rv, rv);
        if (r2 >= h2) continue;  // a Verlet-list candidate beyond the support
        // Coincident particles (a blast can stack them): a fixed, antisymmetric direction so
        // the pair separates without NaN and momentum stays balanced.
        glm::vec3 nrm;
        float dist;
        float cohesion_shape = 0.0f;
        if (r2 > eps2) {
          dist = std::sqrt(r2);
          nrm = rv * (1.0f / dist);
          const float hr = h - dist;
          const float v = hr * hr * hr * r2 * dist;
          cohesion_shape = (2.0f * dist > h ? v : 2.0f * v - c_offset) * c_scale;
        } else {
          dist = 0.0f;
          nrm = i < j ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(0.0f, -1.0f, 0.0f);
        }
        // Akinci 2013 cohesion force per unit mass, contact spring, damping of the
        // relative normal velocity: one scalar along the pair's axis.
        float f = -p.cohesion * cohesion_shape;
        const float contact = half_d * (xi.w + xj.w);
        if (dist < contact) f += p.repulsion * (contact - dist);
        f -= p.pair_damping * glm::dot(glm::vec3(vi) - glm::vec3(s.vel4[j]), nrm);
        a += f * nrm;
      }
      s.accel[i] = a;
    }
  });
}

// Collisions of the predicted positions with every collider (Kolb 2004 §3.3.2 double check, swept
// every max_step so a fast particle cannot cross a thin wall: fluid::collideParticles) and the
// momentum each collider took from the particles (the game applies it to its rigid body).
void collide(BlobWorld& world, std::span<glm::vec3> predicted, float dt, BlobStepStats& stats) {
  const BlobParams& p = world.params;
  BlobScratch& s = world.scratch;
  auto& v = world.particles.velocity;
  const std::size_t n = predicted.size();
  const float mass = blobParticleMass(p);
  CollideDesc desc;
  desc.dt = dt;
  desc.skin = 0.01f * p.spacing;
  desc.max_step = 0.125f * p.spacing;
  desc.parallel.grain = kGrain;
  for (const bool level : {false, true})  // crates before the level (BlobCollider)
    for (BlobCollider& c : world.colliders) {
      if (!c.shape || c.level != level) continue;
      desc.material = c.use_blob_material ? p.material : c.material;
      desc.bounded = c.bounded;
      desc.inside = {c.inside_lo, c.inside_hi};
      s.before.assign(v.begin(), v.end());
      const CollideCounts counts = collideParticles(*c.shape, c.pose, s.previous, predicted, v, desc, s.collide);
      stats.collisions += counts.reacted + counts.pushed_out;
      stats.swept += counts.swept;
      // Serial, in index order: the sums are the same for every thread count.
      for (std::size_t i = 0; i < n; ++i) {
        if (s.collide.outcome[i] == CollisionOutcome::none) continue;
        // Momentum the collider's reaction gave the particle (a push-out moves it without changing it).
        const glm::vec3 dp = mass * (v[i] - s.before[i]);
        c.impulse -= dp;
        c.angular_impulse -= glm::cross(predicted[i] - c.pose.translation, dp);
      }
    }
}

void advanceColliderPoses(BlobWorld& world, float dt) {
  for (BlobCollider& c : world.colliders) {
    c.pose.translation += c.pose.linear_velocity * dt;
    const float w = glm::length(c.pose.angular_velocity);
    if (w > 0.0f)
      c.pose.rotation = glm::normalize(glm::angleAxis(w * dt, c.pose.angular_velocity / w) * c.pose.rotation);
  }
}

template <class T>
void checkRange(std::ostringstream& err, const char* name, T value, T lo, T hi) {
  if (!err.str().empty()) return;
  if (!(value >= lo && value <= hi))
    err << "blob: " << name << " = " << value << " is outside [" << lo << ", " << hi << "]";
}

}  // namespace

namespace {

// The map-coordinate box where a front_back16 map can cast a negative ("inside") vote: over its
// texels that vote at all (not background, not margin ring), the texel's footprint and the depths
// between its front and back surface (to the near / far plane where one of them is background).
// Empty (lo > hi) when no texel can. depth_map.cpp: a LESS vote is negative only for q.z in
// (front, 1], a GREATER vote only for q.z in [0, back); margin-ring texels vote into the fallback
// winner, which is never inside.
void frontBackInsideBox(const DepthMap& map, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(INFINITY), hi = glm::vec3(-INFINITY);
  const std::uint32_t n = map.resolution;
  const float inv_n = 1.0f / static_cast<float>(n);
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint8_t* t = map.texels.data() + (static_cast<std::size_t>(j) * n + i) * 8;
      std::uint16_t front_bits, back_bits;
      std::memcpy(&front_bits, t + 4, 2);
      std::memcpy(&back_bits, t + 6, 2);
      const float front = halfToFloat(front_bits), back = halfToFloat(back_bits);
      if (map.margin_ring && front_bits == back_bits && front >= 0.0f) continue;
      if (front < 0.0f && back < 0.0f) continue;
      const float z_lo = front >= 0.0f ? front : 0.0f, z_hi = back >= 0.0f ? back : 1.0f;
      lo = glm::min(lo, glm::vec3(static_cast<float>(i) * inv_n, static_cast<float>(j) * inv_n, z_lo));
      hi = glm::max(hi, glm::vec3(static_cast<float>(i + 1) * inv_n, static_cast<float>(j + 1) * inv_n, z_hi));
    }
}

}  // namespace

void blobDepthMapBounds(BlobCollider& c, const DepthMapCollider& shape) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const DepthMap& map : shape.maps()) {
    // Map-coordinate box of the map's possible inside votes: front_back16 from its texels, other
    // ortho maps their whole volume [0, 1]^3, cube maps theirs [-1, 1]^3.
    glm::vec3 q_lo(map.format == DepthMapFormat::cube8 ? -1.0f : 0.0f), q_hi(1.0f);
    if (map.format == DepthMapFormat::front_back16 &&
        map.texels.size() == static_cast<std::size_t>(map.resolution) * map.resolution * 8) {
      frontBackInsideBox(map, q_lo, q_hi);
      if (q_lo.x > q_hi.x) continue;  // this map never votes inside
    }
    const glm::mat4 to_collider = glm::inverse(map.collider_to_map);
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 corner((k & 1) ? q_hi.x : q_lo.x, (k & 2) ? q_hi.y : q_lo.y, (k & 4) ? q_hi.z : q_lo.z);
      const glm::vec4 q = to_collider * glm::vec4(corner, 1.0f);
      const glm::vec3 x = glm::vec3(q) / q.w;
      lo = glm::min(lo, x), hi = glm::max(hi, x);
    }
  }
  c.bounded = isFinite(lo) && isFinite(hi) && glm::all(glm::lessThanEqual(lo, hi));
  if (!c.bounded) {
    // No map can vote inside (or none at all): nothing is ever inside, an empty box.
    c.bounded = !shape.maps().empty() && !isFinite(lo);
    c.inside_lo = glm::vec3(INFINITY), c.inside_hi = glm::vec3(-INFINITY);
    return;
  }
  const glm::vec3 pad = glm::vec3(1e-3f) + 1e-4f * (hi - lo);
  c.inside_lo = lo - pad;
  c.inside_hi = hi + pad;
}

float blobBodyRadius(const BlobParams& p) {
  return std::cbrt(3.0f * static_cast<float>(p.particle_count) / (4.0f * kPi)) * p.spacing;
}

std::vector<glm::vec3> blobLatticeShape(std::size_t count, float spacing, glm::vec3 shape) {
  // Ellipsoid radii with the volume of the ball of `count` particles.
  const float ball = std::cbrt(3.0f * static_cast<float>(count) / (4.0f * kPi)) * spacing;
  const glm::vec3 radii = ball * shape / std::cbrt(shape.x * shape.y * shape.z);
  const int k = static_cast<int>(std::ceil(std::max({radii.x, radii.y, radii.z}) / spacing)) + 2;
  struct Candidate {
    float score;
    glm::vec3 point;
  };
  std::vector<Candidate> lattice;
  for (int z = -k; z <= k; ++z)
    for (int y = -k; y <= k; ++y)
      for (int x = -k; x <= k; ++x) {
        const glm::vec3 q = glm::vec3(x, y, z) * spacing;
        lattice.push_back({glm::length(q / radii), q});
      }
  // Stable: ties keep the generation order, so the shape is the same on every platform.
  std::stable_sort(lattice.begin(), lattice.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
  std::vector<glm::vec3> out(count);
  for (std::size_t i = 0; i < count; ++i) out[i] = lattice[i].point;
  const glm::vec3 mean = blobCentroid(out);
  for (glm::vec3& q : out) q -= mean;
  return out;
}

BlobStatus validateBlobParams(const BlobParams& p) {
  std::ostringstream err;
  checkRange<std::size_t>(err, "particle_count", p.particle_count, 1, 65536);
  checkRange(err, "spacing", p.spacing, 0.005f, 1.0f);
  checkRange(err, "density", p.density, 1e-3f, 1e5f);
  checkRange(err, "step", p.step, 1e-4f, 0.1f);
  checkRange(err, "substeps", p.substeps, 1, 64);
  checkRange(err, "cohesion", p.cohesion, 0.0f, 1e5f);
  checkRange(err, "cohesion_radius", p.cohesion_radius, 1.1f, 3.0f);
  checkRange(err, "repulsion", p.repulsion, 0.0f, 1e6f);
  checkRange(err, "pair_damping", p.pair_damping, 0.0f, 1e3f);
  checkRange(err, "goal_stiffness", p.goal_stiffness, 0.0f, 1e5f);
  checkRange(err, "goal_damping", p.goal_damping, 0.0f, 1e3f);
  checkRange(err, "goal_reach", p.goal_reach, 1e-3f, 100.0f);
  checkRange(err, "support", p.support, 0.0f, 1.0f);
  checkRange(err, "drag", p.drag, 0.0f, 100.0f);
  checkRange(err, "max_speed", p.max_speed, 1e-3f, 1e4f);
  if (err.str().empty() && !isFinite(p.gravity)) err << "blob: gravity is not finite";
  return {err.str()};
}

BlobStatus initBlob(BlobWorld& world, glm::vec3 centre, glm::vec3 shape) {
  BlobStatus st = validateBlobParams(world.params);
  if (!st.ok()) return st;
  if (!isFinite(centre) || !isFinite(shape) || !(std::min({shape.x, shape.y, shape.z}) > 0.0f))
    return {"blob: initBlob needs a finite centre and positive shape ratios"};
  const BlobParams& p = world.params;
  const std::size_t n = p.particle_count;
  const float d = p.spacing;
  BlobParticles& parts = world.particles;
  parts.rest = blobLatticeShape(n, d, shape);
  for (std::size_t i = 0; i < n; ++i) parts.rest[i] += 0.01f * d * randomDirection(p.seed, i);
  const glm::vec3 mean = blobCentroid(parts.rest);
  for (glm::vec3& q : parts.rest) q -= mean;
  parts.position.resize(n);
  for (std::size_t i = 0; i < n; ++i) parts.position[i] = centre + parts.rest[i];
  parts.velocity.assign(n, glm::vec3(0.0f));
  resetTexturing(parts);
  setIdleTarget(world);
  world.time = 0.0;
  world.steps = 0;
  return {};
}

BlobStatus placeBlob(BlobWorld& world, std::span<const glm::vec3> positions) {
  BlobParticles& parts = world.particles;
  if (positions.size() != parts.size())
    return {"blob: placeBlob got " + std::to_string(positions.size()) + " positions for " +
            std::to_string(parts.size()) + " particles"};
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!isFinite(positions[i])) return {"blob: placeBlob position " + std::to_string(i) + " is not finite"};
  parts.position.assign(positions.begin(), positions.end());
  parts.velocity.assign(parts.size(), glm::vec3(0.0f));
  return {};
}

std::vector<glm::vec3> blobColumn(const BlobParams& params, glm::vec3 top, float radius) {
  const float d = params.spacing;
  const float r = 0.5f * d;
  const float reach = std::max(radius - r, 0.0f);
  const int k = static_cast<int>(std::floor(reach / d));
  std::vector<glm::vec2> layer;
  for (int z = -k; z <= k; ++z)
    for (int x = -k; x <= k; ++x)
      if (glm::length(glm::vec2(x, z) * d) <= reach) layer.push_back(glm::vec2(x, z) * d);
  if (layer.empty()) layer.push_back(glm::vec2(0.0f));
  std::vector<glm::vec3> out;
  out.reserve(params.particle_count);
  for (std::size_t i = 0; out.size() < params.particle_count; ++i) {
    const float y = top.y - r - static_cast<float>(i / layer.size()) * d;
    const glm::vec2 q = layer[i % layer.size()];
    out.push_back({top.x + q.x, y, top.z + q.y});
  }
  return out;
}

BlobStatus stepBlob(BlobWorld& world, BlobStepStats* stats_out) {
  const auto start = std::chrono::steady_clock::now();
  const BlobParams& p = world.params;
  BlobParticles& parts = world.particles;
  BlobScratch& s = world.scratch;
  const std::size_t n = parts.size();
  for (std::size_t i = 0; i < n; ++i)
    if (!isFinite(parts.position[i]) || !isFinite(parts.velocity[i]))
      return {"blob: particle " + std::to_string(i) + " has a non-finite position or velocity at step " +
              std::to_string(world.steps)};
  if (world.target.offset.size() != n || world.target.weight.size() != n)
    return {"blob: the target has " + std::to_string(world.target.offset.size()) + " offsets for " + std::to_string(n) +
            " particles"};
  BlobStepStats stats;
  for (BlobCollider& c : world.colliders) c.impulse = c.angular_impulse = glm::vec3(0.0f);
  const float dt = p.step / static_cast<float>(p.substeps);
  const float h = p.cohesion_radius * p.spacing;
  // Verlet lists (Verlet 1967): neighbours within h + skin, rebuilt only when some particle has
  // moved more than skin / 2 since the last build, so no pair within h is ever missed. Most steps
  // search once instead of once per sub-step (the search was 30 % of a step, bench_blob).
  const float skin = 0.25f * p.spacing;
  for (int sub = 0; sub < p.substeps; ++sub) {
    bool rebuild = !s.verlet_valid || s.verlet_position.size() != n;
    for (std::size_t i = 0; i < n && !rebuild; ++i) {
      const glm::vec3 moved = parts.position[i] - s.verlet_position[i];
      rebuild = glm::dot(moved, moved) > 0.25f * skin * skin;
    }
    if (rebuild) {
      buildNeighborGrid(s.grid, parts.position, (h + skin) * 1.002f);
      findNeighbors(s.grid, parts.position, h + skin, s.neighbors);
      s.verlet_position.assign(parts.position.begin(), parts.position.end());
      s.verlet_valid = true;
    }
    glm::vec3 goal_velocity;
    computeGoals(world, goal_velocity);
    computeAccelerations(world, goal_velocity);
    s.previous.assign(parts.position.begin(), parts.position.end());
    par::parallelFor(par::Range<std::size_t>(0, n, kGrain), [&](const par::Range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        glm::vec3 v = parts.velocity[i] + dt * s.accel[i];
        const float speed = glm::length(v);
        if (speed > p.max_speed) v *= p.max_speed / speed;
        parts.velocity[i] = v;
        parts.position[i] += dt * v;  // predicted; collisions correct it
      }
    });
    advanceColliderPoses(world, dt);
    collide(world, parts.position, dt, stats);
    for (glm::vec3& v : parts.velocity) {
      const float speed = glm::length(v);
      if (speed > p.max_speed) {
        v *= p.max_speed / speed;
        ++stats.clamped;
      }
    }
  }
  world.time += p.step;
  ++world.steps;
  stats.max_speed = blobMaxSpeed(parts.velocity);
  stats.step_ms = std::chrono::duration<float, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (stats_out) *stats_out = stats;
  return {};
}

std::size_t blastBlob(BlobWorld& world, const Blast& blast) {
  if (!validateBlast(blast).empty()) return 0;
  BlobParticles& parts = world.particles;
  const float r = blobParticleRadius(world.params);
  const float area_over_mass = 3.14159265f * r * r / blobParticleMass(world.params);
  const float max_speed = world.params.max_speed;
  std::size_t reached = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const glm::vec3 dv = blastVelocityChange(blast, parts.position[i], area_over_mass, max_speed);
    if (dv == glm::vec3(0.0f)) continue;
    glm::vec3 v = parts.velocity[i] + dv;
    const float len = glm::length(v);
    if (len > max_speed) v *= max_speed / len;
    parts.velocity[i] = v;
    ++reached;
  }
  return reached;
}

glm::vec3 blobCentroid(std::span<const glm::vec3> positions) {
  glm::dvec3 sum(0.0);
  for (const glm::vec3& x : positions) sum += glm::dvec3(x);
  return positions.empty() ? glm::vec3(0.0f) : glm::vec3(sum / static_cast<double>(positions.size()));
}

glm::quat blobBestRotation(std::span<const glm::vec3> positions, std::span<const glm::vec3> rest, glm::quat warm,
                           int iterations) {
  const glm::vec3 c = blobCentroid(positions);
  const glm::vec3 c0 = blobCentroid(rest);
  // A_pq = sum p_i q_i^T (Müller 2005; equal masses), accumulated in double.
  glm::dmat3 a(0.0);
  for (std::size_t i = 0; i < positions.size(); ++i)
    a += glm::outerProduct(glm::dvec3(positions[i] - c), glm::dvec3(rest[i] - c0));
  // Müller et al. 2016: rotate q by omega = sum r_i x a_i / |sum r_i . a_i| until it stops.
  glm::dquat q = glm::normalize(glm::dquat(warm));
  for (int it = 0; it < iterations; ++it) {
    const glm::dmat3 r = glm::mat3_cast(q);
    const glm::dvec3 num = glm::cross(r[0], a[0]) + glm::cross(r[1], a[1]) + glm::cross(r[2], a[2]);
    const double den = std::abs(glm::dot(r[0], a[0]) + glm::dot(r[1], a[1]) + glm::dot(r[2], a[2])) + 1e-12;
    const glm::dvec3 omega = num / den;
    const double w = glm::length(omega);
    if (!(w > 1e-12)) break;
    q = glm::normalize(glm::angleAxis(w, omega / w) * q);
  }
  return glm::quat(q);
}

float blobShapeError(std::span<const glm::vec3> positions, std::span<const glm::vec3> rest) {
  if (positions.empty() || positions.size() != rest.size()) return 0.0f;
  const glm::quat q = blobBestRotation(positions, rest, glm::quat(1.0f, 0.0f, 0.0f, 0.0f), 100);
  const glm::mat3 r = glm::mat3_cast(q);
  const glm::vec3 c = blobCentroid(positions);
  const glm::vec3 c0 = blobCentroid(rest);
  double sum = 0.0;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const glm::vec3 e = c + r * (rest[i] - c0) - positions[i];
    sum += glm::dot(e, e);
  }
  return static_cast<float>(std::sqrt(sum / static_cast<double>(positions.size())));
}

float blobSphericity(std::span<const glm::vec3> positions) {
  if (positions.size() < 4) return 0.0f;
  const glm::dvec3 c(blobCentroid(positions));
  glm::dmat3 cov(0.0);
  for (const glm::vec3& x : positions) cov += glm::outerProduct(glm::dvec3(x) - c, glm::dvec3(x) - c);
  cov /= static_cast<double>(positions.size());
  // Eigenvalues of the symmetric 3x3 matrix (Smith 1961, "Eigenvalues of a symmetric 3x3 matrix").
  const double p1 = cov[0][1] * cov[0][1] + cov[0][2] * cov[0][2] + cov[1][2] * cov[1][2];
  const double q = (cov[0][0] + cov[1][1] + cov[2][2]) / 3.0;
  const double p2 = (cov[0][0] - q) * (cov[0][0] - q) + (cov[1][1] - q) * (cov[1][1] - q) +
                    (cov[2][2] - q) * (cov[2][2] - q) + 2.0 * p1;
  const double pp = std::sqrt(p2 / 6.0);
  if (pp <= 1e-30) return 1.0f;
  const glm::dmat3 b = (cov - q * glm::dmat3(1.0)) / pp;
  const double rr = std::clamp(glm::determinant(b) / 2.0, -1.0, 1.0);
  const double phi = std::acos(rr) / 3.0;
  const double e1 = q + 2.0 * pp * std::cos(phi);
  const double e3 = q + 2.0 * pp * std::cos(phi + 2.0 * 3.14159265358979323846 / 3.0);
  return e1 > 0.0 ? static_cast<float>(std::sqrt(std::max(0.0, e3) / e1)) : 0.0f;
}

float blobMaxSpeed(std::span<const glm::vec3> velocities) {
  float m = 0.0f;
  for (const glm::vec3& v : velocities) m = std::max(m, glm::length(v));
  return m;
}

bool blobAllFinite(const BlobParticles& particles) {
  for (std::size_t i = 0; i < particles.size(); ++i)
    if (!isFinite(particles.position[i]) || !isFinite(particles.velocity[i])) return false;
  return true;
}

}  // namespace fluid
