#include "game/soak_monitor.hpp"

#include "game/explosives/explosives.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <span>
#include <vector>

namespace game {
namespace {

// Moves the camera to the thrower's place and throws along a lob that lands near the target: a
// crate leaves along the camera's forward axis at its throw_speed, so aim above the target by the
// drop over the flight (flight time from the straight distance, ignoring the arc's extra length).
// An explosive leaves at its own throw speed, lobbed above the camera's axis by lob_degrees (its
// fuse, not the landing point, decides where it blows: near enough for the soak). Returns whether
// an explosive was thrown (a scene without the explosives effect throws a crate instead).
bool throwAt(World& world, const PlayerThrow& t) {
  const RigidBodies& bodies = *world.links.bodies;
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

// Each gauge's drift so far: the medians of the first and last thirds of its samples, as the
// memory's trend (fewer than 3 samples: none yet).
std::vector<SoakStats::GaugeDrift> gaugeDrifts(const SoakMonitor& m) {
  std::vector<SoakStats::GaugeDrift> out;
  const double span_s = static_cast<double>(m.stats.steps - m.gauge_first_step) * m.desc.throws.step_seconds;
  for (std::size_t g = 0; g < m.gauge_samples.size(); ++g) {
    const std::vector<double>& samples = m.gauge_samples[g];
    if (samples.size() < 3) continue;
    const std::size_t third = samples.size() / 3;
    out.push_back({m.probe.gauges[g].name, m.probe.gauges[g].unit, medianOf(std::span(samples).first(third)),
                   medianOf(std::span(samples).last(third)), span_s >= m.desc.gauge_min_seconds});
  }
  return out;
}

}  // namespace

SoakMonitor makeSoakMonitor(const SoakDesc& desc, double step_seconds) {
  SoakMonitor m;
  m.desc = desc;
  m.probe.particle_tolerance = desc.particle_tolerance;
  m.probe.crate_tolerance = desc.crate_tolerance;
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
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->soakBeforeStep(m.probe);
  if (const std::optional<PlayerThrow> due = throwDue(m.schedule, step); due && world.links.bodies != nullptr) {
    m.stats.explosives += throwAt(world, *due) ? 1 : 0;
    ++m.stats.throws;
  }
}

bool soakAfterFrame(SoakMonitor& m, const World& world) {
  SoakStats& s = m.stats;
  s.steps = world.steps;
  SoakProbe& probe = m.probe;
  probe.step = world.steps;
  if (!world.nonfinite_state.empty()) probe.fail("non-finite state: " + world.nonfinite_state);
  if (world.failures.count > 0) probe.fail("run-time failure: " + world.failures.first);
  if (probe.level.empty()) probe.level = world.scene.scene.text("level");
  if (!probe.level_colliders) probe.level_colliders = world.links.colliders;
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->soakCheck(probe);
  if (m.failure.empty()) m.failure = probe.failure;
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
    // The gauges' samples are not started again at the first blast: they are no memory figure.
    if (m.gauge_samples.size() < probe.gauges.size()) {
      m.gauge_samples.resize(probe.gauges.size());
      for (std::vector<double>& g : m.gauge_samples) g.reserve(m.rss_samples.capacity());
    }
    if (!m.gauge_samples.empty() && m.gauge_samples.front().empty()) m.gauge_first_step = world.steps;
    for (std::size_t g = 0; g < probe.gauges.size(); ++g) m.gauge_samples[g].push_back(probe.gauges[g].value);
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
  m.stats.gauges = gaugeDrifts(m);
  for (const SoakStats::GaugeDrift& d : m.stats.gauges) {
    if (!d.judged || !m.failure.empty() || std::abs(d.last - d.first) <= m.desc.gauge_drift * std::abs(d.first))
      continue;
    char text[200];
    std::snprintf(text, sizeof(text), "step %llu: %s drifts from %.4g to %.4g %s (%+.2f %%, allowed %.2f %%)",
                  static_cast<unsigned long long>(m.stats.steps), d.name.c_str(), d.first, d.last, d.unit.c_str(),
                  100.0 * (d.last - d.first) / d.first, 100.0 * m.desc.gauge_drift);
    m.failure = text;
  }
  // The resident set on its trend, the heap in use on its trend and final level (checkMemoryGrowth
  // says why); no heap figure (not glibc): the resident set on both.
  const bool have_heap = !m.heap_samples.empty() && m.heap_samples.front() > 0;
  m.stats.memory = checkMemoryGrowth(m.rss_samples, m.desc.memory, !have_heap);
  if (have_heap) m.stats.heap_memory = checkMemoryGrowth(m.heap_samples, m.desc.memory);
  std::string failure = m.stats.memory.failure;
  if (failure.empty() && !m.stats.heap_memory.failure.empty()) failure = "heap in use: " + m.stats.heap_memory.failure;
  // A run that already failed stopped early: its samples say nothing about the trend.
  if (m.desc.check_memory && m.failure.empty() && !failure.empty())
    m.failure = "step " + std::to_string(m.stats.steps) + ": " + failure;
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
  const SoakProbe& probe = m.probe;
  std::string line, worst;
  add(line, "%llu steps, %d throws (%d explosives)", static_cast<unsigned long long>(s.steps), s.throws, s.explosives);
  for (const SoakProbe::Range& r : probe.ranges) add(line, ", %s %zu..%zu", r.name.c_str(), r.min, r.max);
  if (probe.has_particles) add(line, ", max particle speed %.2f m/s", static_cast<double>(probe.max_particle_speed));
  if (probe.has_bodies) add(line, ", max crate speed %.2f m/s", static_cast<double>(probe.max_body_speed));
  for (const SoakProbe::Worst& w : probe.worst)
    add(worst, "%s %s %.3f (step %llu)", worst.empty() ? "" : ",", w.name.c_str(), static_cast<double>(w.ratio),
        static_cast<unsigned long long>(w.step));
  if (probe.squeezed_frames > 0)
    add(worst, " [squeezed between a moving collider and another: up to %zu particles, in %llu frames]",
        probe.squeezed_max, static_cast<unsigned long long>(probe.squeezed_frames));
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
  // Before finishSoak (the progress lines of a long run): the drift so far.
  for (const SoakStats::GaugeDrift& g : s.gauges.empty() ? gaugeDrifts(m) : s.gauges)
    add(line, ", %s %.4g -> %.4g %s (%+.2f %%, %s)", g.name.c_str(), g.first, g.last, g.unit.c_str(),
        100.0 * (g.last - g.first) / g.first, g.judged ? "judged" : "not judged: samples span under gauge_min_seconds");
  if (!worst.empty()) line += ", worst penetration/radius:" + worst;
  return line;
}

}  // namespace game
