// renderFrame: the frame's passes in order (contract: frame.hpp).
#include "engine/render/frame.hpp"

#include <cstdio>
#include <string>

namespace engine {
namespace {

void releaseWater(WaterSlot& slot) {
  slot.backend.reset();
  slot.stats = {};
}

// The slot's backend for this batch at this size: kept, or made anew from the registry.
WaterBackend* backendFor(WaterSlot& slot, const WaterBatch& batch, int width, int height,
                         const std::filesystem::path& shader_dir) {
  if (slot.backend && slot.width == width && slot.height == height && slot.method == batch.method)
    return slot.backend->ready() ? slot.backend.get() : nullptr;
  const bool failed_before =
      !slot.backend && slot.method == batch.method && slot.width == width && slot.height == height;
  releaseWater(slot);
  slot.method = std::string(batch.method);
  slot.width = width;
  slot.height = height;
  const WaterBackendDesc* desc = findWaterBackend(batch.method);
  if (desc == nullptr) {
    if (!failed_before) std::fprintf(stderr, "fluiddemo: no water renderer named '%s'\n", slot.method.c_str());
    return nullptr;
  }
  FluidRenderDesc create;
  create.width = width;
  create.height = height;
  create.shader_dir = shader_dir;
  slot.backend = desc->create(create);
  if (!slot.backend->ready()) {
    std::fprintf(stderr, "fluiddemo: fluid_surface %s renderer unavailable: %s\n", slot.method.c_str(),
                 slot.backend->error().c_str());
    return nullptr;
  }
  return slot.backend.get();
}

void drawWater(Renderer& renderer, WaterSlot& slot, const FrameView& view, const Lighting& lighting,
               const WaterBatch& batch, const std::filesystem::path& shader_dir) {
  slot.stats = {};
  if (!batch.visible) return;  // the backend's objects stay for when the water shows again
  WaterBackend* backend = backendFor(slot, batch, renderer.width, renderer.height, shader_dir);
  if (backend == nullptr) return;
  WaterInput input;
  input.positions = batch.positions;
  input.normals = batch.normals;
  input.indices = batch.indices;
  input.attributes = batch.attributes;
  input.particles = batch.particles;
  input.rc = batch.rc;
  input.threshold = batch.threshold;
  input.kernel_g = batch.kernel_g;
  input.kernel_max_axis = batch.kernel_max_axis;
  input.kernel_centres = batch.kernel_centres;
  input.ss_filter = batch.ss_filter;
  std::string error;
  const GLuint water_fbo = backend->upload(input, error);
  if (water_fbo == 0) {
    if (!error.empty()) std::fprintf(stderr, "fluiddemo: fluid upload: %s\n", error.c_str());
    return;
  }
  // The opaque scene (colour + depth) is the water's background: copy it into the backend's scene
  // targets (same size, DEPTH24 both), then draw the water back into the scene FBO so screenshots
  // and the window blit see it.
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
  backend->draw(renderer.scene_fbo.id(), camera, water, input);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  slot.stats = backend->stats();
  checkGl(renderer.errors, "fluid surface");
}

// Kolb §3.3: the fixed steps since the last frame (births, update passes, read-backs, recorded by
// spawn/step), then the merge sort for this eye (§3.3.3), then the sprites back-to-front (§3.3.4).
void drawSpritePass(Renderer& renderer, GpuParticles& system, const FrameView& view) {
  runPendingWork(system);
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
  for (WaterSlot& slot : passes.water) releaseWater(slot);
}

void lastWaterStats(const FramePasses& passes, std::vector<WaterStats>& out) {
  out.clear();
  for (const WaterSlot& slot : passes.water) out.push_back(slot.stats);
}

}  // namespace engine
