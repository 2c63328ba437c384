#include "game/soak_checks.hpp"

#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace game {
namespace {

std::string mebibytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return text;
}

// Uniform in [0, 1) from the generator's top 24 bits: the same numbers on every standard library
// (std::uniform_real_distribution's algorithm is implementation-defined).
float uniform01(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

float uniformIn(std::mt19937& rng, float lo, float hi) { return lo + (hi - lo) * uniform01(rng); }

std::uint64_t stepsUntilNext(ThrowSchedule& s) {
  const double interval = s.desc.mean_interval_s * (0.5 + static_cast<double>(uniform01(s.rng)));
  return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::llround(interval / s.desc.step_seconds)));
}

}  // namespace

std::uint64_t residentBytes() {
  std::FILE* file = std::fopen("/proc/self/statm", "r");
  if (file == nullptr) return 0;
  unsigned long long size = 0, resident = 0;
  const int read = std::fscanf(file, "%llu %llu", &size, &resident);
  std::fclose(file);
  const long page = sysconf(_SC_PAGESIZE);
  if (read != 2 || page <= 0) return 0;
  return resident * static_cast<std::uint64_t>(page);
}

std::uint64_t heapInUseBytes() {
#if defined(__GLIBC__)
  const struct mallinfo2 info = mallinfo2();
  return static_cast<std::uint64_t>(info.uordblks) + static_cast<std::uint64_t>(info.hblkhd);
#else
  return 0;
#endif
}

void releaseFreeMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

MemoryGrowth checkMemoryGrowth(std::span<const std::uint64_t> samples, const MemoryGrowthDesc& desc, bool judge_final) {
  MemoryGrowth out;
  if (samples.size() < 3) return out;
  const std::size_t third = samples.size() / 3;
  out.first_level = medianOf(samples.first(third));
  out.last_level = medianOf(samples.last(third));
  out.final_sample = samples.back();
  out.bound = std::max(desc.min_growth_bytes,
                       static_cast<std::uint64_t>(desc.max_growth_fraction * static_cast<double>(out.first_level)));
  const std::uint64_t limit = out.first_level + out.bound;
  if (out.last_level > limit) {
    out.failure = "memory grows after warm-up: resident set " + mebibytes(out.first_level) + " -> " +
                  mebibytes(out.last_level) + " (medians of the first and last thirds of " +
                  std::to_string(samples.size()) + " samples; allowed growth " + mebibytes(out.bound) + ")";
  } else if (judge_final && out.final_sample > limit) {
    out.failure = "memory ends high: resident set " + mebibytes(out.final_sample) + " at the end against " +
                  mebibytes(out.first_level) + " after warm-up (allowed growth " + mebibytes(out.bound) + ")";
  }
  return out;
}

namespace {

// The shape's samples of world-space `points` at `pose`, into scratch.samples.
void queryInColliderSpace(std::span<const glm::vec3> points, const fluid::SignedDistanceShape& shape,
                          const fluid::ColliderPose& pose, PenetrationScratch& scratch) {
  scratch.local.resize(points.size());
  scratch.samples.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) scratch.local[i] = fluid::toColliderSpace(pose, points[i]);
  shape.query(scratch.local, scratch.samples);
}

}  // namespace

Penetration worstPenetration(std::span<const glm::vec3> points, const fluid::SignedDistanceShape& shape,
                             const fluid::ColliderPose& pose, float radius, float offset, PenetrationScratch& scratch) {
  Penetration worst;
  if (points.empty()) return worst;
  queryInColliderSpace(points, shape, pose, scratch);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const fluid::ColliderSample& s = scratch.samples[i];
    if (!s.valid) continue;
    const float depth = offset - s.distance;
    if (depth > worst.depth) {
      worst.depth = depth;
      worst.index = i;
      worst.position = points[i];
    }
  }
  worst.ratio = radius > 0.0f ? worst.depth / radius : 0.0f;
  return worst;
}

