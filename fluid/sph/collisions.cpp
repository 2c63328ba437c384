// End-of-step collisions (collisions.hpp).
#include "fluid/sph/collisions.hpp"

#include "fluid/sph/boundary.hpp"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

namespace fluid::sph_step {

ColliderPose advancedPose(const ColliderPose& pose, float dt) {
  ColliderPose out = pose;
  out.translation += pose.linear_velocity * dt;
  const float angular_speed = glm::length(pose.angular_velocity);
  if (angular_speed > 0.0f)
    out.rotation =
        glm::normalize(glm::angleAxis(angular_speed * dt, pose.angular_velocity / angular_speed) * pose.rotation);
  return out;
}

namespace {

constexpr int kPasses = 4;  // collision passes per sub-step (resolveCollisions)
// A step whose start and end samples are outside but name faces more than 120 degrees apart is
// taken for a crossing of a thin part (collidePass). The two sides of a plate face away from each
// other, 180 degrees less what it turned in the step: a plate that turns up to 60 degrees in a
// step is caught (the test SphCollisions.AThinPlateThatTurnsAsItPassesAParticleLeavesItOnItsSide
// turns one 30). Two faces that meet at a crate's edge are square to each other, 90 degrees plus
// what the crate turned in the step: a particle that only moved from beside one face to beside its
// neighbour is no crossing while the crate turns less than 30 degrees a step, 31 rad/s at the
// fountain's one 16.7 ms step a frame (the soak's traced crate spun at 13 rad/s; the test
// SphCollisions.WaterAtACrateEdgeIsNotTakenForWaterTheCrateCrossed). The price: a fin whose edge
// is blunter than 60 degrees is not told from a corner, and a particle through it is not caught.
constexpr float kOppositeSides = -0.5f;  // cos 120 degrees
// scratch.pushed bits: moved by a pass of this step (stats.pushed_out), moved by its last pass.
constexpr std::uint8_t kPushedThisStep = 1, kPushedInLastPass = 2;

// Where a still collider pushes a particle out (outward normal ns, by `need` along it) that a
// moving collider pushed out earlier in the same step (its face as the plane
// dot(plane.xyz, x) >= plane.w), the position nearest to p outside both tangent planes: the two
// projections one after the other only converge slowly in a narrow wedge (a tilted crate edge
// on the basin floor) and end wherever the last one put the particle. The planes' intersection,
// when the still projection alone would violate the moving face: x = p + l1 ns + l2 nm with both
// constraints active (a 2x2 system). `still_only` (the still projection) is kept where the faces
// are nearly parallel or the wedge's free side is more than `reach` away: there the moving
// collider overlaps the still one, no free position is near, and the still collider wins.
glm::vec3 wedgePosition(glm::vec3 p, glm::vec3 ns, float need, glm::vec4 plane, float reach, glm::vec3 still_only) {
  const glm::vec3 nm(plane);
  const float c = glm::dot(ns, nm);
  const float r1 = need, r2 = plane.w - glm::dot(nm, p);  // displacements required along ns and nm
  if (c * r1 >= r2) return still_only;                    // the still projection keeps the moving face
  const float det = 1.0f - c * c;
  if (det < 1e-3f) return still_only;
  const float l1 = (r1 - c * r2) / det, l2 = (r2 - c * r1) / det;
  if (l1 < 0.0f || l2 < 0.0f) return still_only;
  const glm::vec3 x = p + l1 * ns + l2 * nm;
  return glm::length(x - p) <= reach ? x : still_only;
}

// Where a particle's step [from, to] entered a still collider, to `halvings` bisections of the
// field's sign: on return `from` is the last point of the step the collider calls outside (or not
// valid: no opinion, far outside) and `from_sample` its sample. The depth maps classify a point to
// within half a texel (docs/collide.md) but measure its distance along an axis or a cube's ray, so
// the sign locates the entry better than the distance does.
constexpr int kEntryHalvings = 8;  // a 6 cm step (a fast drop's) to 0.25 mm

void stepEntry(const ColliderQuery& query, glm::vec3 to, int halvings, glm::vec3& from, ColliderSample& from_sample) {
  glm::vec3 inside = to;
  for (int k = 0; k < halvings; ++k) {
    const glm::vec3 mid = 0.5f * (from + inside);
    const ColliderSample sample = query.at(mid);
    if (!sample.valid || sample.distance >= 0.0f) {
      from = mid;
      from_sample = sample;
    } else {
      inside = mid;
    }
  }
}

struct Hits {
  std::size_t count = 0;      // reactions
  std::size_t particles = 0;  // particles reacting for the first time this step
  float depth = 0.0f;         // deepest end-of-step penetration (m)
  ForceTorque reaction{};
};

// One collision pass of collider c (the k-th in collide_order): query, reaction and the
// reaction force/torque sums in one parallel region.
Hits collidePass(StepContext& context, int pass, std::size_t k, std::size_t c) {
  SphScratch& scratch = context.scratch;
  std::vector<glm::vec3>& positions = context.particles.position;
  std::vector<glm::vec3>& velocities = context.particles.velocity;
  const std::size_t n = context.count, collider_count = context.collider_count;
  const float dt = context.dt, support = context.support, spacing = context.spacing, mass = context.mass;
  const float skin =
      context.params.collision_skin > 0.0f ? context.params.collision_skin : 0.01f * context.params.particle_radius;
  // The depth maps' error near a surface is a texel or two, well under a particle radius, and the
  // boundary pressure keeps water about a radius off a wall: a sample deeper than the step by more
  // than that is the axis-distance error of a concave corner (resolveCollision).
  const float depth_slack = context.params.particle_radius;
  const bool track_stale = collider_count <= 32;
  const std::uint32_t all_colliders = collider_count >= 32 ? ~0u : (1u << collider_count) - 1u;
  const SphCollider& collider = context.world.colliders[c];
  const ColliderPose pose = collider.integrate_pose ? advancedPose(collider.pose, dt) : collider.pose;
  // Does not move during the step: the end pose is the start pose, so are the samples' distances.
  const bool still = !sphColliderMoves(collider);
  const bool skip_far = still && collider.lipschitz_distance;
  const std::uint32_t bit = track_stale ? 1u << c : 0u;
  const ColliderQuery query(collider, pose);
  std::vector<ColliderSample>& end_samples = scratch.end_samples[c];
  end_samples.resize(n);
  const std::vector<ColliderSample>& start_samples = scratch.start_samples[c];
  return reduceChunks(
      n, Hits{},
      [&](std::size_t b, std::size_t e, Hits& acc) {
        std::uint32_t which[kGrain];
        std::uint32_t q = 0;
        // Local pointers: the stores below could alias the vectors' own fields, so reading them
        // through `scratch` would reload them for every particle.
        std::uint32_t* const stale = scratch.collide_stale.data();
        if (pass == 0 && k == 0) {
          std::fill(stale + b, stale + e, all_colliders);
          std::fill(scratch.push_plane.begin() + b, scratch.push_plane.begin() + e, glm::vec4(0.0f));
          std::fill(scratch.pushed.begin() + b, scratch.pushed.begin() + e, 0);
        }
        for (std::size_t i = b; i < e; ++i) {
          if (track_stale && pass > 0 && !(stale[i] & bit)) continue;  // unchanged: same sample
          stale[i] &= ~bit;
          const ColliderSample& s0 = start_samples[i];
          if (skip_far && s0.valid) {
            const glm::vec3 p = positions[i], p0 = scratch.old_position[i];
            // Float slack of the distance evaluation, far above its rounding at these coordinates.
            const float slack = 1e-6f * (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), std::abs(p0.x),
                                                   std::abs(p0.y), std::abs(p0.z)}) +
                                         support);
            if (s0.distance > glm::length(p - p0) + skin + slack) {
              end_samples[i].valid = false;  // cannot have reached the surface: no reaction
              continue;
            }
          }
          which[q++] = static_cast<std::uint32_t>(i);
        }
        query.run(positions, which, q, end_samples);
        std::uint32_t again = 0;  // particles this still collider projected (checked below)
        // Only the particles just queried can react: one skipped as unchanged since its last query
        // has the sample that gave no reaction then (a reaction marks every sample stale), and one
        // skipped as far has no reaction. Ascending i, so the sums add in the same order.
        for (std::uint32_t w = 0; w < q; ++w) {
          const std::size_t i = which[w];
          const ColliderSample& s = end_samples[i];
          const ColliderSample& s0 = start_samples[i];
          // Tunnelling through a thin part: outside at both ends of the step but on opposite
          // sides (outward normals more than 120 degrees apart, kOppositeSides), e.g. a thin fast
          // wall that moved past the particle.
          // The particle stays on its side: carried along by the collider, then the §3.3.2
          // reaction against the side it came from.
          const bool crossed = s.valid && s0.valid && s.distance >= 0.0f && s0.distance >= 0.0f &&
                               s.distance < support && s0.distance < support &&
                               glm::dot(s.normal, s0.normal) < kOppositeSides;
          if (!crossed && (!s.valid || s.distance >= 0.0f)) continue;
          ++acc.count;
          if (!(scratch.pushed[i] & kPushedThisStep)) {
            scratch.pushed[i] |= kPushedThisStep;
            ++acc.particles;
          }
          if (pass == kPasses - 1) scratch.pushed[i] |= kPushedInLastPass;
          CollisionResult res;
          // The penetration the reaction resolves: the sample's depth, bounded by the step below, or
          // the step of a held-back particle (resolveCollision).
          float depth = 0.0f;
          if (crossed) {
            const glm::vec3 vc = colliderVelocityAt(collider.pose, scratch.old_position[i]);
            res.position = scratch.old_position[i] + vc * dt + s0.normal * skin;
            res.velocity = collisionResponse(velocities[i] - vc, s0.normal, collider.material) + vc;
          } else {
            // A still collider (its pose the same at both ends of the step, so the step's points are
            // where the particle passed) is entered where its field's sign flips along the step.
            const bool entered = still && !(s0.valid && s0.distance < 0.0f);
            glm::vec3 from = scratch.old_position[i];
            ColliderSample from_sample = s0;
            if (entered) stepEntry(query, positions[i], kEntryHalvings, from, from_sample);
            res = resolveCollision(from, from_sample, positions[i], velocities[i], s,
                                   colliderVelocityAt(pose, positions[i]), dt, skin, collider.material, depth_slack);
            // A vote measures along its map's axis or its cube's ray (Kolb §4.1, §4.3), so where that
            // meets the face at an angle θ to its normal it reads 1 / cos θ times the depth: the
            // steep foot of the statue's spire seen by the y maps about 4x, the basin floor seen by
            // the cavity cube's 44-degree rays 1.4x. A particle that entered the face the sample
            // names (moved into it, along -n) from outside its plane is at most as deep as it moved
            // into it since the entry: projecting by more throws it past where it came in, away from
            // the wall. Where it did not move into that face, the face is not where it came in and
            // the step bounds nothing.
            depth = res.held_back ? glm::length(positions[i] - from) : -s.distance;
            const float into = glm::dot(from - positions[i], s.normal);
            if (entered && !res.held_back && into > 0.0f && into < depth) {
              res.position = positions[i] + s.normal * (skin + into);
              depth = into;
            }
          }
          acc.depth = std::max(acc.depth, depth);
          if (!still) {
            // The moving face the particle now rests on: n . x >= n . x_now (it sits skin outside).
            const glm::vec3 nm = crossed || res.held_back ? s0.normal : s.normal;
            scratch.push_plane[i] = glm::vec4(nm, glm::dot(nm, res.position));
          } else if (!crossed && !res.held_back && scratch.push_plane[i] != glm::vec4(0.0f)) {
            res.position =
                wedgePosition(positions[i], s.normal, skin + depth, scratch.push_plane[i], spacing, res.position);
          }
          const glm::vec3 reaction = -mass * (res.velocity - velocities[i]) / dt;  // on the collider
          positions[i] = res.position;
          velocities[i] = res.velocity;
          scratch.collide_stale[i] = all_colliders;  // moved: every collider's sample is out of date
          // Particles without a reaction add exact zeros in a separate sum (an accumulator
          // starting at +0 never becomes -0), so skipping them gives the same sums.
          if (!inFilmOf(context, c, i)) {
            acc.reaction.force += reaction;
            acc.reaction.torque += glm::cross(positions[i] - pose.translation, reaction);
          }
          if (still && !crossed && !res.held_back) which[again++] = static_cast<std::uint32_t>(i);
        }
        // A still collider's projection is checked where it landed: a depth map measures distance
        // along its axis, so near an edge the projected point can lie under another face of the
        // part (a crate resting on the basin rim hands a particle back into the rim's side every
        // pass). Projected again along the new sample's normal while inside, so a particle leaves
        // a still collider's pass outside it (still colliders win, resolveCollisions).
        for (int round = 0; round < 2 && again > 0; ++round) {
          query.run(positions, which, again, end_samples);
          std::uint32_t still_inside = 0;
          for (std::uint32_t w = 0; w < again; ++w) {
            const std::size_t i = which[w];
            const ColliderSample& s = end_samples[i];
            if (!s.valid || s.distance >= 0.0f) continue;
            const glm::vec3 vc = colliderVelocityAt(pose, positions[i]);
            const glm::vec3 velocity = collisionResponse(velocities[i] - vc, s.normal, collider.material) + vc;
            const glm::vec3 reaction = -mass * (velocity - velocities[i]) / dt;
            positions[i] += s.normal * (skin - s.distance);
            velocities[i] = velocity;
            acc.depth = std::max(acc.depth, -s.distance);
            if (!inFilmOf(context, c, i)) {
              acc.reaction.force += reaction;
              acc.reaction.torque += glm::cross(positions[i] - pose.translation, reaction);
            }
            if (pass == kPasses - 1) scratch.pushed[i] |= kPushedInLastPass;
            which[still_inside++] = static_cast<std::uint32_t>(i);
          }
          again = still_inside;
        }
      },
      [](Hits a, const Hits& b) {
        a.count += b.count;
        a.particles += b.particles;
        a.depth = std::max(a.depth, b.depth);
        a.reaction.force += b.reaction.force;
        a.reaction.torque += b.reaction.torque;
        return a;
      });
}

