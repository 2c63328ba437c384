#include "game/soak_monitor.hpp"

#include "game/explosives/explosives.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace game {
namespace {

void fail(SoakMonitor& m, std::uint64_t step, const std::string& what) {
  if (m.failure.empty()) m.failure = "step " + std::to_string(step) + ": " + what;
}

std::string describe(const char* what, const Penetration& p, float tolerance) {
  char text[256];
  std::snprintf(text, sizeof(text), "%s %.4f m inside a collider (%.2f radii, tolerance %.2f) at (%.3f, %.3f, %.3f)",
                what, p.depth, p.ratio, tolerance, p.position.x, p.position.y, p.position.z);
  return text;
}

// Moves the camera to the thrower's place and throws along a lob that lands near the target: a
// crate leaves along the camera's forward axis at its throw_speed, so aim above the target by the
// drop over the flight (flight time from the straight distance, ignoring the arc's extra length).
// An explosive leaves at its own throw speed, lobbed above the camera's axis by lob_degrees (its
// fuse, not the landing point, decides where it blows: near enough for the soak). Returns whether
// an explosive was thrown (a scene without the explosives effect throws a crate instead).
bool throwAt(World& world, const PlayerThrow& t) {
  const RigidBodies& bodies = *findState<RigidBodies>(world);
  const bool explosive = t.explosive && world.links.explosives != nullptr;
  const float speed = explosive ? world.links.explosives->params.throw_speed : bodies.params.throw_speed;
  const glm::vec3 to_target = t.target - t.from;
  const float flight = glm::length(to_target) / std::max(speed, 0.1f);
  const glm::vec3 aim = to_target - 0.5f * bodies.params.gravity * flight * flight;
  const glm::vec3 dir = glm::normalize(aim);
  world.camera.position = t.from;
  world.camera.yaw_degrees = glm::degrees(std::atan2(dir.z, dir.x));
  world.camera.pitch_degrees = std::clamp(glm::degrees(std::asin(std::clamp(dir.y, -1.0f, 1.0f))), -89.0f, 89.0f);
  if (explosive)
    playerThrowExplosive(world);
  else
    playerThrow(world);
  return explosive;
}

void trackCount(std::size_t count, bool first, std::size_t& lo, std::size_t& hi) {
  lo = first ? count : std::min(lo, count);
  hi = first ? count : std::max(hi, count);
}

float maxSpeed(std::span<const glm::vec3> velocities) {
  float fastest = 0.0f;
  for (const glm::vec3& v : velocities) fastest = std::max(fastest, glm::dot(v, v));
  return std::sqrt(fastest);
}

// Where a failing SPH particle is: its signed distance to every collider within a particle
// radius of it, so a report tells a particle squeezed between two crates from one that went through a wall.
std::string collidersNear(const fluid::SphWorld& sph, glm::vec3 position, PenetrationScratch& scratch) {
  const float radius = sph.params.particle_radius;
  std::string out;
  for (std::size_t c = 0; c < sph.colliders.size(); ++c) {
    const fluid::SphCollider& collider = sph.colliders[c];
    const Penetration p =
        worstPenetration(std::span(&position, 1), *collider.shape, collider.pose, radius, radius, scratch);
    if (p.depth <= 0.0f) continue;
    char part[96];
    std::snprintf(part, sizeof(part), "%s collider %zu%s %.4f m", out.empty() ? "; within a radius of" : ",", c,
                  fluid::sphColliderMoves(collider) ? " (moving)" : "", static_cast<double>(radius - p.depth));
    out += part;
  }
  return out;
}

// SPH particles against every collider the solver knows (the fountain and the coupled crates, at
// the poses the solver ended the step with); sprites against the fountain; crate centres against
// the fountain with their half edge as offset.
void checkPenetration(SoakMonitor& m, const World& world) {
  const std::uint64_t step = world.steps;
  SoakStats& s = m.stats;
  if (const SphFluid* fluid = findState<SphFluid>(world)) {
    const fluid::SphWorld& sph = fluid->world;
    const float radius = sph.params.particle_radius;
    // Where a moving collider (a crate) overlaps another (the fountain, or a crate a blast pressed
    // into it), no position is outside both and the solver leaves a particle between them inside
    // one (fluid/sph: still colliders win, else the last resolved): inside a crate only counts
    // where its way out is not inside another collider (worstFreePenetration).
    std::size_t squeezed_now = 0;
    for (std::size_t c = 0; c < sph.colliders.size(); ++c) {
      const fluid::SphCollider& collider = sph.colliders[c];
      std::size_t squeezed = 0;
      Penetration p;
      if (fluid::sphColliderMoves(collider)) {
        m.blockers.clear();
        for (std::size_t o = 0; o < sph.colliders.size(); ++o)
          if (o != c) m.blockers.push_back({sph.colliders[o].shape.get(), sph.colliders[o].pose});
        p = worstFreePenetration(sph.particles.position, *collider.shape, collider.pose, m.blockers, radius, m.scratch,
                                 squeezed);
      } else {
        p = worstPenetration(sph.particles.position, *collider.shape, collider.pose, radius, 0.0f, m.scratch);
      }
      squeezed_now += squeezed;
      if (p.ratio > s.worst_sph) {
        s.worst_sph = p.ratio;
        s.worst_sph_step = step;
      }
      if (p.ratio > m.desc.particle_tolerance) {
        fail(m, step,
             describe(("sph particle id " + std::to_string(sph.particles.id[p.index]) + " (SPH collider " +
                       std::to_string(c) + (fluid::sphColliderMoves(collider) ? ", moving)" : ", still)"))
                          .c_str(),
                      p, m.desc.particle_tolerance) +
                 collidersNear(sph, p.position, m.scratch));
      }
    }
    s.sph_squeezed_frames += squeezed_now > 0 ? 1u : 0u;
    s.sph_squeezed_max = std::max(s.sph_squeezed_max, squeezed_now);
  }
  if (const SpriteParticles* sp_state = findState<SpriteParticles>(world)) {
    // The GPU sprites as read back after their last step (soak: every step), against the depth
    // maps they collide with on the GPU (baked from the same models; the CPU lookup of
    // fluid/collide is the reference the shader decodes).
    const SpriteParticles& sp = *sp_state;
    m.points.clear();
    for (const glm::vec4& p : sp.sample_positions) m.points.emplace_back(p);
    const std::size_t parts = sp.level_colliders ? sp.level_colliders->parts.size() : 0;
    for (std::size_t c = 0; c < parts; ++c) {
      const Penetration p = worstPenetration(m.points, sp.level_colliders->parts[c].collider, fluid::ColliderPose{},
                                             sp.params.size, 0.0f, m.scratch);
      if (p.ratio > s.worst_sprite) {
        s.worst_sprite = p.ratio;
        s.worst_sprite_step = step;
      }
      if (p.ratio > m.desc.particle_tolerance) {
        fail(m, step,
             describe(("live sprite " + std::to_string(p.index) + " (" + sp.collider_names[c] + ")").c_str(), p,
                      m.desc.particle_tolerance));
      }
    }
  }
  // The crates against the fountain's analytic shape: only the fountain level has it (the blob
  // monster's street has no basin for a crate to be inside).
  const RigidBodies* bodies_state = findState<RigidBodies>(world);
  if (bodies_state != nullptr && world.scene.scene.text("level") == "fountain") {
    const RigidBodies& bodies = *bodies_state;
    m.points.clear();
    for (const engine::BodyState& state : bodies.current) m.points.push_back(state.position);
    const float size = bodies.params.crate_size;
    if (!m.level) m.level = world.links.colliders;
    std::string error;
    if (!ensureFountainColliders(contentDir(), m.level, error)) return fail(m, step, "level colliders: " + error);
    // Crate centres against every part with the half edge as offset. The depth maps answer
    // "beyond reach" farther than their margin from a part: a centre that far is no penetration.
    for (std::size_t c = 0; c < m.level->parts.size(); ++c) {
      const Penetration p =
          worstPenetration(m.points, m.level->parts[c].collider, fluid::ColliderPose{}, size, 0.5f * size, m.scratch);
      if (p.ratio > s.worst_crate) {
        s.worst_crate = p.ratio;
        s.worst_crate_step = step;
      }
      if (p.ratio > m.desc.crate_tolerance) {
        fail(m, step,
             describe(("crate " + std::to_string(p.index) + " (edge " + std::to_string(size) + " m, " +
                       m.level->parts[c].name + ")")
                          .c_str(),
                      p, m.desc.crate_tolerance));
      }
    }
  }
}

}  // namespace

