// bench_surface_count: runs approach 1 (marching slices) on one particle set, single-threaded,
// for instruction counting with callgrind (repeatable on a loaded machine, unlike timings):
//
//   valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*extractImpl*'
//       build/dev/tests/bench/bench_surface_count tests/data/fountain.xyz 1.0
//
// One warm-up extract (allocations), then `reps` measured ones (default 1); prints the triangle
// count so a run can be checked against docs/surface.md, and an FNV-1a hash of the mesh
// (positions, normals, indices, in output order) so an optimisation can be checked bit for bit.
// A fourth argument `blocks` also prints each block's triangles and vertices (thread balance);
// SURFACE_COUNT_THREADS=N in the environment runs with N threads instead of 1, and
// SURFACE_COUNT_BLOCK=B with blockCubes = B instead of auto, SURFACE_COUNT_RC=R with rc = R (default 3).
// SURFACE_COUNT_RATIO=N times N
// interleaved rounds of approach 1 and approach 3 (hashed baseline) on the calling thread's CPU
// clock and prints both medians and a3/a1: a quick check of the Figure 7 ratio between full
// bench_surface runs (1 thread), on the §6 cache route (SURFACE_COUNT_ROUTE=auto|splat for the others).
// SURFACE_COUNT_PORTABLE=1 sets SurfaceParams::portableKernels
// (the SSE2 particle-cache fill even where the CPU has AVX2), to compare the two paths.
// SURFACE_COUNT_SCALING=N times N interleaved rounds of approach 1 on 1 thread and on
// SURFACE_COUNT_THREADS (default 2) threads, wall clock, each timed extraction right after an
// untimed one with the same extractor (as bench_surface's thread-scaling table), and prints both
// medians and their ratio (and, for the several threads, the calling thread's and the process's CPU ms): a quick check
// of the two-thread bar between full bench_surface runs.
#include "bench_timing.hpp"
#include "fluid/io/particle_io.hpp"
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <time.h>

