// The game aim of issue 4, measured on the game's own fountain (plain executable, not a ctest test):
// the `sph_fluid` effect of content/scenes/fountain.json (statue, dish, basin and pump as the
// game builds them, game::initSphFluid), with 10,000 particles of water (the basin filled at load),
// two seconds of jet, then stepped for 60 frames of 1/60 s by the game's own game::stepSphFluid,
// the jet still running.
//
//   bench_game_fountain [--scene FILE] [--threads 1,2] [--frames N] [--set sph_fluid.key=value ...]
//                       [--ab-carry 1] [--ab-batch 1] [--mesh 1]
// --ab-carry 1 adds a row "fresh shapes" per thread count: a copy of the same filled fountain
// whose colliders get a new shape object after every step, so the step carries no collider
// sample from one step to the next (SphScratch::SampleCarry); the copies step frame by frame in
// turn (the same machine load for both), and their state hashes must be equal.
// --ab-batch 1 adds a row "point by point" the same way: a copy whose colliders are each wrapped
// once in a shape that hands the collider one point per query, so the depth-map lookups run one
// point at a time as before the batch query (DepthMapCollider::query); the hashes must be equal.
// --mesh 1 adds the game's meshing (game::meshFluidSurface with the scene's `fluid_surface` section,
// eye and view from its camera): after each frame's steps the frame's particles are handed to the
// mesher, which, asynchronous as in the game (Janisz §3.2.6), meshes them on its worker while the
// next frame's steps run; the frame's clock then covers the steps plus the wait for the previous
// frame's mesh, which is the game's simulation + meshing cost per frame (issue 18 item 5). Three
// columns are added at the end: that frame's median and p95, and the mesher worker's median ms.
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
// --mesh-reps N (issue 20's game-scale bar: a 13,000-particle frame meshed in <= 3 ms on 2 threads) takes
// the first thread count's final frame (after its timed frames) and meshes it synchronously with the
// game's own mesher settings (game::surfaceParamsFor: the scene's fluid_surface section, the particle
// spacing, eye and view from the camera), 1 and 2 threads interleaved, one untimed mesh each first, then
// N timed rounds; prints one more table (median and min wall ms, the 1-thread CPU ms, triangles,
// blocks and field route). --dump-frame FILE also writes that frame as .xyz (for callgrind runs of
// bench_surface_count on it).
// are instrumented (the fill runs at valgrind's uninstrumented speed), e.g.
//   valgrind --tool=callgrind --instr-atstart=no bench_game_fountain --threads 1 --frames 10
// gives the instructions of 10 frames (plus the per-run constant: compare 10 and 20 frames).
#include "bench_timing.hpp"
#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fluid_surface.hpp"
#include "game/world/fountain.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"
#include "load_average.hpp"

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

// The scene's eye and view direction (camera section: yaw -90 looks along -z, pitch up positive).
struct View {
  glm::vec3 eye{0.0f}, dir{0.0f, 0.0f, -1.0f};
};

bool buildFluid(const std::string& scene_file, const std::vector<std::string>& assignments, game::SphFluid& fluid,
                game::FluidSurfaceParams* surface = nullptr, View* view = nullptr) {
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
  if (surface != nullptr) {
    const game::SectionConfig* mesh_section = scene.effect("fluid_surface");
    if (mesh_section == nullptr || !game::surfaceParamsFrom(*mesh_section, *surface, error)) {
      std::fprintf(stderr, "bench_game_fountain: %s has no usable fluid_surface effect %s\n", scene_file.c_str(),
                   error.c_str());
      return false;
    }
  }
  if (view != nullptr) {
    const float yaw = glm::radians(static_cast<float>(scene.camera.number("yaw_degrees")));
    const float pitch = glm::radians(static_cast<float>(scene.camera.number("pitch_degrees")));
    view->eye = scene.camera.vec3("position");
    view->dir = glm::vec3(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
  }
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
  bool fresh = false;           // a new shape object for every collider after every step (nothing carried)
  bool point_by_point = false;  // colliders queried one point per call
  std::vector<std::shared_ptr<const fluid::SignedDistanceShape>> inner;
  std::vector<double> ms, cpu_ms;
  // --mesh: the game's mesher, its frames' steps + mesh wait (ms) and the worker's ms per mesh.
  bool mesh = false;
  game::FluidSurface surface;
  View view;
  std::vector<double> with_mesh_ms, worker_ms;
  double steps = 0.0, iterations = 0.0, err = 0.0, max_err = 0.0;
  double p99_err = 0.0;  // the largest over the steps of the 99th percentile over particles
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
    r.p99_err = std::max(r.p99_err, static_cast<double>(x.p99_density_error));
    if (r.fresh) renewShapes(r);
  });
  r.ms.push_back(frame_ms);
  r.cpu_ms.push_back(benchtiming::threadCpuMs() - cpu0);
  if (ok && r.mesh) {
    bool meshed = false;
    const double wait_ms =
        benchtiming::timeMs([&] { meshed = game::meshFluidSurface(r.surface, r.f, r.view.eye, r.view.dir); });
    if (!meshed) {
      std::fprintf(stderr, "bench_game_fountain: %s\n", r.surface.error.c_str());
      return false;
    }
    r.with_mesh_ms.push_back(frame_ms + wait_ms);
    if (r.surface.job.worker_ms > 0.0) r.worker_ms.push_back(r.surface.job.worker_ms);
  }
  return ok;
}

