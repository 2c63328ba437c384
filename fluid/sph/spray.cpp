// Spray: ballistic drops outside the SPH solve (spray.hpp).
#include "fluid/sph/spray.hpp"

#include "fluid/sph/boundary.hpp"
#include "fluid/sph/collisions.hpp"

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

namespace fluid::sph_step {
namespace {

// Reorders `v` by `order` (new index e holds old index order[e]) through `tmp`.
template <typename T>
void permute(std::vector<T>& v, const std::vector<std::uint32_t>& order, std::vector<T>& tmp) {
  tmp.resize(order.size());
  for (std::size_t e = 0; e < order.size(); ++e) tmp[e] = v[order[e]];
  v.swap(tmp);
}

// The spray's reactions summed per collider (the first kMaxColliders; the others get none).
constexpr std::size_t kMaxColliders = 32;
struct SprayReactions {
  ForceTorque per_collider[kMaxColliders];
  std::size_t collisions = 0;
};

// Calls f(j, r) for every SPH particle j within H of p (r = |x_j - p| < H) at its current position,
// through this step's grid (built at the step-start positions, order the identity after the
// re-sort). A particle moved at most cfl d <= H / 2 in the step (WCSPH: less, its Verlet skin), so
// every neighbour is found among the grid entries within 1.5 H of p (`reach` cells). In the
// grid's cell order, the same for any thread count.
template <typename F>
void forWaterNear(const StepContext& context, glm::vec3 p, int reach, F&& f) {
  const NeighborGrid& grid = context.scratch.grid;
  const std::vector<glm::vec3>& x = context.particles.position;
  const float h2 = context.support * context.support;
  const glm::ivec3 c = grid.cellOf(p);
  const glm::ivec3 lo = glm::max(c - reach, glm::ivec3(0)), hi = glm::min(c + reach, grid.dims - 1);
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y) {
      const std::uint32_t b = grid.cell_start[grid.keyOf({lo.x, y, z})], e = grid.cell_start[grid.keyOf({hi.x, y, z}) + 1];
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t j = grid.identity_order ? k : grid.order[k];
        const glm::vec3 q = x[j] - p;
        const float r2 = glm::dot(q, q);
        if (r2 < h2) f(j, std::sqrt(r2));
      }
    }
}

// A drop's density as water (the SPH water's and its own) may exceed rho_0 by this
// share before its rejoin waits a step (gateCrowdedRejoins). A point inside the bulk sees about
// rho_0 from the water around it and the drop's own m W(0) is about a third of that, so one drop
// rejoins inside the bulk (the solve makes room for it), where a second drop at the same place
// (another m W of up to a third) waits.
constexpr float kSprayRejoinCrowd = 0.35f;

constexpr int kCollisionPasses = 4;  // per sub-step, as the water's (resolveCollisions)

}  // namespace