namespace {
template <class T>
void fnv(std::uint64_t& h, const std::vector<T>& v) {
  const auto* b = reinterpret_cast<const unsigned char*>(v.data());
  for (std::size_t i = 0; i < v.size() * sizeof(T); ++i) h = (h ^ b[i]) * 1099511628211ull;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_surface_count FILE CUBE [REPS [blocks]]\n");
    return 2;
  }
  fluid::ParticlePositions ps;
  const fluid::IoStatus io = fluid::readParticleFile(argv[1], ps);
  if (!io.ok()) {
    std::fprintf(stderr, "%s\n", io.error.c_str());
    return 1;
  }
  fluid::SurfaceParams params;
  params.cube = float(std::atof(argv[2]));
  params.threads = 1;
  if (const char* t = std::getenv("SURFACE_COUNT_THREADS"))
    params.threads = std::max(1, std::atoi(t));                                              // timing checks
  if (const char* b = std::getenv("SURFACE_COUNT_BLOCK")) params.blockCubes = std::atoi(b);  // 0 = auto
  if (const char* rc = std::getenv("SURFACE_COUNT_RC")) params.rc = float(std::atof(rc));
  if (const char* pk = std::getenv("SURFACE_COUNT_PORTABLE")) params.portableKernels = std::atoi(pk) != 0;
  // The §6 cache route (bench_surface's Figure 7 tables use it); SURFACE_COUNT_ROUTE=auto|splat|dense|value for the others.
  params.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
  if (const char* r = std::getenv("SURFACE_COUNT_ROUTE"))
    params.fieldRoute = std::string(r) == "splat"   ? fluid::SurfaceFieldRoute::sliceSplat
                        : std::string(r) == "dense" ? fluid::SurfaceFieldRoute::denseScan
                        : std::string(r) == "value" ? fluid::SurfaceFieldRoute::valueScan
                        : std::string(r) == "auto"  ? fluid::SurfaceFieldRoute::automatic
                                                    : fluid::SurfaceFieldRoute::particleCache;
  const int reps = argc > 3 ? std::max(1, std::atoi(argv[3])) : 1;
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  const fluid::SurfaceInput in{fluid::pointView(ps)};
  for (int r = 0; r <= reps; ++r) {
    const fluid::SurfaceStatus st = extractor.extract(in, params, mesh);
    if (!st.ok()) {
      std::fprintf(stderr, "%s\n", st.error.c_str());
      return 1;
    }
  }
  std::uint64_t h = 1469598103934665603ull;
  fnv(h, mesh.positions);
  fnv(h, mesh.normals);
  fnv(h, mesh.indices);
  std::printf(
      "triangles %zu vertices %zu cubes %llu corners %llu lookups %llu hash %016llx cacheMB %.3f cornerMB %.3f "
      "seedEvals %llu\n",
      mesh.indices.size() / 3, mesh.positions.size(), (unsigned long long)mesh.stats.cubesVisited,
      (unsigned long long)mesh.stats.cornersEvaluated, (unsigned long long)mesh.stats.particlesLookedUp,
      (unsigned long long)h, mesh.stats.particleCacheBytesPeakBlock / 1e6, mesh.stats.cornerCacheBytesPeakBlock / 1e6,
      (unsigned long long)mesh.stats.seedEvaluations);
  if (argc > 4 && std::string(argv[4]) == "blocks")  // per-block share of the work, for balance checks
    for (const fluid::SurfaceBlockRange& b : mesh.blocks)
      std::printf("block (%d %d %d) triangles %u vertices %u\n", b.bx, b.by, b.bz, b.indices.count / 3, b.vertexCount);
  if (const char* rr = std::getenv("SURFACE_COUNT_RATIO")) {
    const int rounds = std::max(1, std::atoi(rr));
    using benchtiming::threadCpuMs;
    fluid::BaselineExtractor base;
    fluid::SurfaceMesh other;
    std::vector<double> t1, t3;
    for (int r = 0; r < rounds; ++r) {
      double c0 = threadCpuMs();
      (void)extractor.extract(in, params, mesh);
      t1.push_back(threadCpuMs() - c0);
      c0 = threadCpuMs();
      (void)base.extract(fluid::BaselineMethod::hashed, in, params, other);
      t3.push_back(threadCpuMs() - c0);
    }
    std::sort(t1.begin(), t1.end());
    std::sort(t3.begin(), t3.end());
    const double m1 = t1[t1.size() / 2], m3 = t3[t3.size() / 2];
    std::printf("cpu ms median of %d: a1 %.3f a3 %.3f a3/a1 %.2f (a3 triangles %zu)\n", rounds, m1, m3, m3 / m1,
                other.indices.size() / 3);
  }
  if (const char* sc = std::getenv("SURFACE_COUNT_SCALING")) {
    const int rounds = std::max(1, std::atoi(sc));
    fluid::SurfaceParams p1 = params, pn = params;
    p1.threads = 1;
    pn.threads = params.threads > 1 ? params.threads : 2;
    fluid::SurfaceExtractor e1, en;
    fluid::SurfaceMesh m1, mn;
    // Also the CPU ms of the calling thread and of the whole process over the timed extraction
    // (benchtiming::processCpuMs says what they show on a loaded machine).
    double callingCpu = 0, processCpu = 0;
    auto wallMs = [&](fluid::SurfaceExtractor& e, const fluid::SurfaceParams& p, fluid::SurfaceMesh& m) {
      (void)e.extract(in, p, m);  // untimed: steady state, as when a game meshes every frame
      const double c0 = benchtiming::threadCpuMs(), p0 = benchtiming::processCpuMs();
      const auto t0 = std::chrono::steady_clock::now();
      (void)e.extract(in, p, m);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      callingCpu = benchtiming::threadCpuMs() - c0, processCpu = benchtiming::processCpuMs() - p0;
      return ms;
    };
    std::vector<double> t1, tn, ratio, cn, pcn;
    for (int r = 0; r < rounds; ++r) {
      t1.push_back(wallMs(e1, p1, m1));
      tn.push_back(wallMs(en, pn, mn));
      cn.push_back(callingCpu);
      pcn.push_back(processCpu);
      ratio.push_back(t1.back() / tn.back());
    }
    const bool same = m1.positions == mn.positions && m1.normals == mn.normals && m1.indices == mn.indices;
    std::sort(t1.begin(), t1.end());
    std::sort(tn.begin(), tn.end());
    std::sort(ratio.begin(), ratio.end());
    std::sort(cn.begin(), cn.end());
    std::sort(pcn.begin(), pcn.end());
    const double a = t1[t1.size() / 2], b = tn[tn.size() / 2];
    std::printf(
        "wall ms median of %d: 1 thr %.3f, %d thr %.3f, ratio of medians %.3f, median of per-round ratios %.3f%s\n",
        rounds, a, pn.threads, b, a / b, ratio[ratio.size() / 2], same ? "" : " MESHES DIFFER");
    std::printf("%d thr CPU ms median: calling thread %.3f, process %.3f\n", pn.threads, cn[cn.size() / 2],
                pcn[pcn.size() / 2]);
  }
  return 0;
}
