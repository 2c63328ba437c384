#include "game/world/fluid_surface.hpp"

#include <chrono>

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

namespace {

// Fills the kernels of `positions` into `job` and returns the extractor's input (their centres and
// stretch). A non-finite position leaves every kernel a sphere at its particle (computeAnisotropy's
// false), and the extractor then refuses that position by name.
fluid::SurfaceInput kernelInput(SurfaceKernelJob& job, std::span<const glm::vec3> positions) {
  const auto t0 = std::chrono::steady_clock::now();
  (void)fluid::computeAnisotropy(positions, job.params, job.scratch, job.kernels);
  job.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return {fluid::pointView(job.kernels.centre), {}, {}, {}, job.kernels.g};
}

}  // namespace

bool meshFluidSurface(FluidSurface& s, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir,
                      const fluid::AnisotropyParams* anisotropy) {
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
  const std::span<const glm::vec3> positions = fluid.world.particles.position;
  const fluid::SurfaceInput input{fluid::pointView(positions)};
  if (anisotropy != nullptr && !s.kernel_job) s.kernel_job = std::make_unique<SurfaceKernelJob>();
  SurfaceKernelJob* kernels = anisotropy != nullptr ? s.kernel_job.get() : nullptr;
  if (kernels == nullptr) s.kernel_ms = 0.0, s.kernels_stretched = 0;
  if (!s.params.async) {
    return finish(s, s.job.meshNow([&](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
      if (n == 0) {
        mesh.clear();
        return fluid::SurfaceStatus{};
      }
      if (kernels == nullptr) return extractor.extract(input, sp, mesh);
      kernels->params = *anisotropy;
      const fluid::SurfaceInput stretched = kernelInput(*kernels, positions);
      s.kernel_ms = kernels->ms, s.kernels_stretched = kernels->kernels.stretched;
      return extractor.extract(stretched, sp, mesh);
    }));
  }
  // The worker's start() copies the particles, so the steps may move them at once. With kernels
  // the job copies them into `kernels` and makes the kernels itself; the job before it has been
  // collected when this runs (SurfaceJob::meshBehind), so its figures are read here, not later.
  return finish(s, s.job.meshBehind([&](fluid::AsyncSurfaceExtractor& worker) {
    fluid::SurfaceStatus valid = fluid::validateSurface(input, sp);
    if (!valid.ok()) return valid;
    if (kernels == nullptr) {
      worker.start(input, sp);
      return valid;
    }
    s.kernel_ms = kernels->ms, s.kernels_stretched = kernels->kernels.stretched;
    kernels->positions.assign(positions.begin(), positions.end());
    kernels->params = *anisotropy;
    kernels->surface = sp;
    worker.startJob([kernels](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
      return extractor.extract(kernelInput(*kernels, kernels->positions), kernels->surface, mesh);
    });
    return valid;
  }));
}

}  // namespace game
