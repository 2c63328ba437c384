// The game aim of issue 4, measured on the game's own fountain (plain executable, not a ctest test):
// the `sph_fluid` effect of content/scenes/fountain.json (statue, dish, basin and drains as the
// game builds them, game::initSphFluid), with its particle budget raised to 10,000, filled with the
// drains shut until one second of jet is left to the budget, then stepped for 60 frames of 1/60 s
// by the game's own game::stepSphFluid, the jet still running.
//
//   bench_game_fountain [--scene FILE] [--threads 1,2] [--frames N] [--set sph_fluid.key=value ...]
//                       [--ab-carry 1] [--ab-batch 1]
// --ab-carry 1 adds a row "fresh shapes" per thread count: a copy of the same filled fountain
// whose colliders get a new shape object after every step, so the step carries no collider
// sample from one step to the next (SphScratch::SampleCarry); the copies step frame by frame in
// turn (the same machine load for both), and their state hashes must be equal.
// --ab-batch 1 adds a row "point by point" the same way: a copy whose colliders are each wrapped
// once in a shape that hands the collider one point per query, so the depth-map lookups run one
// point at a time as before the batch query (DepthMapCollider::query); the hashes must be equal.
// Every solver knob is a scene key, e.g. --set sph_fluid.warm_start=false turns DFSPH's warm start
// off for the whole run, fill included.
//
// Prints one markdown row per configuration and thread count: particles, ms per frame (median
// and worst), SPH steps per frame, solver iterations per step (DFSPH: divergence + density), mean
// and max density error (issue 4's definition: mean over particles of max(0, rho/rho_0 - 1), here
// averaged over the steps of the timed frames), then (added last, so the columns above keep their
// places for sph_bar_status.py) the 95th-percentile frame (issue 18's budget is a p95) and, for
// one thread, the calling thread's CPU ms per frame (median): the work itself, without the time
// a loaded machine kept the thread waiting for a core.
// Configurations: the scene file as written, then each `--config "k=v,k=v"` given (sph_fluid keys).
// Instruction counts: under `valgrind --tool=callgrind --instr-atstart=no` only the timed frames
// are instrumented (the fill runs at valgrind's uninstrumented speed), e.g.
//   valgrind --tool=callgrind --instr-atstart=no bench_game_fountain --threads 1 --frames 10
// gives the instructions of 10 frames (plus the per-run constant: compare 10 and 20 frames).
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"
#include "bench_timing.hpp"

#include <tbb/global_control.h>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace {

using benchtiming::median;

struct Config {
  std::string label;
  std::vector<std::string> assignments;  // "sph_fluid.key=value"
};

bool buildFluid(const std::string& scene_file, const std::vector<std::string>& assignments, game::SphFluid& fluid) {
  game::SceneConfig scene;
  game::SceneStatus st = game::loadSceneFile(scene_file, scene);
  for (const std::string& a : assignments)
    if (st.ok()) st = game::applyOverride(scene, a);
  if (!st.ok()) {
    std::fprintf(stderr, "bench_game_fountain: %s\n", st.error.c_str());
    return false;
  }
  const game::SectionConfig* section = scene.effect("sph_fluid");
  if (section == nullptr) {
    std::fprintf(stderr, "bench_game_fountain: %s does not list the sph_fluid effect\n", scene_file.c_str());
    return false;
  }
  game::SphFluidParams params;
  std::string error;
  std::shared_ptr<const game::LevelColliders> colliders;
  if (!game::sphParamsFrom(*section, params, error) ||
      !game::ensureFountainColliders(std::string(FLUIDDEMO_SOURCE_DIR) + "/content", colliders, error) ||
      !game::initSphFluid(fluid, params, game::FountainGeometry{}, colliders, game::sceneGravity(scene), error)) {
    std::fprintf(stderr, "bench_game_fountain: %s\n", error.c_str());
    return false;
  }
  return true;
}

// One timed copy of the filled fountain and what its frames measured.
struct Run {
  game::SphFluid f;
  bool fresh = false;  // a new shape object for every collider after every step (nothing carried)
  bool point_by_point = false;  // colliders queried one point per call
  std::vector<std::shared_ptr<const fluid::SignedDistanceShape>> inner;
  std::vector<double> ms, cpu_ms;
  double steps = 0.0, iterations = 0.0, err = 0.0, max_err = 0.0;
};

