#include "game/world/surface_job.hpp"

namespace game {

fluid::SurfaceStatus SurfaceJob::failed(const fluid::SurfaceStatus& st) {
  if (!st.ok()) mesh.clear();
  return st;
}

fluid::SurfaceStatus SurfaceJob::meshNow(const MeshNow& mesh_now) {
  worker_.reset();
  worker_ms = 0.0;
  return failed(mesh_now(extractor_, mesh));
}

fluid::SurfaceStatus SurfaceJob::meshBehind(const HandOver& hand_over) {
  worker_ms = 0.0;
  if (!worker_) worker_ = std::make_unique<fluid::AsyncSurfaceExtractor>();
  fluid::AsyncSurfaceExtractor& worker = *worker_;
  // The job in flight meshed the previous frame's copy: collect it, then the copy is free again.
  const bool in_flight = worker.pending();
  fluid::SurfaceStatus st;
  if (in_flight) {
    st = worker.collect(mesh);
    worker_ms = worker.lastJobMs();
  }
  if (const fluid::SurfaceStatus started = hand_over(worker); !started.ok()) return failed(started);
  if (!in_flight) {  // first frame: this frame's own surface, waited for
    st = worker.collect(mesh);
    worker_ms = worker.lastJobMs();
    if (const fluid::SurfaceStatus again = hand_over(worker); !again.ok()) return failed(again);
  }
  return failed(st);
}

void SurfaceJob::drop() {
  worker_.reset();
  worker_ms = 0.0;
  mesh.clear();
}

}  // namespace game