SoakMonitor makeSoakMonitor(const SoakDesc& desc, double step_seconds) {
  SoakMonitor m;
  m.desc = desc;
  m.desc.throws.step_seconds = step_seconds;
  m.schedule = makeThrowSchedule(m.desc.throws, desc.seed);
  m.warmup_steps = std::max(static_cast<std::uint64_t>(desc.warmup_fraction * static_cast<double>(desc.steps)),
                            static_cast<std::uint64_t>(std::llround(desc.min_warmup_seconds / step_seconds)));
  // Reserved now so the samples' own storage never shows up as growth.
  m.rss_samples.reserve(static_cast<std::size_t>(desc.steps / std::max<std::uint64_t>(desc.memory_every, 1) + 2));
  m.heap_samples.reserve(m.rss_samples.capacity());
  return m;
}

void soakBeforeStep(SoakMonitor& m, World& world, std::uint64_t step) {
  if (m.desc.progress_fd >= 0) {
    // The parent keeps the last number it read: the step a crashed child was in.
    char line[32];
    const int length = std::snprintf(line, sizeof(line), "%llu\n", static_cast<unsigned long long>(step + 1));
    if (::write(m.desc.progress_fd, line, static_cast<std::size_t>(length)) < 0) m.desc.progress_fd = -1;
  }
  // The sprites live on the GPU: read them back after every step so the NaN and penetration
  // checks see every live sprite (World::nonfinite_state and checkPenetration use the sample).
  if (SpriteParticles* sprites = findState<SpriteParticles>(world)) sprites->readback_every = 1;
  if (const std::optional<PlayerThrow> due = throwDue(m.schedule, step); due && findState<RigidBodies>(world)) {
    m.stats.explosives += throwAt(world, *due) ? 1 : 0;
    ++m.stats.throws;
  }
}