// Forwards to the shape it wraps: the same samples, from an object the carry has never seen.
class FreshShape final : public fluid::SignedDistanceShape {
 public:
  explicit FreshShape(std::shared_ptr<const fluid::SignedDistanceShape> inner) : inner_(std::move(inner)) {}
  void query(std::span<const glm::vec3> points, std::span<fluid::ColliderSample> out) const override {
    inner_->query(points, out);
  }

 private:
  std::shared_ptr<const fluid::SignedDistanceShape> inner_;
};

// Forwards one point per call to the shape it wraps: the same samples, without the batch path.
class PointByPointShape final : public fluid::SignedDistanceShape {
 public:
  explicit PointByPointShape(std::shared_ptr<const fluid::SignedDistanceShape> inner) : inner_(std::move(inner)) {}
  void query(std::span<const glm::vec3> points, std::span<fluid::ColliderSample> out) const override {
    for (std::size_t k = 0; k < points.size(); ++k) inner_->query(points.subspan(k, 1), out.subspan(k, 1));
  }

 private:
  std::shared_ptr<const fluid::SignedDistanceShape> inner_;
};

void renewShapes(Run& r) {
  for (std::size_t c = 0; c < r.inner.size(); ++c)
    r.f.world.colliders[c].shape = std::make_shared<FreshShape>(r.inner[c]);
}

bool stepFrame(Run& r) {
  if (r.fresh) renewShapes(r);
  double frame_ms = 0.0;
  const double cpu0 = benchtiming::threadCpuMs();
  const bool ok = game::stepSphFluid(r.f, 1.0 / 60.0, [&](const fluid::SphStepStats& x) {
    frame_ms += x.step_ms;
    r.steps += 1.0;
    r.iterations += x.density_iterations + x.divergence_iterations;
    r.err += x.avg_density_error;
    r.max_err = std::max(r.max_err, static_cast<double>(x.max_density_error));
    if (r.fresh) renewShapes(r);
  });
  r.ms.push_back(frame_ms);
  r.cpu_ms.push_back(benchtiming::threadCpuMs() - cpu0);
  return ok;
}