// SphParams::speculative_contacts, before the passes: against each collider (moving ones first),
// a particle that started the step outside it, d0 from its surface along the step-start sample's
// normal n, and approaches it at a = -(v - v_c) . n (v_c the collider's velocity there) loses the
// part of the approach that would take it nearer than the standoff s within the step:
// excess = a dt - max(d0 - s, 0), removed from the velocity (excess / dt along n) and from the
// advected position (excess along n). Only approach is removed, never added: a particle already
// nearer than s keeps its velocity where it does not approach. The collider takes the reaction.
void speculativeContacts(StepContext& context) {
  SphScratch& scratch = context.scratch;
  std::vector<glm::vec3>& positions = context.particles.position;
  std::vector<glm::vec3>& velocities = context.particles.velocity;
  const std::size_t n = context.count;
  const float dt = context.dt, mass = context.mass, support = context.support;
  const float standoff = context.params.contact_standoff * context.params.particle_radius;
  for (std::size_t k = 0; k < context.collider_count; ++k) {
    const std::size_t c = scratch.collide_order[k];
    SphCollider& collider = context.world.colliders[c];
    const std::vector<ColliderSample>& start_samples = scratch.start_samples[c];
    const ForceTorque sum = reduce(
        n, ForceTorque{},
        [&](std::size_t i, ForceTorque& acc) {
          const ColliderSample& s0 = start_samples[i];
          if (!s0.valid || s0.distance < 0.0f || s0.distance > support) return;
          const glm::vec3 vc = colliderVelocityAt(collider.pose, scratch.old_position[i]);
          const float approach = -glm::dot(velocities[i] - vc, s0.normal);
          const float excess = approach * dt - std::max(s0.distance - standoff, 0.0f);
          if (!(approach > 0.0f) || !(excess > 0.0f)) return;
          const glm::vec3 change = s0.normal * (excess / dt);
          velocities[i] += change;
          positions[i] += s0.normal * excess;
          if (inFilmOf(context, c, i)) return;             // the caller's film closure carries it
          const glm::vec3 reaction = -mass * change / dt;  // on the collider
          acc.force += reaction;
          acc.torque += glm::cross(positions[i] - collider.pose.translation, reaction);
        },
        [](ForceTorque a, const ForceTorque& b) {
          a.force += b.force;
          a.torque += b.torque;
          return a;
        });
    collider.force += sum.force;
    collider.torque += sum.torque;
  }
}

