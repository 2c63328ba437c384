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
#include "fluid/surface/marching_slices.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace fluid {

class AsyncSurfaceExtractor {
 public:
  AsyncSurfaceExtractor();
  ~AsyncSurfaceExtractor();  // waits for a running job, then stops the worker
  AsyncSurfaceExtractor(const AsyncSurfaceExtractor&) = delete;
  AsyncSurfaceExtractor& operator=(const AsyncSurfaceExtractor&) = delete;

  // Copies `input` and starts meshing it on the worker. Waits first for a job not yet collected
  // (its mesh is dropped). The input is validated by the worker: an error comes with collect().
  void start(const SurfaceInput& input, const SurfaceParams& params);

  // True from start() until collect() has taken the job's result.
  bool pending() const { return pending_; }

  // Waits for the started job and swaps its mesh into `out`; returns its status. Without a
  // pending job returns an error and leaves `out` alone.
  SurfaceStatus collect(SurfaceMesh& out);

 private:
  void work();

  SurfaceExtractor extractor_;
  // The job: a copy of the particles (one layout, the SurfaceInput's), its params and its result.
  std::vector<float> x_, y_, z_, strength_, radius_scale_;
  std::vector<glm::vec4> user_;
  SurfaceParams params_;
  SurfaceMesh mesh_;
  SurfaceStatus status_;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool job_ready_ = false;  // set by start(), cleared by the worker when it begins
  bool job_done_ = false;   // set by the worker, cleared by collect()
  bool quit_ = false;
  bool pending_ = false;    // caller thread only
  std::thread worker_;      // last: starts after the members it uses exist
};

}  // namespace fluid