void printRow(const std::string& label, int t, int frames, const Run& r) {
  // A hash of the final state's bits (stderr, keeps the table clean): equal hashes mean
  // bit-identical runs (thread counts, or builds before/after an optimisation).
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](const void* data, std::size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) hash = (hash ^ p[k]) * 1099511628211ull;
  };
  const fluid::ParticleStore& p = r.f.world.particles;
  mix(p.position.data(), p.position.size() * sizeof(glm::vec3));
  mix(p.velocity.data(), p.velocity.size() * sizeof(glm::vec3));
  mix(p.id.data(), p.id.size() * sizeof(std::uint32_t));
  std::fprintf(stderr, "%s (%d): state hash %016llx\n", label.c_str(), t, static_cast<unsigned long long>(hash));
  const double per_step = 1.0 / std::max(r.steps, 1.0);
  std::vector<double> sorted = r.ms;
  std::sort(sorted.begin(), sorted.end());
  // Nearest rank: the smallest frame time that at least 95 % of the frames do not exceed.
  const double p95 = sorted[static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(sorted.size()))) - 1];
  char cpu[32] = "-";
  if (t == 1) std::snprintf(cpu, sizeof cpu, "%.2f", median(r.cpu_ms));
  std::printf("| %s (%d) | %zu | %.2f | %.2f | %.1f | %.2f | %.3f %% | %.2f %% | %.2f | %s |\n", label.c_str(), t,
              p.size(), median(r.ms), sorted.back(), r.steps / frames, r.iterations * per_step,
              100.0 * r.err * per_step, 100.0 * r.max_err, p95, cpu);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_file = std::string(FLUIDDEMO_SOURCE_DIR) + "/content/scenes/fountain.json";
  std::vector<int> threads{1, 2};
  int frames = 60;
  bool ab_carry = false, ab_batch = false;
  std::vector<std::string> common{"sph_fluid.max_particles=10000"};
  std::vector<Config> configs{{"as in the scene file", {}}};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--ab-carry") {
      ab_carry = v == "1";
    } else if (k == "--ab-batch") {
      ab_batch = v == "1";
    } else if (k == "--scene") {
      scene_file = v;
    } else if (k == "--frames") {
      frames = std::atoi(v.c_str());
    } else if (k == "--set") {
      common.push_back(v);
    } else if (k == "--config") {
      Config c{v, {}};
      std::size_t start = 0;
      while (start <= v.size()) {
        const std::size_t comma = std::min(v.find(',', start), v.size());
        if (comma > start) c.assignments.push_back("sph_fluid." + v.substr(start, comma - start));
        start = comma + 1;
      }
      configs.push_back(c);
    } else if (k == "--threads") {
      threads.clear();
      for (char ch : v)
        if (ch >= '1' && ch <= '9') threads.push_back(ch - '0');
    } else {
      std::fprintf(stderr, "bench_game_fountain: unknown option %s\n", k.c_str());
      return 2;
    }
  }
  if (argc % 2 == 0 || frames < 1 || threads.empty()) {
    std::fprintf(stderr,
                 "usage: bench_game_fountain [--scene FILE] [--threads 1,2] [--frames N] [--set sph_fluid.k=v] "
                 "[--config \"k=v,k=v\"]... [--ab-carry 1] [--ab-batch 1]\n");
    return 2;
  }

  std::printf(
      "| configuration (threads) | particles | ms per 1/60 s frame (median) | worst frame (ms) | SPH steps per frame | "
      "solver iterations per step | mean density error | max density error | p95 frame (ms) | CPU ms per frame "
      "(median, 1 thread) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Config& config : configs) {
    std::vector<std::string> assignments = common;
    assignments.insert(assignments.end(), config.assignments.begin(), config.assignments.end());
    game::SphFluid filled;
    {
      // Fill with the drains shut (one fill per configuration, all rows of it time the same state).
      std::vector<std::string> fill = assignments;
      fill.push_back("sph_fluid.drain=false");
      if (!buildFluid(scene_file, fill, filled)) return 1;
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      const double budget = static_cast<double>(filled.world.params.max_particles);
      const double target = budget - std::min(0.5 * budget, static_cast<double>(filled.params.rate));
      while (static_cast<double>(filled.world.particles.size()) < target && filled.world.time < 120.0)
        if (!game::stepSphFluid(filled, 1.0 / 60.0)) {
          std::fprintf(stderr, "bench_game_fountain: %s\n", filled.error.c_str());
          return 1;
        }
    }
    for (int t : threads) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(t));
      // --ab-carry: a second copy whose colliders get a new shape object after every step, so no
      // collider sample is carried to the next step (SphScratch::SampleCarry); the two copies step
      // frame by frame in turn, so both see the same machine load.
      // --ab-batch: likewise, a copy whose colliders take one point per query.
      std::vector<Run> runs(1 + (ab_carry ? 1 : 0) + (ab_batch ? 1 : 0));
      for (std::size_t k = 0; k < runs.size(); ++k) {
        runs[k].f = filled;
        runs[k].fresh = ab_carry && k == 1;
        runs[k].point_by_point = ab_batch && k + 1 == runs.size();
        for (const fluid::SphCollider& c : filled.world.colliders) runs[k].inner.push_back(c.shape);
        if (runs[k].point_by_point)
          for (fluid::SphCollider& c : runs[k].f.world.colliders)
            c.shape = std::make_shared<PointByPointShape>(c.shape);
      }
      CALLGRIND_START_INSTRUMENTATION;
      for (int frame = 0; frame < frames; ++frame)
        for (Run& r : runs)
          if (!stepFrame(r)) {
            std::fprintf(stderr, "bench_game_fountain: %s\n", r.f.error.c_str());
            return 1;
          }
      CALLGRIND_STOP_INSTRUMENTATION;
      for (const Run& r : runs)
        printRow(config.label + (r.fresh ? " fresh shapes" : r.point_by_point ? " point by point" : ""), t, frames, r);
    }
  }
  return 0;
}
