// renderFrame: the frame's passes in order (contract: frame.hpp).
#include "engine/render/frame.hpp"

#include <cstdio>
#include <string>

namespace engine {
namespace {

void releaseWater(WaterRenderers& pass) {
  if (pass.created) {
    destroyFluidRenderer(pass.mesh);
    destroyScreenSpaceRenderer(pass.screen_space);
    destroyRaycastRenderer(pass.raycast);
  }
  pass.created = false;
}

void createWater(WaterRenderers& pass, FluidMethod method, int width, int height,
                 const std::filesystem::path& shader_dir) {
  FluidRenderDesc desc;
  desc.width = width;
  desc.height = height;
  desc.shader_dir = shader_dir;
  bool ready = false;
  std::string error;
  if (method == FluidMethod::screen_space) {
    createScreenSpaceRenderer(desc, pass.screen_space);
    ready = pass.screen_space.ready;
    error = pass.screen_space.error;
  } else if (method == FluidMethod::raycast) {
    RaycastDesc rc;
    rc.base = desc;
    createRaycastRenderer(rc, pass.raycast);
    ready = pass.raycast.ready;
    error = pass.raycast.error;
  } else {
    createFluidRenderer(desc, pass.mesh);
    ready = pass.mesh.ready;
    error = pass.mesh.error;
  }
  pass.method = method;
  pass.width = width;
  pass.height = height;
  pass.created = true;
  if (!ready)
    std::fprintf(stderr, "fluiddemo: fluid_surface %s renderer unavailable: %s\n", fluidMethodName(method),
                 error.c_str());
}

// Uploads the batch to the method's renderer; returns its scene FBO (0 when that renderer is
// unavailable or the upload was refused).
GLuint uploadWater(WaterRenderers& pass, const WaterBatch& batch) {
  GLuint scene_fbo = 0;
  std::string error;
  bool uploaded = true;
  if (batch.method == FluidMethod::screen_space && pass.screen_space.ready) {
    scene_fbo = pass.screen_space.scene.fbo;
    uploaded = uploadScreenSpaceParticles(pass.screen_space, batch.particles, error);
  } else if (batch.method == FluidMethod::raycast && pass.raycast.ready) {
    scene_fbo = pass.raycast.scene.fbo;
    uploaded = uploadRaycastParticles(pass.raycast, batch.particles, error);
  } else if (batch.method == FluidMethod::mesh && pass.mesh.ready) {
    scene_fbo = pass.mesh.scene_fbo;
    uploaded = uploadFluidMesh(pass.mesh, batch.positions, batch.normals, batch.indices, batch.attributes, error);
  }
  if (scene_fbo != 0 && !uploaded) {
    std::fprintf(stderr, "fluiddemo: fluid upload: %s\n", error.c_str());
    return 0;
  }
  return scene_fbo;
}

void drawWater(Renderer& renderer, WaterRenderers& pass, const FrameView& view, const Lighting& lighting,
               const WaterBatch& batch, const std::filesystem::path& shader_dir) {
  if (!batch.visible) return;  // the renderer's objects stay for when the water shows again
  if (pass.created && (pass.width != renderer.width || pass.height != renderer.height || pass.method != batch.method))
    releaseWater(pass);
  if (!pass.created) createWater(pass, batch.method, renderer.width, renderer.height, shader_dir);
  const GLuint water_fbo = uploadWater(pass, batch);
  if (water_fbo == 0) return;
  // The opaque scene (colour + depth) is the water's background: copy it into the water
  // renderer's scene targets (same size, DEPTH24 both), then draw the water back into the scene
  // FBO so screenshots and the window blit see it.
  glBindFramebuffer(GL_READ_FRAMEBUFFER, renderer.scene_fbo.id());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, water_fbo);
  glBlitFramebuffer(0, 0, renderer.width, renderer.height, 0, 0, renderer.width, renderer.height,
                    GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  FluidCamera camera;
  camera.view = view.view;
  camera.projection = view.projection;
  camera.eye = view.eye;
  camera.near_plane = view.near_plane;
  camera.far_plane = view.far_plane;
  WaterParams water;
  water.refraction = batch.refraction;
  water.opacity = batch.opacity;
  water.absorption = batch.absorption;
  water.style = batch.style;
  water.goo_colour = batch.goo_colour;
  water.goo_density = batch.goo_density;
  water.goo_texture = batch.goo_texture != nullptr ? batch.goo_texture->texture.id() : 0;
  // Sky reflected by the water: the scene's own sky colours, so the water matches the scene.
  water.sky_zenith = lighting.sky_zenith;
  water.sky_horizon = lighting.sky_horizon;
  water.light_direction = lighting.sun_direction;
  water.flash_position = lighting.flash_position;
  water.flash_colour = lighting.flash_colour;
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
  if (batch.method == FluidMethod::screen_space) {
    ScreenSpaceParams ss;
    ss.radius = 0.975f * batch.rc / 3.0f;  // a lone particle's iso-surface radius
    ss.filter_radius = 0.5f * batch.rc;
    drawScreenSpaceFluid(pass.screen_space, renderer.scene_fbo.id(), camera, water, ss);
  } else if (batch.method == FluidMethod::raycast) {
    RaycastParams rp;
    rp.rc = batch.rc;
    rp.threshold = batch.threshold;
    drawRaycastFluid(pass.raycast, renderer.scene_fbo.id(), camera, water, rp);
    if (batch.raycast_counts != nullptr) {
      batch.raycast_counts->records = pass.raycast.used;
      batch.raycast_counts->dropped = pass.raycast.dropped;
      batch.raycast_counts->pool = pass.raycast.pool_records;
      batch.raycast_counts->pool_bound = pass.raycast.max_pool_records;
    }
  } else {
    drawFluid(pass.mesh, renderer.scene_fbo.id(), camera, water);
  }
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  checkGl(renderer.errors, "fluid surface");
}

void drawSpritePass(Renderer& renderer, GpuParticles& system, const FrameView& view) {
  sortStep(system, view.eye);
  glBindFramebuffer(GL_FRAMEBUFFER, renderer.scene_fbo.id());
  glViewport(0, 0, renderer.width, renderer.height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
  drawSprites(system, view.projection * view.view, view.projection[1][1], renderer.height);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl(renderer.errors, "sprites");
}

// A full-screen colour over the frame; the scene's alpha stays 1.
void drawScreenTint(Renderer& renderer, glm::vec4 tint) {
  glBindFramebuffer(GL_FRAMEBUFFER, renderer.scene_fbo.id());
  glViewport(0, 0, renderer.width, renderer.height);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
  const GLuint program = renderer.tint_program.id();
  glUseProgram(program);
  setUniform(program, "u_tint", glm::clamp(tint, glm::vec4(0.0f), glm::vec4(1.0f)));
  glBindVertexArray(renderer.empty_vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl(renderer.errors, "screen tint");
}

}  // namespace

void renderFrame(Renderer& renderer, FramePasses& passes, const FrameView& view, const Lighting& lighting,
                 const FrameBatches& batches) {
  renderScene(renderer, view, lighting, batches.opaque, true);
  for (std::size_t i = batches.water.size(); i < passes.water.size(); ++i) releaseWater(passes.water[i]);
  if (passes.water.size() < batches.water.size()) passes.water.resize(batches.water.size());
  for (std::size_t i = 0; i < batches.water.size(); ++i)
    drawWater(renderer, passes.water[i], view, lighting, batches.water[i], passes.shader_dir);
  for (GpuParticles* system : batches.sprites) drawSpritePass(renderer, *system, view);
  if (batches.screen_tint.a > 0.0f) drawScreenTint(renderer, batches.screen_tint);
}

void releaseFramePasses(FramePasses& passes) {
  for (WaterRenderers& pass : passes.water) releaseWater(pass);
}

}  // namespace engine
