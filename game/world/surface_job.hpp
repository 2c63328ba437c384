#pragma once
// One particle-surface meshing job for every effect that turns particles into a surface each frame
// (the water's fluid_surface, the blob's goo). Either synchronous (mesh the current particles before
// drawing), or asynchronous (Janisz §3.2.6): the worker meshes frame N while the next steps run and
// the frame draws the surface of frame N-1. The first asynchronous frame waits for its own surface,
// so the first frame has one; refused input is reported in its own frame and starts no job.
//
// The effect says only what differs: how to mesh (its extractor call and any pass over the finished
// mesh), and, for the worker, how to hand over a copy the job owns while the caller's particles move.

#include "fluid/surface/async_extractor.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <functional>
#include <memory>

namespace game {

class SurfaceJob {
 public:
  fluid::SurfaceMesh mesh;  // the surface drawn this frame (asynchronous: the previous frame's particles)
  double worker_ms = 0.0;   // asynchronous: the worker's time on `mesh` (0 when synchronous)

  // Meshes with `mesh_now(extractor, mesh)` on the caller's thread; a worker left from asynchronous
  // frames is stopped (its job dropped).
  using MeshNow = std::function<fluid::SurfaceStatus(fluid::SurfaceExtractor&, fluid::SurfaceMesh&)>;
  fluid::SurfaceStatus meshNow(const MeshNow& mesh_now);

  // Takes the surface of the job in flight into `mesh`, then `hand_over(worker)` validates this
  // frame's copy and starts its job (AsyncSurfaceExtractor::start or startJob); an error it returns
  // clears `mesh` and starts nothing. `hand_over` may run twice in the first frame (once for the
  // surface waited for, once for the job left running), so it must only copy and start.
  using HandOver = std::function<fluid::SurfaceStatus(fluid::AsyncSurfaceExtractor&)>;
  fluid::SurfaceStatus meshBehind(const HandOver& hand_over);

  // No surface (a renderer that needs none): the worker stops and the mesh is emptied.
  void drop();

 private:
  fluid::SurfaceStatus failed(const fluid::SurfaceStatus& st);

  fluid::SurfaceExtractor extractor_;                     // synchronous frames
  std::unique_ptr<fluid::AsyncSurfaceExtractor> worker_;  // asynchronous frames, made at first use
};

}  // namespace game
