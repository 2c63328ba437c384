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

bool meshFluidSurface(FluidSurface& s, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir,
                      const fluid::Anisotropy* kernels) {
  const engine::WaterBackendDesc* backend = engine::findWaterBackend(s.params.method);
  if (backend == nullptr || !backend->needs_mesh) {  // the particle renderers need no mesh
    s.job.drop();
    s.error.clear();
    return true;
  }
  // The SPH store's own positions, read in place through a pointer + stride view (one particle
  // layout; the async job copies them, as it must: the next steps move them while it meshes).
  const std::size_t n = fluid.world.particles.size();
  ++s.meshes;
  const fluid::SurfaceParams sp = surfaceParamsFor(s.params, fluid::sphSpacing(fluid.world.params), eye, view_dir);
  const fluid::SurfaceInput input =
      kernels != nullptr ? fluid::SurfaceInput{fluid::pointView(kernels->centre), {}, {}, {}, kernels->g}
                         : fluid::SurfaceInput{fluid::pointView(fluid.world.particles.position)};
  if (!s.params.async) {
    return finish(s, s.job.meshNow([&](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
      if (n == 0) {
        mesh.clear();
        return fluid::SurfaceStatus{};
      }
      return extractor.extract(input, sp, mesh);
    }));
  }
  // The worker's start() copies the particles, so the steps may move them at once.
  return finish(s, s.job.meshBehind([&](fluid::AsyncSurfaceExtractor& worker) {
    fluid::SurfaceStatus valid = fluid::validateSurface(input, sp);
    if (valid.ok()) worker.start(input, sp);
    return valid;
  }));
}

}  // namespace game
