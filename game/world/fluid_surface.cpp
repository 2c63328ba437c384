#include "game/world/fluid_surface.hpp"

namespace game {

fluid::SurfaceParams surfaceParamsFor(const FluidSurfaceParams& p, float spacing, glm::vec3 eye, glm::vec3 view_dir) {
  fluid::SurfaceParams sp;
  sp.rc = p.smoothing * spacing;
  sp.cube = p.cube * spacing;
  sp.threshold = p.threshold;
  sp.fieldRoute = p.field;
  // Paper §5: sweep along the axis nearest the view, farthest blocks first, so blending the
  // triangles in index order composites back-to-front.
  sp.order = p.order == SurfaceOrderChoice::unsorted ? fluid::SurfaceOrder::none : fluid::SurfaceOrder::backToFront;
  sp.exactSlabOrder = p.order == SurfaceOrderChoice::exact;
  sp.eye = eye;
  sp.viewDir = view_dir;
  return sp;
}

namespace {

bool finish(FluidSurface& s, const fluid::SurfaceStatus& st) {
  if (!st.ok()) {
    s.error = "fluid_surface: " + st.error;
    return false;
  }
  s.error.clear();
  return true;
}

}  // namespace

bool meshFluidSurface(FluidSurface& s, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir) {
  s.mesh_worker_ms = 0.0;
  const engine::WaterBackendDesc* backend = engine::findWaterBackend(s.params.method);
  if (backend == nullptr || !backend->needs_mesh) {  // the particle renderers need no mesh
    s.async_job.reset();
    s.mesh.clear();
    s.error.clear();
    return true;
  }
  // The SPH store's own SoA arrays (fluid/sph: one particle layout), read without a copy (the
  // async job copies them, as it must: the next steps move them while it meshes).
  const fluid::SphPositionArrays positions = fluid::sphPositionArrays(fluid.world);
  const std::size_t n = fluid.world.particles.size();
  if (positions.x.size() != n) {
    s.mesh.clear();
    s.error = "fluid_surface: the SPH position arrays hold " + std::to_string(positions.x.size()) + " of " +
              std::to_string(n) + " particles (positions written outside a step without refreshSphPositionArrays)";
    return false;
  }
  ++s.meshes;
  const fluid::SurfaceParams sp = surfaceParamsFor(s.params, fluid::sphSpacing(fluid.world.params), eye, view_dir);
  fluid::SurfaceInput input;
  input.x = positions.x;
  input.y = positions.y;
  input.z = positions.z;
  if (!s.params.async) {
    s.async_job.reset();
    if (n == 0) {
      s.mesh.clear();
      return finish(s, {});
    }
    return finish(s, s.extractor.extract(input, sp, s.mesh));
  }
  if (!s.async_job) s.async_job = std::make_unique<fluid::AsyncSurfaceExtractor>();
  fluid::AsyncSurfaceExtractor& job = *s.async_job;
  // Refused input is reported in this frame, once, and starts no job: the job in flight is
  // dropped, and the next good frame waits for its own surface like the first one.
  if (const fluid::SurfaceStatus valid = fluid::validateSurface(input, sp); !valid.ok()) {
    if (job.pending()) (void)job.collect(s.mesh);
    s.mesh.clear();
    return finish(s, valid);
  }
  if (!job.pending()) job.start(input, sp);  // first frame: this frame's own surface, waited for
  const fluid::SurfaceStatus st = job.collect(s.mesh);
  s.mesh_worker_ms = job.lastJobMs();
  job.start(input, sp);
  return finish(s, st);
}

}  // namespace game
