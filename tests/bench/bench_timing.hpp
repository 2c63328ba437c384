#pragma once
// Timing helpers shared by the benchmarks that print tables (not the Google Benchmark ones):
// wall-clock, thread-CPU and process-CPU milliseconds, and the median of repeated runs.
#include <algorithm>
#include <chrono>
#include <vector>

#include <time.h>

namespace benchtiming {

// Median; for an even count the mean of the two middle values.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t mid = values.size() / 2;
  return values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

template <class F>
double timeMs(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// CPU time of the calling thread. One-thread runs (a one-slot oneTBB arena runs its work on the
// calling thread) then leave out the time the thread waited for a core on a loaded machine,
// which wall-clock medians include.
inline double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

// CPU time of the whole process (every thread). Over a several-thread run, a figure near the
// one-thread CPU time with a wall time that does not drop says the other threads waited for a
// core rather than that the work did not split.
inline double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

}  // namespace benchtiming