Penetration worstFreePenetration(std::span<const glm::vec3> points, const fluid::SignedDistanceShape& shape,
                                 const fluid::ColliderPose& pose, std::span<const PlacedShape> blockers, float radius,
                                 PenetrationScratch& scratch, std::size_t& squeezed) {
  Penetration worst;
  squeezed = 0;
  if (points.empty()) return worst;
  queryInColliderSpace(points, shape, pose, scratch);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const fluid::ColliderSample s = scratch.samples[i];
    if (!s.valid || s.distance >= 0.0f) continue;
    // The way out: the surface point along the outward normal (world space).
    const glm::vec3 exit = points[i] - s.distance * fluid::toWorldDirection(pose, s.normal);
    bool blocked = false;
    for (const PlacedShape& other : blockers) {
      const glm::vec3 local = fluid::toColliderSpace(other.pose, exit);
      fluid::ColliderSample o;
      other.shape->query(std::span<const glm::vec3>(&local, 1), std::span<fluid::ColliderSample>(&o, 1));
      blocked = blocked || (o.valid && o.distance < 0.0f);
    }
    if (blocked) {
      ++squeezed;
      continue;
    }
    if (-s.distance > worst.depth) {
      worst.depth = -s.distance;
      worst.index = i;
      worst.position = points[i];
    }
  }
  worst.ratio = radius > 0.0f ? worst.depth / radius : 0.0f;
  return worst;
}

ThrowSchedule makeThrowSchedule(const ThrowScheduleDesc& desc, std::uint32_t seed) {
  ThrowSchedule s;
  s.desc = desc;
  s.rng.seed(seed);
  s.next_step = desc.mean_interval_s > 0.0 && desc.step_seconds > 0.0 ? stepsUntilNext(s) : UINT64_MAX;
  return s;
}

std::optional<PlayerThrow> throwDue(ThrowSchedule& s, std::uint64_t step) {
  if (step < s.next_step) return std::nullopt;
  PlayerThrow t;
  t.step = step;
  const float two_pi = 2.0f * std::numbers::pi_v<float>;
  const float stand_angle = two_pi * uniform01(s.rng);
  const float stand_radius = uniformIn(s.rng, s.desc.stand_radius_min, s.desc.stand_radius_max);
  t.from = glm::vec3(std::cos(stand_angle) * stand_radius,
                     uniformIn(s.rng, s.desc.stand_height_min, s.desc.stand_height_max),
                     std::sin(stand_angle) * stand_radius);
  // Uniform over the disc's area: radius from the square root.
  const float target_angle = two_pi * uniform01(s.rng);
  const float target_radius = s.desc.target_radius * std::sqrt(uniform01(s.rng));
  t.target = glm::vec3(std::cos(target_angle) * target_radius, uniformIn(s.rng, 0.0f, s.desc.target_height_max),
                       std::sin(target_angle) * target_radius);
  // Drawn for every throw, whatever the share, so the share changes what is thrown and nothing else.
  t.explosive = uniform01(s.rng) < s.desc.explosive_share;
  s.next_step = step + stepsUntilNext(s);
  return t;
}

void SoakProbe::fail(const std::string& what) {
  if (failure.empty()) failure = "step " + std::to_string(step) + ": " + what;
}

void SoakProbe::count(std::string_view name, std::size_t value) {
  for (Range& r : ranges)
    if (r.name == name) {
      r.min = std::min(r.min, value);
      r.max = std::max(r.max, value);
      return;
    }
  ranges.push_back({std::string(name), value, value});
}

void SoakProbe::penetration(std::string_view name, const Penetration& p, float tolerance, const std::string& what) {
  auto known = std::find_if(worst.begin(), worst.end(), [&](const Worst& w) { return w.name == name; });
  if (known == worst.end()) known = worst.insert(worst.end(), Worst{std::string(name), 0.0f, step});
  if (p.ratio > known->ratio) {
    known->ratio = p.ratio;
    known->step = step;
  }
  if (p.ratio > tolerance) fail(describePenetration(what, p, tolerance));
}

void SoakProbe::particleSpeed(float speed) {
  has_particles = true;
  max_particle_speed = std::max(max_particle_speed, speed);
}

void SoakProbe::bodySpeed(float speed) {
  has_bodies = true;
  max_body_speed = std::max(max_body_speed, speed);
}

void SoakProbe::gauge(std::string_view name, double value, std::string_view unit) {
  for (Gauge& g : gauges)
    if (g.name == name) {
      g.value = value;
      return;
    }
  gauges.push_back({std::string(name), std::string(unit), value});
}

const SoakProbe::Range* SoakProbe::range(std::string_view name) const {
  for (const Range& r : ranges)
    if (r.name == name) return &r;
  return nullptr;
}

std::string describePenetration(const std::string& what, const Penetration& p, float tolerance) {
  char text[160];
  std::snprintf(text, sizeof(text), " %.4f m inside a collider (%.2f radii, tolerance %.2f) at (%.3f, %.3f, %.3f)",
                p.depth, p.ratio, tolerance, p.position.x, p.position.y, p.position.z);
  return what + text;
}

}  // namespace game
