#pragma once
// The checks `fluiddemo soak` applies to a long run (game/commands/soak_command.cpp), as plain
// functions on plain data so each can be shown to fire on a crafted bad case (tests/game):
//  - memory that grows after warm-up (resident set sampled from /proc/self/statm),
//  - a particle (or a crate) inside a collider, measured as penetration depth over its radius,
//  - the seeded schedule of crate throws (the same seed throws the same crates at the same steps).

#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace game {

// ---- memory ----------------------------------------------------------------------------------

// Resident set size of this process in bytes (/proc/self/statm, field 2 times the page size);
// 0 where it cannot be read.
std::uint64_t residentBytes();

// Bytes the C allocator has handed out and not had back (glibc: mallinfo2's uordblks + hblkhd, every
// arena and the mmapped blocks); 0 where that is not known. Unlike the resident set it does not see
// freed heap the allocator keeps because it cannot hand it back (fragmentation after a short peak).
std::uint64_t heapInUseBytes();

// Hands the allocator's free pages back to the system (glibc malloc_trim; nothing elsewhere), so
// that a following residentBytes() counts live memory: without it a leak first refills the tens
// of MiB that start-up freed but the heap kept resident, and stays invisible until they are used up.
void releaseFreeMemory();

// The upper median of a copy of `values` (non-empty; the samples keep their order): the memory
// trend's and the gauges' thirds (checkMemoryGrowth below, gaugeDrifts in game/soak_monitor.cpp).
template <class T>
T medianOf(std::span<const T> values) {
  std::vector<T> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  return sorted[sorted.size() / 2];
}

// Bound on the growth of the resident set after warm-up (sampled after releaseFreeMemory). A soak
// fails when it grows by more than max(min_growth_bytes, max_growth_fraction * level), level being
// the median of the first third of the samples. Why this bound: without a leak the sampled RSS
// still moves by a few MiB (buffers whose capacity follows their high-water mark, e.g. the
// fountain's surface mesh and the solver's scratch, and the malloc arenas of the worker threads);
// 8 MiB sits above that, and 5 % keeps the bound meaningful for bigger scenes whose buffers scale
// with their size. What it catches: a leak of L bytes per step moves the last third's median by
// L x 0.53 x steps (after a 20 % warm-up the thirds' medians are 0.53 of the run apart) and the
// last sample by L x 0.67 x steps, so the 3,600-step ctest run catches about 3.5 KiB/step and up,
// the 216,000-step nightly run about 60 B/step (8 MiB over 144,000 steps).
struct MemoryGrowthDesc {
  std::uint64_t min_growth_bytes = 8ull << 20;  // 8 MiB
  double max_growth_fraction = 0.05;
};

struct MemoryGrowth {
  std::uint64_t first_level = 0;  // median of the first third of the samples
  std::uint64_t last_level = 0;   // median of the last third
  std::uint64_t final_sample = 0;
  std::uint64_t bound = 0;  // allowed growth, bytes
  std::string failure;      // empty when neither the trend nor the final level exceeds the bound
};

// `samples` are memory sizes taken at equal intervals after warm-up. Two checks, both against
// the first third's median: steady growth (the last third's median) and, with `judge_final`, the
// final level (the last sample, so a late jump that the median would hide still fails). Fewer than
// 3 samples: nothing to compare, no failure. The soak judges the resident set on its trend only and
// the heap in use on both: a short peak of temporaries (a blast's splash) can leave the resident set
// higher for good, as freed heap the allocator cannot hand back, which is no leak; a leak through
// the allocator shows in the heap's trend and final level, one outside it in the resident set's trend.
MemoryGrowth checkMemoryGrowth(std::span<const std::uint64_t> samples, const MemoryGrowthDesc& desc = {},
                               bool judge_final = true);

// ---- particles inside colliders ---------------------------------------------------------------

// The deepest point of a set inside one collider.
struct Penetration {
  float depth = 0.0f;        // m below the surface (0 when every point is outside)
  float ratio = 0.0f;        // depth / radius
  std::size_t index = 0;     // which point
  glm::vec3 position{0.0f};  // where it is (world space)
};

// Scratch for worstPenetration (caller-owned, reused every frame).
struct PenetrationScratch {
  std::vector<glm::vec3> local;
  std::vector<fluid::ColliderSample> samples;
};

// Deepest penetration of the points (world space) into `shape` placed at `pose` (collider space =
// rotation^-1 (world - translation)). A point counts `inset` metres deep when its signed distance
// is -inset; `offset` is subtracted from every distance first (for a crate: its half edge, so a
// crate centre nearer than that to the surface counts as the box reaching into the solid).
// Invalid samples (no opinion) count as outside. `radius` scales the ratio.
Penetration worstPenetration(std::span<const glm::vec3> points, const fluid::SignedDistanceShape& shape,
                             const fluid::ColliderPose& pose, float radius, float offset, PenetrationScratch& scratch);

// A placed collider that can block a particle's way out (worstFreePenetration).
struct PlacedShape {
  const fluid::SignedDistanceShape* shape = nullptr;
  fluid::ColliderPose pose;
};