bool soakAfterFrame(SoakMonitor& m, const World& world) {
  SoakStats& s = m.stats;
  s.steps = world.steps;
  if (!world.nonfinite_state.empty()) fail(m, world.steps, "non-finite state: " + world.nonfinite_state);
  if (world.failures.count > 0) fail(m, world.steps, "run-time failure: " + world.failures.first);
  s.has_sph = findState<SphFluid>(world) != nullptr;
  s.has_sprites = findState<SpriteParticles>(world) != nullptr;
  s.has_crates = findState<RigidBodies>(world) != nullptr;
  if (const SphFluid* fluid = findState<SphFluid>(world)) {
    const fluid::ParticleStore& p = fluid->world.particles;
    trackCount(p.size(), !m.have_counts, s.sph_min, s.sph_max);
    s.max_speed = std::max(s.max_speed, maxSpeed(p.velocity));
  }
  if (const SpriteParticles* sp_state = findState<SpriteParticles>(world)) {
    const SpriteParticles& sp = *sp_state;
    trackCount(liveSprites(sp), !m.have_counts, s.sprite_min, s.sprite_max);
    for (const glm::vec4& v : sp.sample_velocities) s.max_speed = std::max(s.max_speed, glm::length(glm::vec3(v)));
    // The read-back must be fresh: a check of stale data would pass whatever the GPU did.
    if (sp.attached && sp.readback_every > 0 && sp.sample_step != sp.steps)
      fail(m, world.steps,
           "sprite read-back is stale (step " + std::to_string(sp.sample_step) + " of " + std::to_string(sp.steps) +
               ")");
  }
  if (const RigidBodies* bodies = findState<RigidBodies>(world)) {
    for (const engine::BodyState& state : bodies->current)
      s.max_crate_speed = std::max(s.max_crate_speed, glm::length(state.linear_velocity));
  }
  m.have_counts = true;
  checkPenetration(m, world);
  const bool go_on = m.failure.empty() && world.steps < m.desc.steps;
  // The first blast allocates what every later one reuses (about 7 MiB of heap in the fountain):
  // part of warm-up, so the memory samples start again after it.
  const std::uint64_t detonated = world.links.explosives ? world.links.explosives->detonated : 0;
  if (detonated > 0 && m.detonations_seen == 0 && !m.rss_samples.empty()) {
    m.rss_samples.clear();
    m.heap_samples.clear();
    s.memory_restart_step = world.steps;
  }
  m.detonations_seen = detonated;
  if (world.steps >= m.warmup_steps && (world.steps % std::max<std::uint64_t>(m.desc.memory_every, 1) == 0 || !go_on)) {
    releaseFreeMemory();
    const std::uint64_t rss = residentBytes(), heap = heapInUseBytes();
    if (m.rss_samples.empty()) s.rss_warmup = rss, s.heap_warmup = heap;
    m.rss_samples.push_back(rss);
    m.heap_samples.push_back(heap);
    s.rss_end = rss;
    s.heap_end = heap;
  }
  return go_on;
}

