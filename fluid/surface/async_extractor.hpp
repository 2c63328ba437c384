#pragma once
// Asynchronous extraction (Janisz, §3.2.6 "Multithreading"): the caller hands over frame N's
// particles and goes on (simulating the next step, rendering the surface of frame N-1) while a
// worker thread meshes frame N. The surface shown is one frame old: the latency the thesis trades
// for keeping the main thread out of the extraction.
//
// start() copies the input, so the caller may change its particles at once; collect() waits for
// the job and swaps its mesh into the caller's, whose old buffers become the next job's output
// (no allocation once both meshes have grown). The mesh is what SurfaceExtractor::extract gives
// for the copied input: deterministic and thread-count invariant like it.
//
// The worker's jobs run inside a oneTBB task arena of `threads` slots. An extraction with
// SurfaceParams::threads = 0 and any parallel loop in a job then use that many threads. The default
// (threads <= 0, asyncMeshSlots) is half of what the caller may use, at least one: the caller's own
// loops (the SPH's steps) are what the frame waits for, and oneTBB keeps one worker thread per core
// beyond the first, so a mesher arena as wide as the machine takes the workers the caller's loops
// were using whenever both run. On 2 cores that is the worker alone (fountain_tour, rendered:
// simulation + meshing p95 13.9 -> 11.1 ms against a two-slot arena; README, "The fountain's frame
// budget"); on 16 cores 8 slots, where one slot left the main thread waiting for the worker
// (docs/gpu.md, runs 7 and 8). The width is read once, by the constructor, on the constructing
// thread (under its oneTBB global_control and arena); two extractors made by default (the water's
// and the goo's in one scene) would each take half. The mesh is the same for every thread count.
//
// startJob() runs any extraction on the worker (a marching_slices_policy.hpp policy and a pass over
// the finished mesh, as the blob's tentacle texturing does); the job owns the copy it reads.
#include "fluid/surface/marching_slices.hpp"

#include <tbb/task_arena.h>

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace fluid {

// The arena slots AsyncSurfaceExtractor(threads) gives its jobs: threads when positive, else half the
// threads the calling thread's loops may use (fluid::par::allowedThreads: oneTBB's active
// max_allowed_parallelism, at most its arena's slots), at least 1.
int asyncMeshSlots(int threads);

class AsyncSurfaceExtractor {
 public:
  explicit AsyncSurfaceExtractor(int threads = 0);  // threads: the jobs' arena slots; <= 0: asyncMeshSlots
  ~AsyncSurfaceExtractor();                         // waits for a running job, then stops the worker
  AsyncSurfaceExtractor(const AsyncSurfaceExtractor&) = delete;
  AsyncSurfaceExtractor& operator=(const AsyncSurfaceExtractor&) = delete;

  // Copies `input` and starts meshing it on the worker. Waits first for a job not yet collected
  // (its mesh is dropped). The input is validated by the worker: an error comes with collect().
  void start(const SurfaceInput& input, const SurfaceParams& params);

  // The general form: `job` runs on the worker with the worker's extractor and the mesh that
  // collect() hands over. Everything it reads must stay untouched by the caller until collect()
  // (or the next start) returns: a copy the job owns, or caller data set aside for it. Waits first
  // like start(). A job capturing one pointer needs no allocation (std::function's local storage).
  using Job = std::function<SurfaceStatus(SurfaceExtractor&, SurfaceMesh&)>;
  void startJob(Job job);

  // True from start() until collect() has taken the job's result.
  bool pending() const { return pending_; }

  // Waits for the started job and swaps its mesh into `out`; returns its status. Without a
  // pending job returns an error and leaves `out` alone.
  SurfaceStatus collect(SurfaceMesh& out);

  // Wall time (ms) the worker spent on the job the last collect() took: the meshing cost that no
  // longer shows on the caller's thread.
  double lastJobMs() const { return last_job_ms_; }

 private:
  void work();
  void waitForPending();  // drops the mesh of a job not yet collected
  void launch(Job job);

  tbb::task_arena arena_;  // the jobs run in it (threads slots)
  SurfaceExtractor extractor_;
  // The job: a copy of the particles (packed vec3 positions, the one layout), its params and its result.
  std::vector<glm::vec3> positions_;
  std::vector<float> strength_, radius_scale_;
  std::vector<glm::vec4> user_;
  std::vector<glm::mat3> stretch_;
  SurfaceParams params_;
  Job job_;
  SurfaceMesh mesh_;
  SurfaceStatus status_;
  double job_ms_ = 0.0;       // written by the worker before job_done_
  double last_job_ms_ = 0.0;  // caller thread only

  std::mutex mutex_;
  std::condition_variable wake_;
  bool job_ready_ = false;  // set by start(), cleared by the worker when it begins
  bool job_done_ = false;   // set by the worker, cleared by collect()
  bool quit_ = false;
  bool pending_ = false;  // caller thread only
  std::thread worker_;    // last: starts after the members it uses exist
};

}  // namespace fluid
