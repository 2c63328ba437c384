#pragma once
// What `fluiddemo soak` does to a running World through runScene's hooks (FrameHooks::before_steps
// and after_frame): throws crates on a seeded schedule, and after every frame applies the soak
// checks (game/soak_checks.hpp) and keeps the run's statistics. The first failure stops the run.

#include "game/soak_checks.hpp"
#include "game/world/fountain.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace game {

struct World;

struct SoakDesc {
  std::uint64_t steps = 3600;  // run length; the monitor asks to stop after this many steps
  // Memory is judged on the samples after warm-up: this share of the run, and at least
  // min_warmup_seconds of game time (twice what the fountain takes to fill its 2,500-particle budget
  // at 500 particles/s, after which its buffers have their working size). The samples also start
  // again at the first blast, whose allocations every later one reuses. A run too short to leave
  // 3 samples after it is not judged.
  double warmup_fraction = 0.2;
  double min_warmup_seconds = 10.0;
  std::uint64_t memory_every = 30;  // steps between resident-set samples
  ThrowScheduleDesc throws;         // step_seconds is taken from the world
  std::uint32_t seed = 1;
  // Tolerated penetration as a fraction of the particle radius (SPH particle_radius, sprite size).
  // The SPH solver and the sprites end every step with the particle centre on or outside every
  // collider surface (Kolb et al. 2004 §3.3.2 push-out, fluid/core/collider.hpp), except water
  // squeezed where a crate reaches into the fountain or into another crate: no position is outside
  // both, the solver keeps it outside the fountain (still colliders win) or the crate resolved last,
  // and the check leaves out the particles inside a crate there (worstFreePenetration). What
  // remains is float rounding and the projections' remainder at corners. A quarter radius is far
  // above rounding and far below the depth of a particle that went through a wall.
  float particle_tolerance = 0.25f;
  // Crates: the box reaches at least (half edge - centre distance) into the fountain's solid. Resting
  // contacts stay within Bullet's few-centimetre margin, but a thrown crate (14 m/s) travels 0.12 m,
  // 0.2 of a 0.6 m edge, per 1/120 s substep before its first contact acts. Half an edge means the
  // centre reached the surface: the crate sank or went through a wall.
  float crate_tolerance = 0.5f;
  MemoryGrowthDesc memory;
  // A gauge (SoakProbe::gauge: the fountain's pool level) fails when the median of the last third of
  // its samples after warm-up (taken with the memory's) differs from the first third's by more than
  // this share of it: issue 33 asks the pool to hold its level within 2 % over an hour of throws and
  // blasts. Judged only when the samples span gauge_min_seconds of game time: a blast throws water
  // out of the basin, and until it is back through the gutter and the pump the level is down by more
  // than that, which over a short run's thirds is no drift.
  double gauge_drift = 0.02;
  double gauge_min_seconds = 600.0;
  bool check_memory = true;  // false: the resident set is still sampled and printed, never judged
  int progress_fd = -1;      // when >= 0: "N\n" is written here before step N (1-based) runs
};

struct SoakStats {
  std::uint64_t steps = 0;
  int throws = 0;                               // crates and explosives
  int explosives = 0;                           // of them
  std::uint64_t rss_warmup = 0, rss_end = 0;    // resident set at the end of warm-up and at the last frame
  std::uint64_t heap_warmup = 0, heap_end = 0;  // heap in use (heapInUseBytes), the same samples
  std::uint64_t memory_restart_step = 0;        // > 0: the samples started again at the first blast, this step
  MemoryGrowth memory;       // the resident set's verdict (its trend; the final level too without a heap figure)
  MemoryGrowth heap_memory;  // the heap in use's verdict (trend and final level)
  struct GaugeDrift {        // one gauge's medians of the first and last thirds of its samples
    std::string name, unit;
    double first = 0.0, last = 0.0;
    bool judged = false;  // the samples spanned SoakDesc::gauge_min_seconds
  };
  std::vector<GaugeDrift> gauges;  // in SoakProbe::gauges' order, filled by finishSoak
};

struct SoakMonitor {
  SoakDesc desc;
  std::uint64_t warmup_steps = 0;  // from desc.warmup_fraction and min_warmup_seconds
  ThrowSchedule schedule;
  SoakStats stats;
  std::vector<std::uint64_t> rss_samples;          // after warm-up; reserved up front
  std::vector<std::uint64_t> heap_samples;         // heap in use at the same samples
  std::vector<std::vector<double>> gauge_samples;  // per SoakProbe::gauges entry, at the same steps, from warm-up on
  std::uint64_t gauge_first_step = 0;              // the step of the first gauge sample
  SoakProbe probe;  // every effect's checks report here (Effect::soakCheck); counts, speeds, worst penetrations
  std::uint64_t detonations_seen = 0;  // the explosives' detonation count at the last frame
  std::string failure;                 // the first failure, naming the step and what
};

SoakMonitor makeSoakMonitor(const SoakDesc& desc, double step_seconds);

// FrameHooks::before_steps: reports progress, throws a crate or an explosive when one is due (the
// camera moves to the thrower's place and looks along the throw, so the surface is meshed for that view).
void soakBeforeStep(SoakMonitor& monitor, World& world, std::uint64_t step);

// FrameHooks::after_frame: every check on the world as this frame left it. False (stop) on the
// first failure or once desc.steps steps ran.
bool soakAfterFrame(SoakMonitor& monitor, const World& world);

// After the run: the memory verdict (sets failure when the resident set grew after warm-up).
void finishSoak(SoakMonitor& monitor);

// One line: steps, throws, particles min/max, max speed, RSS at warm-up and end, worst penetrations.
std::string soakSummary(const SoakMonitor& monitor);

}  // namespace game
