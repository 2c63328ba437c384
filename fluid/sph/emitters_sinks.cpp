// Sinks and emitters of the SPH world, and the input check that shares the sinks' pass
// (emitters_sinks.hpp).
#include "fluid/sph/emitters_sinks.hpp"

#include "fluid/core/splitmix.hpp"
#include "fluid/sph/boundary.hpp"

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

namespace fluid::sph_step {

// Validation and the sink test in one parallel pass. Returns the refusal naming the first
// particle with a non-finite position or velocity (the world is left untouched), otherwise
// marks scratch.keep[i] = 0 for the particles inside a sink box and returns their count in
// `in_sinks` (applySinks removes them).
SphStatus checkFiniteAndSinks(SphWorld& world, std::size_t& in_sinks, std::size_t& nonfinite) {
  const auto& x = world.particles.position;
  const auto& v = world.particles.velocity;
  auto& keep = world.scratch.keep;
  keep.resize(x.size());
  // Each particle starts as the one at its index at the end of the last step (sampleBoundary
  // checks that its position is still the carried one, so a store changed between steps only
  // loses the reuse).
  SphScratch::SampleCarry& carry = world.scratch.carry;
  carry.index.resize(x.size());
  const std::size_t none = std::numeric_limits<std::size_t>::max();
  struct Scan {
    std::size_t bad;
    std::size_t inside = 0;
    std::size_t nonfinite = 0;
  };
  const Scan scan = reduce(
      x.size(), Scan{none},
      [&](std::size_t i, Scan& acc) {
        const glm::vec3 p = x[i];
        const bool ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(v[i].x) &&
                        std::isfinite(v[i].y) && std::isfinite(v[i].z);
        if (!ok && i < acc.bad) acc.bad = i;
        acc.nonfinite += ok ? 0 : 1;
        // keep: 1 stays, 0 removed, 2 to the pump (gutter), 3 to the pump if it has room (intake).
        std::uint32_t fate = 1u;
        for (const SphSink& k : world.sinks) {
          if (!(p.x >= k.min.x && p.y >= k.min.y && p.z >= k.min.z && p.x <= k.max.x && p.y <= k.max.y &&
                p.z <= k.max.z))
            continue;
          const std::uint32_t f = k.kind == SphSinkKind::remove ? 0u : k.kind == SphSinkKind::pump ? 2u : 3u;
          if (fate == 1u || (f != 0u && (fate == 0u || f < fate))) fate = f;  // the pump before removal
        }
        const bool inside = fate != 1u;
        keep[i] = fate;
        carry.index[i] = i < carry.count ? static_cast<std::uint32_t>(i) : SphScratch::SampleCarry::kNone;
        acc.inside += inside ? 1 : 0;
      },
      [](Scan a, const Scan& b) {
        a.bad = std::min(a.bad, b.bad);
        a.inside += b.inside;
        a.nonfinite += b.nonfinite;
        return a;
      });
  in_sinks = scan.inside;
  nonfinite = scan.nonfinite;
  const std::size_t bad = scan.bad;
  if (bad == none) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "sph step %llu (t = %.6f s): particle id %u (index %zu) has a non-finite state: position (%g, %g, %g), "
                "velocity (%g, %g, %g); step refused",
                static_cast<unsigned long long>(world.step_count), world.time, world.particles.id[bad], bad,
                static_cast<double>(x[bad].x), static_cast<double>(x[bad].y), static_cast<double>(x[bad].z),
                static_cast<double>(v[bad].x), static_cast<double>(v[bad].y), static_cast<double>(v[bad].z));
  return {buf};
}

