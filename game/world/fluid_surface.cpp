#include "game/world/fluid_surface.hpp"

namespace game {

bool meshFluidSurface(FluidSurface& s, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir) {
  if (s.params.method != SurfaceMethodChoice::mesh) {  // the particle renderers need no mesh
    s.mesh.clear();
    s.error.clear();
    return true;
  }
  // The SPH store's own SoA arrays (fluid/sph: one particle layout), read without a copy.
  const fluid::SphPositionArrays positions = fluid::sphPositionArrays(fluid.world);
  const std::size_t n = fluid.world.particles.size();
  if (positions.x.size() != n) {
    s.mesh.clear();
    s.error = "fluid_surface: the SPH position arrays hold " + std::to_string(positions.x.size()) + " of " +
              std::to_string(n) + " particles (positions written outside a step without refreshSphPositionArrays)";
    return false;
  }
  ++s.meshes;
  if (n == 0) {
    s.mesh.clear();
    return true;
  }
  const float spacing = fluid::sphSpacing(fluid.world.params);
  fluid::SurfaceParams sp;
  sp.rc = s.params.smoothing * spacing;
  sp.cube = s.params.cube * spacing;
  sp.threshold = s.params.threshold;
  // Paper §5: sweep along the axis nearest the view, farthest blocks first, so blending the
  // triangles in index order composites back-to-front.
  sp.order =
      s.params.order == SurfaceOrderChoice::unsorted ? fluid::SurfaceOrder::none : fluid::SurfaceOrder::backToFront;
  sp.exactSlabOrder = s.params.order == SurfaceOrderChoice::exact;
  sp.eye = eye;
  sp.viewDir = view_dir;
  fluid::SurfaceInput input;
  input.x = positions.x;
  input.y = positions.y;
  input.z = positions.z;
  const fluid::SurfaceStatus st = s.extractor.extract(input, sp, s.mesh);
  if (!st.ok()) {
    s.error = "fluid_surface: " + st.error;
    return false;
  }
  s.error.clear();
  return true;
}

}  // namespace game