// Deepest penetration of the points into a collider that moves (a crate coupled to the SPH fluid),
// leaving out the points that have no free position there. Where a moving collider overlaps a still
// one the SPH solver lets the still one win (fluid/sph/sph.hpp, sphColliderMoves), so a particle
// squeezed between a crate and the basin ends outside the basin and inside the crate; where two
// crates overlap (a blast presses them together), the one resolved last wins. A point counts as
// squeezed when its way out of `shape`, the nearest point of its surface (p - distance * normal),
// lies inside one of `blockers` (distance < 0): the other colliders, still or moving. `squeezed`
// receives how many points were left out for that reason.
Penetration worstFreePenetration(std::span<const glm::vec3> points, const fluid::SignedDistanceShape& shape,
                                 const fluid::ColliderPose& pose, std::span<const PlacedShape> blockers, float radius,
                                 PenetrationScratch& scratch, std::size_t& squeezed);

// ---- what each effect checks (Effect::soakBeforeStep / soakCheck) -----------------------------

struct LevelColliders;  // game/world/fountain.hpp

// What an effect's soak check reads and reports into. The monitor (game/soak_monitor.hpp) owns one
// for the run, sets `step` before every frame's checks and prints the tallies in its summary; an
// effect names its own particles and bodies, so nothing outside it knows what it checks.
struct SoakProbe {
  std::uint64_t step = 0;
  // Tolerated penetration as a fraction of the particle radius and of a crate's edge (SoakDesc).
  float particle_tolerance = 0.25f;
  float crate_tolerance = 0.5f;
  std::string level;  // the scene's level ("fountain", ...)
  // The level's baked colliders: the world's (EffectLinks::colliders) or loaded by the first check
  // that needs them.
  std::shared_ptr<const LevelColliders> level_colliders;
  PenetrationScratch scratch;
  std::vector<glm::vec3> points;
  std::vector<PlacedShape> blockers;
  std::string failure;  // the first failure, "step N: what"

  struct Range {  // a count over the run's frames ("sph", "sprites")
    std::string name;
    std::size_t min = 0, max = 0;
  };
  struct Worst {  // the deepest penetration / radius of one kind of thing, and when
    std::string name;
    float ratio = 0.0f;
    std::uint64_t step = 0;
  };
  std::vector<Range> ranges;  // in the order first reported
  std::vector<Worst> worst;
  float max_particle_speed = 0.0f;  // m/s, fastest particle of any effect
  float max_body_speed = 0.0f;      // m/s, fastest rigid body
  bool has_particles = false, has_bodies = false;
  // Particles inside a moving collider where it reaches into another (no free position; not failures,
  // see worstFreePenetration): the most in one frame, and the frames with any.
  std::size_t squeezed_max = 0;
  std::uint64_t squeezed_frames = 0;
  struct Gauge {  // a quantity that should hold steady over a long run (the pool's level), as of this frame
    std::string name;
    std::string unit;
    double value = 0.0;
  };
  std::vector<Gauge> gauges;  // in the order first reported

  void fail(const std::string& what);
  void count(std::string_view name, std::size_t value);
  // Records `p` as a candidate for the deepest of `name`; fails naming `what` beyond `tolerance`.
  void penetration(std::string_view name, const Penetration& p, float tolerance, const std::string& what);
  void particleSpeed(float speed);
  void bodySpeed(float speed);
  // Sets gauge `name` to this frame's value; the monitor samples it after warm-up and judges its drift
  // (SoakDesc::gauge_drift).
  void gauge(std::string_view name, double value, std::string_view unit);
  const Range* range(std::string_view name) const;  // null when never counted
};

// "<what> 0.0123 m inside a collider (0.49 radii, tolerance 0.25) at (x, y, z)"
std::string describePenetration(const std::string& what, const Penetration& p, float tolerance);

// ---- the player's throws: crates and fused explosives -----------------------------------------

// Where soak throws come from and go: the thrower stands on a ring around the fountain (so throws
// come from every side and the camera, which the surface is meshed for, sees it from everywhere)
// and aims at a random point of the basin and the yard around it. A share of the throws are fused
// explosives (the right mouse button), so blasts hit the water, the crates and the sprites too.
struct ThrowScheduleDesc {
  double mean_interval_s = 2.0;   // intervals uniform in [0.5, 1.5] x this; <= 0: never throw
  double explosive_share = 0.25;  // chance that a throw is an explosive, [0, 1]; 0 = crates only
  double step_seconds = 1.0 / 60.0;
  float stand_radius_min = 6.0f, stand_radius_max = 10.0f;  // m from the fountain's axis
  float stand_height_min = 1.5f, stand_height_max = 4.0f;   // eye height, m
  float target_radius = 4.5f;                               // targets within this disc (basin 3.2 m)
  float target_height_max = 1.0f;                           // targets at y in [0, this]
};

struct PlayerThrow {
  std::uint64_t step = 0;  // thrown just before this step (world.steps == step)
  glm::vec3 from{0.0f};
  glm::vec3 target{0.0f};
  bool explosive = false;  // a fused explosive instead of a crate
};

struct ThrowSchedule {
  ThrowScheduleDesc desc;
  std::mt19937 rng;
  std::uint64_t next_step = 0;
};

ThrowSchedule makeThrowSchedule(const ThrowScheduleDesc& desc, std::uint32_t seed);

// The throw due before `step`, if any (at most one per step); advances the schedule past it.
// Call with every step in increasing order: the sequence depends only on the seed and desc, and
// the steps, places and targets not on explosive_share (which only decides what is thrown).
std::optional<PlayerThrow> throwDue(ThrowSchedule& schedule, std::uint64_t step);

}  // namespace game