// Removes the particles checkFiniteAndSinks marked (`in_sinks` of them); nothing to do (and no
// pass over the data) when none is inside a sink.
std::size_t applySinks(SphWorld& world, std::size_t in_sinks, std::size_t& pumped) {
  pumped = 0;
  if (in_sinks == 0) return 0;
  ParticleStore& store = world.particles;
  SphScratch& scratch = world.scratch;
  SphPump& pump = world.pump;
  const std::size_t n = store.size();
  const std::size_t spray_begin = store.sphCount();
  std::size_t out = 0, spray_gone = 0;
  // Stable compaction: survivors keep their relative order, so the result is deterministic. The
  // pump takes in storage order (grid-cell order, the same at any thread count); an intake's
  // particle stays in the water once the pump is at capacity.
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t fate = scratch.keep[i];
    if (fate == 3u) fate = pump.size() < pump.capacity ? 2u : 1u;
    if (fate == 2u) {
      pump.held.push_back({store.id[i], world.time + pump.delay});
      ++pumped;
    }
    if (fate == 0u || fate == 2u) {
      spray_gone += i >= spray_begin ? 1 : 0;
      continue;
    }
    if (out != i) {
      store.position[out] = store.position[i];
      store.velocity[out] = store.velocity[i];
      store.density[out] = store.density[i];
      store.pressure[out] = store.pressure[i];
      store.id[out] = store.id[i];
      scratch.warm_kappa[out] = scratch.warm_kappa[i];
      scratch.carry.index[out] = scratch.carry.index[i];
      scratch.last_neighbours[out] = scratch.last_neighbours[i];
    }
    ++out;
  }
  store.spray_count -= spray_gone;  // the order is kept, so the spray is still last
  const std::size_t removed = n - out - pumped;
  store.position.resize(out);
  store.velocity.resize(out);
  store.density.resize(out);
  store.pressure.resize(out);
  store.id.resize(out);
  scratch.warm_kappa.resize(out);
  scratch.carry.index.resize(out);
  scratch.last_neighbours.resize(out);
  return removed;
}

