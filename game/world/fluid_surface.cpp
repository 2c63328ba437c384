#include "game/world/fluid_surface.hpp"

namespace game {

bool meshFluidSurface(FluidSurface& s, const SphFluid& fluid, glm::vec3 eye, glm::vec3 view_dir) {
  if (s.params.method != SurfaceMethodChoice::mesh) {  // the particle renderers need no mesh
    s.mesh.clear();
    s.error.clear();
    return true;
  }
  const fluid::ParticleStore& particles = fluid.world.particles;
  const std::size_t n = particles.size();
  s.xs.resize(n);
  s.ys.resize(n);
  s.zs.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.xs[i] = particles.position[i].x;
    s.ys[i] = particles.position[i].y;
    s.zs[i] = particles.position[i].z;
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
  input.x = s.xs;
  input.y = s.ys;
  input.z = s.zs;
  const fluid::SurfaceStatus st = s.extractor.extract(input, sp, s.mesh);
  if (!st.ok()) {
    s.error = "fluid_surface: " + st.error;
    return false;
  }
  s.error.clear();
  return true;
}

}  // namespace game
