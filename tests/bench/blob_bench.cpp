// bench_blob: the blob monster's cost per frame (issue 19: "body step + meshing per frame at 250,
// 1,000 and 4,000 particles, 1 and 2 threads"). A body on the ground growing four tentacles toward a
// target (the busiest behaviour: goal springs, pairs, ground contacts), warmed up for one second.
//   bench_blob [--benchmark_filter=...]
// Each case reports the mean (Google Benchmark's time) and p95_ms over its iterations.
#include "fluid/blob/behaviour.hpp"
#include "fluid/blob/blob.hpp"
#include "fluid/blob/tentacle_uv.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/marching_slices_policy.hpp"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace {

struct Scene {
  fluid::BlobWorld world;
  fluid::BlobBehaviour behaviour;
  glm::vec3 target{4.0f, 1.0f, 0.0f};
};

void makeScene(Scene& s, std::size_t particles) {
  s.world.params.particle_count = particles;
  fluid::initBlob(s.world, glm::vec3(0.0f, 0.6f, 0.0f));
  fluid::BlobCollider ground;
  ground.shape = std::make_shared<fluid::PlaneShape>(glm::vec3(0.0f, 1.0f, 0.0f), 0.0f);
  s.world.colliders.push_back(ground);
  s.behaviour.kind = fluid::BlobBehaviourKind::tentacles;
  s.behaviour.tentacles = 4;
  s.behaviour.tentacle_particles = static_cast<int>(std::min<std::size_t>(30, particles / 10));
  fluid::startBlobBehaviour(s.world, s.behaviour, s.target);
  for (int k = 0; k < 60; ++k) {
    fluid::updateBlobBehaviour(s.world, s.behaviour, s.target, s.world.params.step);
    fluid::stepBlob(s.world);
  }
}

void frame(Scene& s) {
  fluid::updateBlobBehaviour(s.world, s.behaviour, s.target, s.world.params.step);
  fluid::stepBlob(s.world);
}

void report(benchmark::State& state, std::vector<double>& ms) {
  std::sort(ms.begin(), ms.end());
  if (!ms.empty()) state.counters["p95_ms"] = ms[std::min(ms.size() - 1, ms.size() * 95 / 100)];
}

void BM_BlobStep(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
  Scene s;
  makeScene(s, static_cast<std::size_t>(state.range(0)));
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    frame(s);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  report(state, ms);
}

// The same plus the body's mesh as the game makes it each frame (game/effects/blob.cpp
// prepareFrame, blob_monster.json defaults): marching slices with the tentacle texturing policy
// (Rc = 2 d, cube d / 2, T = 0.2, back to front from an eye 4 m away), then u around the tentacles.
void BM_BlobStepAndMesh(benchmark::State& state) {
  const int n_threads = static_cast<int>(state.range(1));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(n_threads));
  Scene s;
  makeScene(s, static_cast<std::size_t>(state.range(0)));
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  fluid::SurfaceParams sp;
  sp.rc = 2.0f * s.world.params.spacing;
  sp.cube = 0.5f * s.world.params.spacing;
  sp.threshold = 0.2f;
  sp.threads = n_threads;
  sp.order = fluid::SurfaceOrder::backToFront;
  sp.eye = glm::vec3(2.5f, 2.0f, -3.0f);
  sp.viewDir = glm::normalize(glm::vec3(0.0f, 0.5f, 0.0f) - sp.eye);
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    frame(s);
    // The goo's own positions, read in place (one layout).
    const fluid::SurfaceInput in{
        fluid::pointView(s.world.particles.position), s.world.particles.strength, s.world.particles.radius_scale, {}};
    const fluid::SurfaceStatus st = fluid::extractWithPolicy(
        extractor, in, sp, fluid::BlobTentaclePolicy{s.world.particles.length_coord.data()}, mesh);
    if (!st.ok()) state.SkipWithError(st.error.c_str());
    fluid::blobTentacleU(mesh, s.world);
    benchmark::DoNotOptimize(mesh.indices.data());
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["triangles"] = static_cast<double>(mesh.indices.size() / 3);
  report(state, ms);
}

void cases(benchmark::internal::Benchmark* b) {
  for (int n : {250, 1000, 4000})
    for (int t : {1, 2}) b->Args({n, t});
  b->ArgNames({"particles", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_BlobStep)->Apply(cases);
BENCHMARK(BM_BlobStepAndMesh)->Apply(cases);

}  // namespace

BENCHMARK_MAIN();