void finishSoak(SoakMonitor& m) {
  // The resident set on its trend, the heap in use on its trend and final level (checkMemoryGrowth
  // says why); no heap figure (not glibc): the resident set on both.
  const bool have_heap = !m.heap_samples.empty() && m.heap_samples.front() > 0;
  m.stats.memory = checkMemoryGrowth(m.rss_samples, m.desc.memory, !have_heap);
  if (have_heap) m.stats.heap_memory = checkMemoryGrowth(m.heap_samples, m.desc.memory);
  std::string failure = m.stats.memory.failure;
  if (failure.empty() && !m.stats.heap_memory.failure.empty()) failure = "heap in use: " + m.stats.heap_memory.failure;
  // A run that already failed stopped early: its samples say nothing about the trend.
  if (m.desc.check_memory && m.failure.empty() && !failure.empty()) fail(m, m.stats.steps, failure);
}

std::string soakSummary(const SoakMonitor& m) {
  const SoakStats& s = m.stats;
  const double mib = 1024.0 * 1024.0;
  char part[160];
  // Only the systems the scene has: "sph 0..0" of a scene without water would read as a failure.
  auto add = [&](std::string& out, const char* format, auto... values) {
    std::snprintf(part, sizeof(part), format, values...);
    out += part;
  };
  std::string line, worst;
  add(line, "%llu steps, %d throws (%d explosives)", static_cast<unsigned long long>(s.steps), s.throws, s.explosives);
  if (s.has_sph) {
    add(line, ", sph %zu..%zu", s.sph_min, s.sph_max);
    add(worst, " sph %.3f (step %llu)", static_cast<double>(s.worst_sph),
        static_cast<unsigned long long>(s.worst_sph_step));
    if (s.sph_squeezed_frames > 0)
      add(worst, " [squeezed between a crate and another collider: up to %zu particles, in %llu frames]",
          s.sph_squeezed_max, static_cast<unsigned long long>(s.sph_squeezed_frames));
  }
  if (s.has_sprites) {
    add(line, ", sprites %zu..%zu", s.sprite_min, s.sprite_max);
    add(worst, "%s sprites %.3f (step %llu)", worst.empty() ? "" : ",", static_cast<double>(s.worst_sprite),
        static_cast<unsigned long long>(s.worst_sprite_step));
  }
  if (s.has_sph || s.has_sprites) add(line, ", max particle speed %.2f m/s", static_cast<double>(s.max_speed));
  if (s.has_crates) {
    add(line, ", max crate speed %.2f m/s", static_cast<double>(s.max_crate_speed));
    add(worst, "%s crates %.3f (step %llu)", worst.empty() ? "" : ",", static_cast<double>(s.worst_crate),
        static_cast<unsigned long long>(s.worst_crate_step));
  }
  if (s.memory_restart_step > 0)
    add(line, ", memory from step %llu (the first blast's)", static_cast<unsigned long long>(s.memory_restart_step));
  if (m.rss_samples.size() < 3) {
    add(line, ", RSS not judged (%zu samples after warm-up)", m.rss_samples.size());
  } else {
    add(line, ", RSS %.1f -> %.1f MiB", static_cast<double>(s.rss_warmup) / mib, static_cast<double>(s.rss_end) / mib);
    if (s.heap_warmup > 0)
      add(line, " (heap in use %.1f -> %.1f)", static_cast<double>(s.heap_warmup) / mib,
          static_cast<double>(s.heap_end) / mib);
  }
  if (!worst.empty()) line += ", worst penetration/radius:" + worst;
  return line;
}

}  // namespace game
