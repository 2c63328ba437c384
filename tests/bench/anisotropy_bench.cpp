// Anisotropic kernels (fluid/sph/anisotropy.hpp) per frame against the SPH step, in one process:
// a dambreak_box of about 2,500 / 13,000 / 50,000 particles (DFSPH) runs 20 steps, the median of
// the last 10 step times is the reference, then the anisotropy pass runs on those particles.
// Counters: particles, sph_step_ms (median, wall), aniso_ms (mean per pass, wall) and their
// ratio, and the same as processor time of all threads (sph_cpu_ms, aniso_cpu_ms, cpu_ratio: the
// work, which a machine shared with other jobs distorts less than the wall clock), the share of
// stretched particles. Second argument: the neighbourhood radius in tenths of a particle
// spacing (30 = the game's 3 spacings).
//   bench_anisotropy [--benchmark_filter=...]
#include "fluid/sph/anisotropy.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

namespace {

using namespace fluid;

double cpuMs() {  // processor time of the whole process (every thread), ms
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

void BM_AnisotropyVsSphStep(benchmark::State& state) {
  const int per_side = static_cast<int>(state.range(0));
  const float radius_spacings = static_cast<float>(state.range(1)) / 10.0f;
  const float r = 1.0f / (2.0f * static_cast<float>(per_side + 1));
  SphScene s;
  const SphStatus st = makeSphScene("dambreak_box", SphSolverKind::dfsph, {{"particle_radius", std::to_string(r)}}, s);
  if (!st.ok()) {
    state.SkipWithError(st.error.c_str());
    return;
  }
  reserveSph(s.world, s.world.particles.size());
  std::vector<double> step_ms, step_cpu;
  for (int i = 0; i < 20; ++i) {
    SphStepStats stats;
    const double c0 = cpuMs();
    if (!stepSph(s.world, 0.0f, &stats).ok()) {
      state.SkipWithError("stepSph failed");
      return;
    }
    if (i >= 10) {
      step_ms.push_back(stats.step_ms);
      step_cpu.push_back(cpuMs() - c0);
    }
  }
  std::nth_element(step_cpu.begin(), step_cpu.begin() + step_cpu.size() / 2, step_cpu.end());
  const double sph_cpu = step_cpu[step_cpu.size() / 2];
  std::nth_element(step_ms.begin(), step_ms.begin() + step_ms.size() / 2, step_ms.end());
  const double sph_ms = step_ms[step_ms.size() / 2];

  AnisotropyParams a;
  a.radius = radius_spacings * sphSpacing(s.world.params);
  Anisotropy out;
  AnisotropyScratch scratch;
  computeAnisotropy(s.world.particles.position, a, scratch, out);  // warm-up (allocations)
  double total_ms = 0.0, total_cpu = 0.0;
  std::int64_t passes = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = cpuMs();
    computeAnisotropy(s.world.particles.position, a, scratch, out);
    total_cpu += cpuMs() - c0;
    total_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++passes;
    benchmark::DoNotOptimize(out.g.data());
  }
  const double aniso_ms = total_ms / static_cast<double>(std::max<std::int64_t>(passes, 1));
  double neighbours = 0.0;
  for (std::uint32_t c : out.neighbours) neighbours += c;
  state.counters["particles"] = static_cast<double>(s.world.particles.size());
  state.counters["sph_step_ms"] = sph_ms;
  state.counters["aniso_ms"] = aniso_ms;
  state.counters["aniso_per_step"] = aniso_ms / sph_ms;
  const double aniso_cpu = total_cpu / static_cast<double>(std::max<std::int64_t>(passes, 1));
  state.counters["sph_cpu_ms"] = sph_cpu;
  state.counters["aniso_cpu_ms"] = aniso_cpu;
  state.counters["cpu_ratio"] = aniso_cpu / sph_cpu;
  state.counters["stretched"] = static_cast<double>(out.stretched) / static_cast<double>(out.g.size());
  state.counters["mean_neighbours"] = neighbours / static_cast<double>(out.neighbours.size());
}
BENCHMARK(BM_AnisotropyVsSphStep)
    ->Args({14, 30})
    ->Args({24, 30})
    ->Args({37, 30})
    ->Args({14, 20})
    ->Args({24, 20})
    ->Args({37, 20})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