bool applySprayTransitions(SphWorld& world, SphStepStats& stats) {
  ParticleStore& store = world.particles;
  SphScratch& scratch = world.scratch;
  const SphParams& params = world.params;
  const std::size_t n = store.size();
  if (params.spray_speed <= 0.0f && store.spray_count == 0) return false;
  // Kept one per particle by stepImpl, applySinks and addSphParticleWithId.
  std::vector<std::uint32_t>& last = scratch.last_neighbours;
  const std::size_t spray_begin = n - store.spray_count;
  const bool on = params.spray_speed > 0.0f;
  const float v2 = params.spray_speed * params.spray_speed;
  const std::uint32_t calm_needed = static_cast<std::uint32_t>(params.spray_neighbours);
  // Faster than a full step's CFL speed, water would shorten the step for all of it: it leaves
  // whatever its neighbours.
  const float full_step_speed = params.cfl * sphSpacing(params) / params.max_time_step;
  const float step2 = full_step_speed * full_step_speed;
  const auto staysOrBecomesSpray = [&](std::size_t i) {
    if (!on) return false;
    if (i < spray_begin) {
      const float speed2 = glm::dot(store.velocity[i], store.velocity[i]);
      return speed2 > v2 && (last[i] < calm_needed || speed2 > step2);
    }
    // advanceSpray let it back in (kJoinNeighbours); kUnknownNeighbours: never through it.
    return last[i] != SphScratch::kJoinNeighbours && last[i] != SphScratch::kUnknownNeighbours;
  };
  std::size_t left = 0, joined = 0, spray = 0;
  std::vector<std::uint32_t>& order = scratch.spray_order;
  order.resize(n);
  std::size_t front = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool is_spray = staysOrBecomesSpray(i);
    if (is_spray) {
      ++spray;
      left += i < spray_begin ? 1 : 0;
    } else {
      joined += i >= spray_begin ? 1 : 0;
      order[front++] = static_cast<std::uint32_t>(i);
    }
  }
  stats.spray_left = left;
  stats.spray_joined = joined;
  if (left == 0 && joined == 0) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (staysOrBecomesSpray(i)) order[front++] = static_cast<std::uint32_t>(i);
  // A drop that leaves the water takes no solver state with it, one that rejoins starts afresh:
  // no warm-start stiffness, no carried boundary samples (SampleCarry), densities from the next pass.
  for (std::size_t e = 0; e < n; ++e) {
    const std::uint32_t o = order[e];
    const bool was_spray = o >= spray_begin, now_spray = e >= n - spray;
    if (was_spray != now_spray) {
      scratch.warm_kappa[o] = 0.0f;
      scratch.carry.index[o] = SphScratch::SampleCarry::kNone;
    }
  }
  permute(store.position, order, scratch.vec_a);
  permute(store.velocity, order, scratch.vec_b);
  permute(store.density, order, scratch.float_tmp);
  permute(store.pressure, order, scratch.float_tmp);
  permute(scratch.warm_kappa, order, scratch.float_tmp);
  permute(store.id, order, scratch.u32_tmp);
  permute(scratch.carry.index, order, scratch.u32_tmp);
  permute(last, order, scratch.u32_tmp);
  store.spray_count = spray;
  return true;
}

