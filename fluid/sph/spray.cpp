// Spray: ballistic drops outside the SPH solve (spray.hpp).
#include "fluid/sph/spray.hpp"

#include "fluid/sph/boundary.hpp"
#include "fluid/sph/collisions.hpp"

#include <algorithm>
#include <cmath>
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

// Calm SPH particles (|v|^2 <= calm2) within H of p at their end-of-step positions, through this step's grid (built at
// the step-start positions, order the identity after the re-sort). A particle moved at most
// cfl d <= H / 2 in the step (WCSPH: less, its Verlet skin), so every neighbour is found among
// the grid entries within 1.5 H of p.
std::uint32_t countCalmSphNeighbours(const StepContext& context, glm::vec3 p, int reach, float calm2) {
  const NeighborGrid& grid = context.scratch.grid;
  const std::vector<glm::vec3>& x = context.particles.position;
  const std::vector<glm::vec3>& v = context.particles.velocity;
  const float h2 = context.support * context.support;
  const glm::ivec3 c = grid.cellOf(p);
  const glm::ivec3 lo = glm::max(c - reach, glm::ivec3(0)), hi = glm::min(c + reach, grid.dims - 1);
  std::uint32_t count = 0;
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y) {
      const std::uint32_t b = grid.cell_start[grid.keyOf({lo.x, y, z})], e = grid.cell_start[grid.keyOf({hi.x, y, z}) + 1];
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t j = grid.identity_order ? k : grid.order[k];
        const glm::vec3 q = x[j] - p;
        count += glm::dot(q, q) < h2 && glm::dot(v[j], v[j]) <= calm2 ? 1u : 0u;
      }
    }
  return count;
}

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
  const auto staysOrBecomesSpray = [&](std::size_t i) {
    if (!on) return false;
    if (i < spray_begin) {
      const glm::vec3 v = store.velocity[i];
      return last[i] < calm_needed && glm::dot(v, v) > v2;
    }
    return last[i] < calm_needed;  // kJoinNeighbours and kUnknownNeighbours rejoin
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

void advanceSpray(StepContext& context) {
  const std::size_t begin = context.count, end = context.total;
  ParticleStore& store = context.particles;
  SphScratch& scratch = context.scratch;
  const SphParams& params = context.params;
  scratch.old_position.resize(end);
  if (begin >= end) return;
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
  const float slow2 = params.spray_speed * params.spray_speed;
  const int reach = context.count > 0 ? neighborReach(scratch.grid, 1.5f * context.support) : 0;
  const SprayReactions sums = reduce(
      end - begin, SprayReactions{},
      [&](std::size_t s, SprayReactions& acc) {
        const std::size_t i = begin + s;
        glm::vec3 x = store.position[i], v = store.velocity[i];
        scratch.old_position[i] = x;
        const float speed = glm::length(v) + glm::length(g) * dt;
        const int subs = std::clamp(static_cast<int>(std::ceil(speed * dt / max_move)), 1, 64);
        const float h = dt / static_cast<float>(subs);
        bool touched = false;
        for (int sub = 0; sub < subs; ++sub) {
          // Gravity explicit, the drag implicit in |v| (stable at any drag): v' = (v + h g) / (1 + h k |v + h g|).
          const glm::vec3 vg = v + h * g;
          v = vg / (1.0f + h * k * glm::length(vg));
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
        scratch.last_neighbours[i] = touched && glm::dot(v, v) <= slow2 ? SphScratch::kJoinNeighbours
                                     : context.count > 0 ? countCalmSphNeighbours(context, x, reach, slow2)
                                                         : 0u;
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