namespace {

// Calls f(offset) for each point of the emitter's disc lattice (offset in world units).
template <typename F>
void forDiscLattice(const SphEmitter& e, float d, glm::vec3 dir, F&& f) {
  const glm::vec3 helper = std::abs(dir.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 u = glm::normalize(glm::cross(dir, helper));
  const glm::vec3 w = glm::cross(dir, u);
  const int reach = static_cast<int>(std::floor(std::max(e.radius, 0.0f) / d));
  const float r2 = e.radius * e.radius + 1e-6f * d * d;
  for (int j = -reach; j <= reach; ++j)
    for (int i = -reach; i <= reach; ++i) {
      const glm::vec3 o = d * (static_cast<float>(i) * u + static_cast<float>(j) * w);
      if (glm::dot(o, o) <= r2) f(o);
    }
}

// True when a sphere of radius `room` around p overlaps a collider (its signed distance at p is
// below `room`). Emitters skip such lattice points: a nozzle placed in or against a solid cannot
// emit there, and a particle created inside the boundary's filled half-space would start at up to
// twice the rest density (WCSPH's Tait pressure then fires it off at km/s). One query per
// collider serves both tests: otherwise `volume` is the boundary volume at p, combined over the
// colliders as in the step (sampleBoundary); when it returns true, `volume` is 0.
bool overlapsCollider(const SphWorld& world, glm::vec3 p, float room, float& volume) {
  float product = 1.0f;  // prod_c (1 - V_c)
  volume = 0.0f;
  for (const SphCollider& col : world.colliders) {
    const glm::vec3 local = toColliderSpace(col.pose, p);
    ColliderSample sample;
    col.shape->query(std::span<const glm::vec3>(&local, 1), std::span<ColliderSample>(&sample, 1));
    if (sample.valid && sample.distance < room) return true;
    product *= openFraction(world.scratch, col, sample);
  }
  volume = 1.0f - product;
  return false;
}

// The boundary volume at p alone (no overlap test: no distance is below -infinity).
float boundaryVolumeAt(const SphWorld& world, glm::vec3 p) {
  float volume = 0.0f;
  overlapsCollider(world, p, -std::numeric_limits<float>::infinity(), volume);
  return volume;
}

// Emitters also skip lattice points closer than the lattice spacing d (less 1 % for rounding) to an
// existing particle: in a resting lattice no neighbour is nearer than d, so a point that close sits
// in fluid already there (a slow upward jet falling back onto its nozzle, a nozzle buried in a
// pile). A particle inserted there is compressed from its first step, and the pressure solve
// would turn that stored compression into kinetic energy the emitter never supplied. A blocked
// nozzle emits less instead.
constexpr float kEmitterRoom = 0.99f;  // x d

// Compression the density test below lets through, relative to rho_0. It has to be well above the
// float rounding of a density sum: sphParticleMass makes a full lattice neighbourhood sum to exactly
// rho_0, so a free jet whose layers are exactly d apart completes neighbourhoods at rho_0 up to the
// last bit. 0.1 % is about a hundred times that rounding.
constexpr float kEmitterDensitySlack = 1e-3f;

// The distance test alone is not enough where an existing particle is pressed against a collider
// closer than the rest distance r (a jet running onto a solid: the Kolb 2004 §3.3.2 reaction leaves
// it at the surface, and the boundary volume already gives it nearly rho_0): a point d from it on
// the far side squeezes it between the new particle and the wall, and DFSPH removes that
// compression within one step as a velocity kick. So the point is tested by what it does to the
// fluid: the SPH density (Becker & Teschner 2007 eq. 4, plus rho_0 times the boundary volume as in
// the step) of the new particle and of every existing particle within its support must stay at or
// below rho_0 (1 + kEmitterDensitySlack) with it added. Creating compression is creating energy the
// emitter does not supply; density below rho_0 is free (the solvers only correct compression).
// The particles near a layer are gathered once per layer: those within the support of a point
// (disc radius + H) need their own density, which needs their neighbours (disc radius + 2H).
void gatherCrowd(const SphWorld& world, glm::vec3 centre, float reach, std::vector<glm::vec3>& crowd) {
  crowd.clear();
  const float reach2 = reach * reach;
  for (const glm::vec3& x : world.particles.position) {
    const glm::vec3 q = x - centre;
    if (glm::dot(q, q) <= reach2) crowd.push_back(x);
  }
}

// density[k] = SPH density of crowd[k] at the current positions, for the members within `inner`
// of the centre (the others are never within H of a lattice point: 0, unused). Every neighbour of
// such a member is in the crowd (it was gathered to inner + H).
void crowdDensities(const SphWorld& world, glm::vec3 centre, float inner, std::span<const glm::vec3> crowd,
                    std::vector<float>& density) {
  const SphScratch& scratch = world.scratch;
  const float H = scratch.kernel.support, h2 = H * H, m = scratch.particle_mass, rho0 = world.params.rest_density;
  const float inner2 = inner * inner;
  density.assign(crowd.size(), 0.0f);
  for (std::size_t a = 0; a < crowd.size(); ++a) {
    const glm::vec3 xa = crowd[a];
    const glm::vec3 c = xa - centre;
    if (glm::dot(c, c) > inner2) continue;
    float sum = scratch.kernel.value(0.0f);
    for (std::size_t b = 0; b < crowd.size(); ++b) {
      const glm::vec3 q = xa - crowd[b];
      const float q2 = glm::dot(q, q);
      if (b != a && q2 < h2) sum += scratch.kernel.value(std::sqrt(q2));
    }
    density[a] = m * sum + rho0 * boundaryVolumeAt(world, xa);
  }
}

bool crowded(std::span<const glm::vec3> crowd, glm::vec3 p, float room2) {
  for (const glm::vec3& x : crowd) {
    const glm::vec3 q = x - p;
    if (glm::dot(q, q) < room2) return true;
  }
  return false;
}

// `dir` (unit) tilted by an angle in [0, spread] within the cone around it, uniform over the cone's
// solid angle, at an azimuth, both from a hash of `id` (SphEmitter::spread).
glm::vec3 scatteredDirection(glm::vec3 dir, float spread, std::uint32_t id) {
  if (!(spread > 0.0f)) return dir;
  const std::uint64_t z = splitmix64(id);
  const float u1 = unitFloat(z), u2 = static_cast<float>(z & 0xffffffu) / 16777216.0f;  // top and bottom 24 bits
  const float cos_tilt = 1.0f - u1 * (1.0f - std::cos(std::min(spread, glm::half_pi<float>())));
  const float sin_tilt = std::sqrt(std::max(0.0f, 1.0f - cos_tilt * cos_tilt));
  const glm::vec3 helper = std::fabs(dir.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 e1 = glm::normalize(glm::cross(helper, dir)), e2 = glm::cross(dir, e1);
  const float azimuth = glm::two_pi<float>() * u2;
  return cos_tilt * dir + sin_tilt * (std::cos(azimuth) * e1 + std::sin(azimuth) * e2);
}

}  // namespace

std::size_t applyEmitters(SphWorld& world) {
  const float d = sphSpacing(world.params);
  const float room = kEmitterRoom * d;
  SphScratch& scratch = world.scratch;
  std::vector<glm::vec3>& crowd = scratch.emitter_crowd;
  std::vector<float>& crowd_density = scratch.emitter_crowd_density;
  const float H = scratch.kernel.support, h2 = H * H, m = scratch.particle_mass, rho0 = world.params.rest_density;
  const float rhoLimit = rho0 * (1.0f + kEmitterDensitySlack);
  const float self = m * scratch.kernel.value(0.0f);
  std::size_t emitted = 0;
  for (SphEmitter& e : world.emitters) {
    if (!(e.rate > 0.0f) || !(e.speed > 0.0f) || !std::isfinite(e.rate) || !std::isfinite(e.speed)) continue;
    glm::vec3 dir = e.direction;
    const float len = glm::length(dir);
    dir = (len > 0.0f && std::isfinite(len)) ? dir / len : glm::vec3(0, 1, 0);
    std::size_t layer = 0;
    forDiscLattice(e, d, dir, [&](glm::vec3) { ++layer; });
    // Layers closer than d along the jet would overlap (compressed fluid = stored energy), so the
    // rate is clamped to speed * layer / d particles per second.
    const double interval = std::max(static_cast<double>(layer) / e.rate, static_cast<double>(d) / e.speed);
    while (e.accumulator >= interval) {
      e.accumulator -= interval;
      if (!world.pump.feeds_emitters && world.particles.size() + layer > world.params.max_particles)
        continue;  // over budget: layer dropped
      // The layer was due `accumulator` seconds ago and has travelled that far.
      const glm::vec3 base = e.position + dir * (e.speed * static_cast<float>(e.accumulator));
      // Layers placed earlier in this loop are existing particles here (d apart along the jet:
      // interval >= d / speed). The points of this layer join the crowd as they are placed, so
      // the density test sees them; they are d apart, so they do not block each other by distance.
      const float disc = std::max(e.radius, 0.0f) + 1e-3f * d;  // a lattice point is at most this far from base
      gatherCrowd(world, base, disc + 2.0f * H + 1e-3f * d, crowd);
      bool densities = false;  // crowd_density is filled when the first point passes the cheaper tests
      forDiscLattice(e, d, dir, [&](glm::vec3 o) {
        const glm::vec3 p = base + o;
        // The crowd test first: a few distances, where the collider test is a query per collider.
        if (crowded(crowd, p, room * room)) return;
        float volume = 0.0f;
        if (overlapsCollider(world, p, world.params.particle_radius, volume)) return;
        if (!densities) {
          crowdDensities(world, base, disc + H + 1e-3f * d, crowd, crowd_density);
          densities = true;
        }
        // f(k, m W(|p - crowd[k]|)) for the crowd members within the support of p, in crowd order;
        // stops early when f returns false.
        auto forSupport = [&](auto&& f) {
          for (std::size_t k = 0; k < crowd.size(); ++k) {
            const glm::vec3 q = p - crowd[k];
            const float q2 = glm::dot(q, q);
            if (q2 < h2 && !f(k, m * scratch.kernel.value(std::sqrt(q2)))) return false;
          }
          return true;
        };
        float rho = self + rho0 * volume;
        const bool room_left = forSupport([&](std::size_t k, float wk) {
          rho += wk;
          return crowd_density[k] + wk <= rhoLimit;  // else it would compress an existing particle
        });
        if (!room_left || rho > rhoLimit) return;  // (rho > limit: it would start compressed)
        if (world.pump.feeds_emitters) {
          SphPump& pump = world.pump;
          if (pump.size() == 0 || pump.held[pump.head].ready_time > world.time) return;  // the pipe is empty
          const std::uint32_t id = pump.held[pump.head].id;
          if (!addSphParticleWithId(world, id, p, scatteredDirection(dir, e.spread, id) * e.speed)) return;
          ++pump.head;
          if (pump.head * 2 >= pump.held.size()) {  // drop the given-back front (amortised, no allocation)
            pump.held.erase(pump.held.begin(), pump.held.begin() + static_cast<std::ptrdiff_t>(pump.head));
            pump.head = 0;
          }
        } else if (!addSphParticle(world, p, scatteredDirection(dir, e.spread, world.next_id) * e.speed)) {
          return;
        }
        ++emitted;
        forSupport([&](std::size_t k, float wk) {
          crowd_density[k] += wk;
          return true;
        });
        crowd.push_back(p);
        crowd_density.push_back(rho);
      });
    }
  }
  return emitted;
}

void advanceEmitterClocks(SphWorld& world, float dt) {
  for (SphEmitter& e : world.emitters) {
    const double t0 = world.time, t1 = world.time + dt;
    const double active =
        std::max(0.0, std::min(t1, static_cast<double>(e.end_time)) - std::max(t0, static_cast<double>(e.start_time)));
    e.accumulator += active;
  }
}

}  // namespace fluid::sph_step