namespace {

// The submerged drops' drag (SphParams::spray_water_drag), before they move: each drop in store
// order, so the water's sums are the same for any thread count. With the SPH water within H of
// the drop (its current positions, after the water's collisions) at weights W_j: the water's share
// phi = min(m sum W_j / rho_0, 1), its velocity v_w = sum W_j v_j / sum W_j, and the drop's velocity
// relative to it u. The drag F = 1/2 rho_0 C_d pi r^2 |u| u on the drop's mass rho_0 (2r)^3 gives
// du/dt = -phi k |u| u with k = C_d pi / (16 r), taken implicit in |u| over dt (stable at any
// drag): u' = u / (1 + dt phi k |u|). The water around takes the momentum the drop lost, shared
// by W_j / sum W_j (equal masses), so the pair conserves it. Writes phi per drop into
// scratch.spray_water_share.
void shareWithTheWater(StepContext& context, int reach) {
  const std::size_t begin = context.count, end = context.total;
  ParticleStore& store = context.particles;
  SphScratch& scratch = context.scratch;
  const SphParams& params = context.params;
  scratch.spray_water_share.assign(end - begin, 0.0f);
  if (context.count == 0) return;
  const float k = params.spray_water_drag * glm::pi<float>() / (16.0f * params.particle_radius);
  const float dt = context.dt, mass = context.mass;
  std::vector<std::uint32_t>& near = scratch.spray_near;
  std::vector<float>& weight = scratch.spray_near_weight;
  for (std::size_t i = begin; i < end; ++i) {
    near.clear();
    weight.clear();
    float sum_w = 0.0f;
    glm::vec3 sum_wv(0.0f);
    forWaterNear(context, store.position[i], reach, [&](std::uint32_t j, float r) {
      const float w = scratch.kernel.value(r);
      if (!(w > 0.0f)) return;
      near.push_back(j);
      weight.push_back(w);
      sum_w += w;
      sum_wv += w * store.velocity[j];
    });
    if (!(sum_w > 0.0f)) continue;
    const float phi = std::min(mass * sum_w / context.rest_density, 1.0f);
    scratch.spray_water_share[i - begin] = phi;
    if (!(k > 0.0f)) continue;
    const glm::vec3 water = sum_wv / sum_w;
    const glm::vec3 u = store.velocity[i] - water;
    const glm::vec3 change = u / (1.0f + dt * phi * k * glm::length(u)) - u;
    store.velocity[i] += change;
    for (std::size_t n = 0; n < near.size(); ++n) store.velocity[near[n]] -= change * (weight[n] / sum_w);
  }
}

// Lets back into the water, in store order, the drops advanceSpray found ready (kJoinNeighbours: slow
// on a collider; a count >= spray_neighbours: slow among calm water) while the density each would
// have as water, the SPH water's (scratch.spray_water_density), its own m W(0) and the drops let in
// before it, stays within (1 + kSprayRejoinCrowd) rho_0 (less at short steps, below), and it keeps
// half a spacing from the water and from the drops let in (nearer, it would add most of its m W(0)
// to that one particle: two drops that fell together would be one particle's place). The density
// counts no wall, so the distance rule is what holds a drop off a particle resting on the floor.
// The others stay spray (a count of 0) and try again the next step: drops bunched in the water
// (the jet's crown slowing at its apex together, a blast's sheet landing) rejoin over a few steps
// instead of starting one step at twice the rest density.
void gateCrowdedRejoins(StepContext& context) {
  const std::size_t begin = context.count, end = context.total;
  ParticleStore& store = context.particles;
  SphScratch& scratch = context.scratch;
  const std::uint32_t needed = static_cast<std::uint32_t>(context.params.spray_neighbours);
  const float mass = context.mass, support = context.support;
  const float self = mass * scratch.kernel.value(0.0f);
  // The next step's pressure solve removes a compression e within its step, as a velocity of about
  // e d / dt (Bender & Koschier 2015 §4.2: kappa ~ (rho* - rho_0) / dt^2): a rejoin may add no more
  // than turns into half of spray_speed, or the drop it let in is thrown out again as spray (at
  // spray_speed 4 m/s and d = 0.08 m: 12 % of rho_0 at 5 ms steps, 42 % at one step a frame).
  const float kick_bound = 0.5f * context.params.spray_speed * context.dt / context.spacing;
  const float limit = (1.0f + std::min(kSprayRejoinCrowd, kick_bound)) * context.rest_density;
  const float apart2 = 0.25f * context.spacing * context.spacing;
  std::vector<glm::vec3>& rejoined = scratch.rejoined;
  rejoined.clear();
  std::size_t crowded = 0;
  for (std::size_t i = begin; i < end; ++i) {
    std::uint32_t& last = scratch.last_neighbours[i];
    const bool on_collider = last == SphScratch::kJoinNeighbours;
    if (!on_collider && last < needed) continue;
    const glm::vec3 x = store.position[i];
    float density = scratch.spray_water_density[i - begin] + self;
    bool too_near = false;
    for (const glm::vec3& other : rejoined) {
      const glm::vec3 q = other - x;
      const float r2 = glm::dot(q, q);
      if (r2 >= support * support) continue;
      density += mass * scratch.kernel.value(std::sqrt(r2));
      too_near = too_near || r2 < apart2;
    }
    if (density > limit || too_near) {
      last = 0;
      ++crowded;
      continue;
    }
    last = SphScratch::kJoinNeighbours;
    rejoined.push_back(x);
  }
  context.stats.rejoins_crowded += crowded;
}

}  // namespace