// Nearest rank: the smallest value that at least 95 % of the values do not exceed.
double p95Of(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(values.size()))) - 1];
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
  const double worst = *std::max_element(r.ms.begin(), r.ms.end());
  char cpu[32] = "-";
  if (t == 1) std::snprintf(cpu, sizeof cpu, "%.2f", median(r.cpu_ms));
  char mesh[96] = "- | - | -";
  if (r.mesh && !r.with_mesh_ms.empty())
    std::snprintf(mesh, sizeof mesh, "%.2f | %.2f | %.2f", median(r.with_mesh_ms), p95Of(r.with_mesh_ms),
                  r.worker_ms.empty() ? 0.0 : median(r.worker_ms));
  std::printf("| %s (%d) | %zu | %.2f | %.2f | %.1f | %.2f | %.3f %% | %.2f %% | %.2f %% | %.2f | %s | %s |\n",
              label.c_str(), t, p.size(), median(r.ms), worst, r.steps / frames, r.iterations * per_step,
              100.0 * r.err * per_step, 100.0 * r.p99_err, 100.0 * r.max_err, p95Of(r.ms), cpu, mesh);
  std::fflush(stdout);
}

// --mesh-reps: the frame's particles meshed by the game's mesher settings, 1 and 2 threads interleaved.
void meshFrameTable(const fluid::ParticlePositions& ps, const fluid::SurfaceParams& game_params, int reps) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
  fluid::SurfaceExtractor ex[2];
  fluid::SurfaceMesh mesh[2];
  // CPU ms: the calling thread's for both thread counts, and for 2 threads also the whole process's
  // (both threads: when it about equals the one-thread CPU time while the wall time does not halve,
  // the second thread found no free core).
  std::vector<double> wall[2], cpu[2], process2;
  const fluid::SurfaceInput input{fluid::pointView(ps)};
  auto run = [&](int k) {
    fluid::SurfaceParams sp = game_params;
    sp.threads = k + 1;
    const fluid::SurfaceStatus st = ex[k].extract(input, sp, mesh[k]);
    if (!st.ok()) {
      std::fprintf(stderr, "bench_game_fountain: %s\n", st.error.c_str());
      std::exit(1);
    }
  };
  const std::string load_start = benchplot::loadAverage();
  run(0);
  run(1);
  for (int r = 0; r < reps; ++r)
    for (int k : {1, 0}) {
      const double c0 = benchtiming::threadCpuMs(), p0 = benchtiming::processCpuMs();
      wall[k].push_back(benchtiming::timeMs([&] { run(k); }));
      cpu[k].push_back(benchtiming::threadCpuMs() - c0);
      if (k == 1) process2.push_back(benchtiming::processCpuMs() - p0);
    }
  const fluid::SurfaceStats& st = mesh[0].stats;
  std::printf(
      "\n| particles | Rc | S | triangles | blocks (slice splat) | 1 thr ms median | 1 thr ms min | 2 thr ms "
      "median | 2 thr ms min | 2 thr speed-up | 1 thr CPU ms median | 2 thr calling thread CPU ms median | 2 thr "
      "process CPU ms median |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| %zu | %.4g | %.4g | %zu%s | %u (%u) | %.3f | %.3f | %.3f | %.3f | %.2fx | %.3f | %.3f | %.3f |\n",
              ps.size(), double(game_params.rc), double(game_params.cube), mesh[0].indices.size() / 3,
              mesh[0].indices == mesh[1].indices ? "" : " (**2 thr differ**)", st.blocks, st.splatBlocks,
              median(wall[0]), *std::min_element(wall[0].begin(), wall[0].end()), median(wall[1]),
              *std::min_element(wall[1].begin(), wall[1].end()), median(wall[0]) / median(wall[1]), median(cpu[0]),
              median(cpu[1]), median(process2));
  std::printf("\nLoad average (1, 5, 15 min) from /proc/loadavg: %s before the meshes, %s after.\n", load_start.c_str(),
              benchplot::loadAverage().c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_file = std::string(FLUIDDEMO_SOURCE_DIR) + "/content/scenes/fountain.json";
  std::vector<int> threads{1, 2};
  int frames = 60;
  bool ab_carry = false, ab_batch = false, with_mesh = false;
  int mesh_reps = 0;
  std::string dump_frame;
  std::vector<std::string> common{"sph_fluid.max_particles=10000"};
  std::vector<Config> configs{{"as in the scene file", {}}};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--ab-carry") {
      ab_carry = v == "1";
    } else if (k == "--ab-batch") {
      ab_batch = v == "1";
    } else if (k == "--mesh") {
      with_mesh = v == "1";
    } else if (k == "--mesh-reps") {
      mesh_reps = std::atoi(v.c_str());
    } else if (k == "--dump-frame") {
      dump_frame = v;
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
                 "[--config \"k=v,k=v\"]... [--ab-carry 1] [--ab-batch 1] [--mesh 1] [--mesh-reps N] "
                 "[--dump-frame FILE]\n");
    return 2;
  }

  std::printf(
      "| configuration (threads) | particles | ms per 1/60 s frame (median) | worst frame (ms) | SPH steps per frame | "
      "solver iterations per step | mean density error | p99 density error (worst step) | max density error | p95 "
      "frame (ms) | CPU ms per frame "
      "(median, 1 thread) | steps + mesh wait ms (median) | steps + mesh wait ms (p95) | mesher worker ms (median) "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Config& config : configs) {
    std::vector<std::string> assignments = common;
    assignments.insert(assignments.end(), config.assignments.begin(), config.assignments.end());
    game::SphFluid filled;
    game::FluidSurfaceParams surface_params;
    View view;
    fluid::ParticlePositions last_frame;  // --mesh-reps / --dump-frame: the first thread count's final frame
    fluid::SurfaceParams frame_params;
    {
      // The basin starts filled (the pump's pool, game::initSphFluid); two seconds of jet bring it to
      // the running state (one warm-up per configuration, all rows of it time the same state).
      if (!buildFluid(scene_file, assignments, filled, &surface_params, &view)) return 1;
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      for (int frame = 0; frame < 120; ++frame)
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
        runs[k].mesh = with_mesh;
        runs[k].view = view;
        runs[k].surface.params = surface_params;
        // The first call meshes its own particles before returning (nothing handed over yet): untimed,
        // like the fill, so the timed frames are the steady state the game plays in.
        if (with_mesh && !game::meshFluidSurface(runs[k].surface, runs[k].f, view.eye, view.dir)) {
          std::fprintf(stderr, "bench_game_fountain: %s\n", runs[k].surface.error.c_str());
          return 1;
        }
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
      if (t == threads.front() && (mesh_reps > 0 || !dump_frame.empty())) {
        last_frame = runs[0].f.world.particles.position;
        frame_params =
            game::surfaceParamsFor(surface_params, fluid::sphSpacing(runs[0].f.world.params), view.eye, view.dir);
      }
    }
    if (!dump_frame.empty()) {
      const fluid::IoStatus io = fluid::writeParticleXyz(dump_frame, last_frame, fluid::OverwritePolicy::replace);
      if (!io.ok()) {
        std::fprintf(stderr, "bench_game_fountain: %s\n", io.error.c_str());
        return 1;
      }
    }
    if (mesh_reps > 0) meshFrameTable(last_frame, frame_params, mesh_reps);
  }
  return 0;
}