// After passes that did not settle: every particle the last pass still moved takes a free exit of
// the moving collider it is in, if there is one (escapeSqueeze), keeping the velocity and the
// reactions the passes gave it. Its samples are then out of date (collide_stale).
void escapeSqueezes(StepContext& context) {
  SphScratch& scratch = context.scratch;
  const std::size_t n = context.count, collider_count = context.collider_count;
  const float skin =
      context.params.collision_skin > 0.0f ? context.params.collision_skin : 0.01f * context.params.particle_radius;
  const std::uint32_t all_colliders = collider_count >= 32 ? ~0u : (1u << collider_count) - 1u;
  std::vector<glm::vec3>& positions = context.particles.position;
  forEach(n, [&](std::size_t i) {
    if ((scratch.pushed[i] & kPushedInLastPass) && escapeSqueeze(context, scratch.carry.pose, skin, positions[i]))
      scratch.collide_stale[i] = all_colliders;
  });
}

}  // namespace

// Kolb et al. 2004 §3.3.2 double check against the collider at its end-of-step pose, with the
// step-start sample as "previous". Repeated (up to 4 passes) while a later collider pushed a
// particle into an earlier one (corners), so no particle ends the step inside a collider where a
// position outside all of them exists nearby.
// Queries that cannot change the outcome are skipped (bit-identical results):
//  - in passes after the first, a particle that has not moved since collider c last queried it
//    gets the same sample, so the same (no) reaction: only particles moved since are queried;
//  - for a static collider with a 1-Lipschitz distance (SphCollider::lipschitz_distance), a
//    particle that started at s0 and moved less than s0 (minus a margin) stayed outside along
//    its whole step (every point of the segment is at least s0 - |displacement| > 0 away): no
//    reaction and nothing tunnelled, so no query is needed. (The tunnelling test could only fire
//    there on a normal flip across a medial axis, e.g. between a spire and a dish wall, which is
//    not a crossing for a collider that does not move.)
// Order within a pass: the colliders that move during the step first, the still ones
// (sphColliderMoves false) last, so a pass ends with the still colliders' projections. Where a
// moving collider's end-of-step pose overlaps a still one (a crate, advanced by its velocities
// through the step, reaching into a basin wall, which the rigid-body solver stops only
// afterwards), a particle between them has no position outside both, and alternating projections
// would leave it wherever the last collider put it: inside the wall, carried further by the crate
// every step. Still colliders win: the particle ends outside them, inside the moving collider only
// where that overlaps a still one, and the moving collider gets the reactions of its own
// projections (its push on the particle) like any other contact.
void resolveCollisions(StepContext& context) {
  SphScratch& scratch = context.scratch;
  const std::size_t n = context.count, collider_count = context.collider_count;
  scratch.collide_order.resize(collider_count);
  scratch.push_plane.resize(n);
  scratch.pushed.resize(n);
  {
    std::size_t k = 0;
    for (const bool moving_first : {true, false})
      for (std::size_t c = 0; c < collider_count; ++c)
        if (sphColliderMoves(context.world.colliders[c]) == moving_first)
          scratch.collide_order[k++] = static_cast<std::uint32_t>(c);
  }
  if (context.params.speculative_contacts) speculativeContacts(context);
  scratch.end_samples.resize(collider_count);
  scratch.collide_stale.resize(n);
  bool settled = true;
  for (int pass = 0; pass < kPasses && collider_count > 0; ++pass) {
    std::size_t inside_total = 0;
    for (std::size_t k = 0; k < collider_count; ++k) {
      const std::size_t c = scratch.collide_order[k];
      const Hits hits = collidePass(context, pass, k, c);
      inside_total += hits.count;
      context.stats.collisions += hits.count;
      context.stats.pushed_out += hits.particles;
      context.stats.max_push_depth = std::max(context.stats.max_push_depth, hits.depth);
      if (hits.count > 0) {
        SphCollider& collider = context.world.colliders[c];
        collider.force += hits.reaction.force;
        collider.torque += hits.reaction.torque;
      }
    }
    settled = inside_total == 0;
    if (settled) break;
  }
  // What the next step's boundary sampling may reuse (SphScratch::SampleCarry): end_samples[c]
  // where collide_stale bit c is clear were queried at the particle's final position, except for
  // colliders whose far particles were skipped without a query.
  SphScratch::SampleCarry& carry = scratch.carry;
  carry.shape.resize(collider_count);
  carry.pose.resize(collider_count);
  carry.usable.resize(collider_count);
  for (std::size_t c = 0; c < collider_count; ++c) {
    const SphCollider& collider = context.world.colliders[c];
    carry.shape[c] = collider.shape;
    carry.pose[c] = collider.integrate_pose ? advancedPose(collider.pose, context.dt) : collider.pose;
    const bool skipped_far = !sphColliderMoves(collider) && collider.lipschitz_distance;
    carry.usable[c] = collider_count <= 32 && !skipped_far ? 1 : 0;
  }
  if (!settled) escapeSqueezes(context);
}

bool escapeSqueeze(const StepContext& context, const std::vector<ColliderPose>& poses, float skin, glm::vec3& x) {
  const SphScratch& scratch = context.scratch;
  const std::size_t colliders = context.collider_count;
  for (std::size_t slot = 0; slot < colliders; ++slot) {
    const std::size_t c = scratch.collide_order[slot];
    const SphCollider& collider = context.world.colliders[c];
    if (!sphColliderMoves(collider)) continue;
    const ColliderSample inside = ColliderQuery(collider, poses[c]).at(x);
    if (!inside.valid || inside.distance >= 0.0f) continue;
    const glm::vec3 exit = x + inside.normal * (skin - inside.distance);
    bool free = true;
    for (std::size_t o = 0; o < colliders && free; ++o) {
      const ColliderSample s = ColliderQuery(context.world.colliders[o], poses[o]).at(exit);
      free = !s.valid || s.distance >= 0.0f;
    }
    if (!free) continue;
    x = exit;
    return true;
  }
  return false;
}

}  // namespace fluid::sph_step