void advanceSpray(StepContext& context) {
  const std::size_t begin = context.count, end = context.total;
  ParticleStore& store = context.particles;
  SphScratch& scratch = context.scratch;
  const SphParams& params = context.params;
  scratch.old_position.resize(end);
  if (begin >= end) return;
  const int reach = context.count > 0 ? neighborReach(scratch.grid, 1.5f * context.support) : 0;
  shareWithTheWater(context, reach);
  scratch.spray_water_density.resize(end - begin);
  const float dt = context.dt, mass = context.mass;
  const glm::vec3 g = params.gravity;
  // Quadratic drag a = -k |v| v with k = |g| / v_t^2, so a drop falls no faster than v_t.
  const float k = params.spray_terminal_speed > 0.0f
                      ? glm::length(g) / (params.spray_terminal_speed * params.spray_terminal_speed)
                      : 0.0f;
  const float skin = params.collision_skin > 0.0f ? params.collision_skin : 0.01f * params.particle_radius;
  const float depth_slack = params.particle_radius;
  const float max_move = 0.5f * context.spacing;
  const std::size_t colliders = context.collider_count;
  // resolveCollisions left each collider's end-of-step pose in the carry.
  const std::vector<ColliderPose>& poses = scratch.carry.pose;
  // A drop rejoins at half the speed at which water leaves (hysteresis): one that rejoined just
  // under spray_speed would carry that speed into the solve along a wall, where the next face
  // (a corner's floor) is one the step-start sample did not see.
  const float slow2 = 0.25f * params.spray_speed * params.spray_speed;
  const float calm2 = params.spray_speed * params.spray_speed;
  const SprayReactions sums = reduce(
      end - begin, SprayReactions{},
      [&](std::size_t s, SprayReactions& acc) {
        const std::size_t i = begin + s;
        glm::vec3 x = store.position[i], v = store.velocity[i];
        scratch.old_position[i] = x;
        // In the water a drop is water among water: the pressure that holds the water up holds it
        // too (buoyancy), and the air's drag is the water's (shareWithTheWater).
        const float air = 1.0f - scratch.spray_water_share[s];
        const glm::vec3 gravity = air * g;
        const float air_drag = air * k;
        const float speed = glm::length(v) + glm::length(gravity) * dt;
        const int subs = std::clamp(static_cast<int>(std::ceil(speed * dt / max_move)), 1, 64);
        const float h = dt / static_cast<float>(subs);
        bool touched = false;
        for (int sub = 0; sub < subs; ++sub) {
          // Gravity explicit, the drag implicit in |v| (stable at any drag): v' = (v + h g) / (1 + h k |v + h g|).
          const glm::vec3 vg = v + h * gravity;
          v = vg / (1.0f + h * air_drag * glm::length(vg));
          glm::vec3 xn = x + h * v;
          // Moving colliders first, still ones last (resolveCollisions' order): where a crate overlaps
          // a wall, the drop ends outside the wall. The first pass is the §3.3.2 double check from
          // the sub-step's start; later passes push out along the new sample's normal a drop that one
          // collider's push left inside another (a corner), or that a depth map's axis distance left
          // inside the same part near an edge, as the water's collision passes do.
          for (int pass = 0; pass < kCollisionPasses; ++pass) {
            bool moved = false;
            for (std::size_t slot = 0; slot < colliders; ++slot) {
              const std::size_t c = scratch.collide_order[slot];
              const SphCollider& collider = context.world.colliders[c];
              const ColliderPose& pose = poses[c];
              const ColliderQuery query(collider, pose);
              const ColliderSample s1 = query.at(xn);
              if (!s1.valid || s1.distance >= 0.0f) continue;
              const glm::vec3 vc = colliderVelocityAt(pose, xn);
              glm::vec3 position, velocity;
              if (pass == 0) {
                const CollisionResult res = resolveCollision(x, query.at(x), xn, v, s1, vc, h, skin,
                                                             collider.material, depth_slack);
                if (res.outcome == CollisionOutcome::none) continue;
                position = res.position;
                velocity = res.velocity;
              } else {
                position = xn + s1.normal * (skin - s1.distance);
                velocity = collisionResponse(v - vc, s1.normal, collider.material) + vc;
              }
              moved = touched = true;
              ++acc.collisions;
              if (c < kMaxColliders) {
                const glm::vec3 reaction = -mass * (velocity - v) / dt;  // on the collider, over the step
                acc.per_collider[c].force += reaction;
                acc.per_collider[c].torque += glm::cross(position - pose.translation, reaction);
              }
              xn = position;
              v = velocity;
            }
            if (!moved) break;
            if (pass == kCollisionPasses - 1) escapeSqueeze(context, poses, skin, xn);  // the passes did not settle
          }
          x = xn;
        }
        store.position[i] = x;
        store.velocity[i] = v;
        store.density[i] = 0.0f;
        store.pressure[i] = 0.0f;
        // Ready to rejoin (gateCrowdedRejoins decides): slow, and on a collider or among
        // spray_neighbours calm SPH particles. The SPH water's density here is the gate's.
        std::uint32_t calm = 0;
        float density = 0.0f, nearest = std::numeric_limits<float>::infinity();
        const bool slow = glm::dot(v, v) <= slow2;
        if (slow && context.count > 0)
          forWaterNear(context, x, reach, [&](std::uint32_t j, float r) {
            const glm::vec3 vj = store.velocity[j];
            calm += glm::dot(vj, vj) <= calm2 ? 1u : 0u;
            const float w = mass * scratch.kernel.value(r);
            density += w;
            nearest = std::min(nearest, r);
          });
        // Nearer than half a spacing to a water particle, the drop would add most of its own
        // m W(0) to that particle's density: it waits (gateCrowdedRejoins reads infinity).
        scratch.spray_water_density[s] = nearest < 0.5f * context.spacing ? std::numeric_limits<float>::infinity() : density;
        scratch.last_neighbours[i] = !slow ? 0u : touched ? SphScratch::kJoinNeighbours : calm;
      },
      [](SprayReactions a, const SprayReactions& b) {
        for (std::size_t c = 0; c < kMaxColliders; ++c) {
          a.per_collider[c].force += b.per_collider[c].force;
          a.per_collider[c].torque += b.per_collider[c].torque;
        }
        a.collisions += b.collisions;
        return a;
      });
  for (std::size_t c = 0; c < std::min(colliders, kMaxColliders); ++c) {
    SphCollider& collider = context.world.colliders[c];
    collider.force += sums.per_collider[c].force;
    collider.torque += sums.per_collider[c].torque;
  }
  context.stats.collisions += sums.collisions;
  gateCrowdedRejoins(context);
}

void countCalmNeighbours(StepContext& context) {
  const SphParams& params = context.params;
  if (!(params.spray_speed > 0.0f)) return;
  const float calm2 = params.spray_speed * params.spray_speed;
  const std::vector<glm::vec3>& v = context.particles.velocity;
  std::uint32_t* const last = context.scratch.last_neighbours.data();
  const std::uint32_t* const offsets = context.neighbor_offsets;
  const std::uint32_t* const counts = context.neighbor_counts;
  const std::uint32_t* const neighbours = context.neighbor_indices;
  forEach(context.count, [&](std::size_t i) {
    if (glm::dot(v[i], v[i]) <= calm2) {
      last[i] = SphScratch::kUnknownNeighbours;  // calm: stays in the water
      return;
    }
    std::uint32_t calm = 0;
    for (std::uint32_t k = offsets[i]; k < offsets[i] + counts[i]; ++k) {
      const glm::vec3 vj = v[neighbours[k]];
      calm += glm::dot(vj, vj) <= calm2 ? 1u : 0u;
    }
    last[i] = calm;
  });
}

}  // namespace fluid::sph_step
