#include "game/world/fluid_surface.hpp"

namespace game {

bool surfaceParamsFrom(const SectionConfig& section, FluidSurfaceParams& out, std::string& error) {
  FluidSurfaceParams p;
  const std::string& order = section.text("order");
  if (order == "sorted") {
    p.order = SurfaceOrderChoice::sorted;
  } else if (order == "unsorted") {
    p.order = SurfaceOrderChoice::unsorted;
  } else if (order == "exact") {
    p.order = SurfaceOrderChoice::exact;
  } else {
    error = "fluid_surface.order: unknown order '" + order + "' (expected sorted, unsorted or exact)";
    return false;
  }
  const std::string& method = section.text("method");
  if (method == "mesh") {
    p.method = SurfaceMethodChoice::mesh;
  } else if (method == "screen_space") {
    p.method = SurfaceMethodChoice::screen_space;
  } else if (method == "raycast") {
    p.method = SurfaceMethodChoice::raycast;
  } else {
    error = "fluid_surface.method: unknown method '" + method + "' (expected mesh, screen_space or raycast)";
    return false;
  }
  p.smoothing = static_cast<float>(section.number("smoothing"));
  p.cube = static_cast<float>(section.number("cube"));
  p.threshold = static_cast<float>(section.number("threshold"));
  p.refraction = static_cast<float>(section.number("refraction"));
  p.opacity = static_cast<float>(section.number("opacity"));
  p.absorption = section.vec3("absorption");
  p.visible = section.boolean("visible");
  out = p;
  return true;
}

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
