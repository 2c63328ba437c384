#include "engine/fluid_render/screen_space.hpp"
#include "engine/fluid_render/water_backend.hpp"

#include "fluid/core/finite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace engine {

namespace {

constexpr float kEmptyDepth = 1e30f;  // "no water" in the depth targets (shaders test >= 1e20)

GLuint colourTargetFbo(GLuint texture, GLuint depth) {
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
  if (depth != 0) glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth, 0);
  return fbo;
}

bool drawsEllipsoids(const ScreenSpaceRenderer& r) {
  return r.shapes.count > 0 && r.shapes.count == r.particles.count;
}

void drawParticles(const ScreenSpaceRenderer& r) {
  glBindVertexArray(drawsEllipsoids(r) ? r.ellipsoid_vao : r.vao);
  glDrawArraysInstanced(GL_TRIANGLES, 0, 3, static_cast<GLsizei>(r.particles.count));
  glBindVertexArray(0);
}

}  // namespace

bool parseDepthFilter(std::string_view text, DepthFilter& out) {
  if (text == "bilateral") {
    out = DepthFilter::bilateral;
    return true;
  }
  if (text == "narrow_range") {
    out = DepthFilter::narrow_range;
    return true;
  }
  return false;
}

void createScreenSpaceRenderer(const FluidRenderDesc& desc, ScreenSpaceRenderer& out) {
  destroyScreenSpaceRenderer(out);
  out = ScreenSpaceRenderer{};
  out.desc = desc;
  if (desc.width < 1 || desc.height < 1 || desc.width > 8192 || desc.height > 8192) {
    out.error = "screen-space fluid: size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                " out of range 1..8192";
    return;
  }
  const std::filesystem::path dir = desc.shader_dir / "fluid";
  const std::filesystem::path billboard = dir / "particle_billboard.vert", blit = dir / "blit.vert";
  std::string error;
  auto build = [&](std::vector<ShaderStageFiles> stages) {
    const GLuint p = buildProgram(stages, "", error);
    out.error += error;
    return p;
  };
  out.depth_program =
      build({{GL_VERTEX_SHADER, {billboard}}, {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "ss_depth.frag"}}});
  out.thickness_program =
      build({{GL_VERTEX_SHADER, {billboard}}, {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "ss_thickness.frag"}}});
  out.smooth_program = build({{GL_VERTEX_SHADER, {blit}}, {GL_FRAGMENT_SHADER, {dir / "ss_smooth.frag"}}});
  out.composite_program = build({{GL_VERTEX_SHADER, {blit}},
                                 {GL_FRAGMENT_SHADER,
                                  {dir / "shading.glsl", dir / "depth.glsl", dir / "ray.glsl", dir / "water_shade.glsl",
                                   dir / "ss_composite.frag"}}});
  out.blit_program = build({{GL_VERTEX_SHADER, {blit}}, {GL_FRAGMENT_SHADER, {dir / "blit.frag"}}});
  out.narrow_program = build({{GL_VERTEX_SHADER, {blit}}, {GL_FRAGMENT_SHADER, {dir / "ss_narrow.frag"}}});
  // The same splat shaders with ELLIPSOID defined (anisotropic kernels).
  auto build_ellipsoid = [&](std::vector<ShaderStageFiles> stages) {
    const GLuint p = buildProgram(stages, "#define ELLIPSOID 1", error);
    out.error += error;
    return p;
  };
  out.ellipsoid_depth_program = build_ellipsoid(
      {{GL_VERTEX_SHADER, {billboard}}, {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "ss_depth.frag"}}});
  out.ellipsoid_thickness_program = build_ellipsoid(
      {{GL_VERTEX_SHADER, {billboard}}, {GL_FRAGMENT_SHADER, {dir / "ray.glsl", dir / "ss_thickness.frag"}}});
  if (!out.error.empty()) {
    out.error = "screen-space fluid disabled, shader build failed:\n" + out.error;
    return;
  }
  const int w = desc.width, h = desc.height;
  const bool scene_ok = createSceneTargets(w, h, out.scene);
  out.depth_buffer = createTexture2D(GL_DEPTH_COMPONENT24, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  for (int i = 0; i < 2; ++i) {
    out.smooth_depth[i] = createTexture2D(GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
    out.smooth_fbo[i] = colourTargetFbo(out.smooth_depth[i], 0);
  }
  out.depth_fbo = colourTargetFbo(out.smooth_depth[0], out.depth_buffer);
  const bool depth_ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  out.thickness = createTexture2D(GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
  out.thickness_fbo = colourTargetFbo(out.thickness, 0);
  const bool thickness_ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  createParticleBuffer(out.particles, out.vao);
  glGenVertexArrays(1, &out.empty_vao);
  createShapeBuffer(out.particles, out.shapes, out.ellipsoid_vao);  // attributes 0-3: centre, g
  if (!scene_ok || !depth_ok || !thickness_ok || glGetError() != GL_NO_ERROR) {
    out.error = "screen-space fluid disabled: float render targets not supported";
    return;
  }
  out.ready = true;
}

GlObjectNames glNames(const ScreenSpaceRenderer& r) {
  GlObjectNames n;
  if (r.scene.fbo != 0) listNames(r.scene, n);
  for (GLuint t : {r.depth_buffer, r.smooth_depth[0], r.smooth_depth[1], r.thickness})
    if (t != 0) n.textures.push_back(t);
  for (GLuint f : {r.depth_fbo, r.smooth_fbo[0], r.smooth_fbo[1], r.thickness_fbo})
    if (f != 0) n.framebuffers.push_back(f);
  for (GLuint b : {r.particles.buffer, r.shapes.buffer})
    if (b != 0) n.buffers.push_back(b);
  for (GLuint v : {r.vao, r.empty_vao, r.ellipsoid_vao})
    if (v != 0) n.vertex_arrays.push_back(v);
  for (GLuint p : {r.depth_program, r.thickness_program, r.smooth_program, r.composite_program, r.blit_program,
                   r.narrow_program, r.ellipsoid_depth_program, r.ellipsoid_thickness_program})
    if (p != 0) n.programs.push_back(p);
  return n;
}

void destroyScreenSpaceRenderer(ScreenSpaceRenderer& r) {
  destroySceneTargets(r.scene);
  for (GLuint* t : {&r.depth_buffer, &r.smooth_depth[0], &r.smooth_depth[1], &r.thickness})
    if (*t != 0) glDeleteTextures(1, t);
  for (GLuint* f : {&r.depth_fbo, &r.smooth_fbo[0], &r.smooth_fbo[1], &r.thickness_fbo})
    if (*f != 0) glDeleteFramebuffers(1, f);
  for (GLuint* b : {&r.particles.buffer, &r.shapes.buffer})
    if (*b != 0) glDeleteBuffers(1, b);
  for (GLuint* v : {&r.vao, &r.empty_vao, &r.ellipsoid_vao})
    if (*v != 0) glDeleteVertexArrays(1, v);
  for (GLuint p : {r.depth_program, r.thickness_program, r.smooth_program, r.composite_program, r.blit_program,
                   r.narrow_program, r.ellipsoid_depth_program, r.ellipsoid_thickness_program})
    if (p != 0) glDeleteProgram(p);
  const FluidRenderDesc desc = r.desc;
  r = ScreenSpaceRenderer{};
  r.desc = desc;
}

void beginScreenSpaceOpaquePass(ScreenSpaceRenderer& r, glm::vec4 clear_colour) {
  if (!r.ready) return;
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene.fbo);
  glViewport(0, 0, r.desc.width, r.desc.height);
  glClearColor(clear_colour.r, clear_colour.g, clear_colour.b, clear_colour.a);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

bool uploadScreenSpaceParticles(ScreenSpaceRenderer& r, std::span<const glm::vec3> positions, std::string& error) {
  r.shapes.count = 0;  // spheres
  return uploadParticles(r.particles, positions, error);
}

bool uploadScreenSpaceEllipsoids(ScreenSpaceRenderer& r, std::span<const glm::vec3> centres,
                                 std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error) {
  return uploadEllipsoids(r.particles, r.shapes, centres, g, max_axis, error);
}

void filterScreenSpaceDepth(ScreenSpaceRenderer& r, const FluidCamera& camera, const ScreenSpaceParams& params) {
  if (!r.ready) return;
  const int w = r.desc.width, h = r.desc.height;
  glViewport(0, 0, w, h);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE0);
  const bool narrow = params.filter == DepthFilter::narrow_range;
  const GLuint p = narrow ? r.narrow_program : r.smooth_program;
  glUseProgram(p);
  setUniform(p, "u_world_radius", std::max(params.filter_radius, 0.0f));
  setUniform(p, "u_focal_px", camera.projection[1][1] * static_cast<float>(h) * 0.5f);
  setUniform(p, "u_depth", 0);
  if (narrow) {
    const float radius = std::max(params.radius, 1e-5f);
    setUniform(p, "u_threshold", radius * std::clamp(params.narrow_threshold, 0.0f, 1000.0f));
    setUniform(p, "u_clamp", radius * std::clamp(params.narrow_clamp, 0.0f, 1000.0f));
  } else {
    setUniform(p, "u_depth_falloff", std::max(params.depth_falloff, 1e-4f));
  }
  glBindVertexArray(r.empty_vao);
  int iterations = std::clamp(params.smoothing_iterations, 0, 32);
  if (narrow && iterations > 1) {
    // The narrow-range filter runs once (the paper's use): its clamp moves a surface in front of
    // a far layer back by up to `clamp` per round, so repeated rounds would add up. One round as
    // wide as the bilateral's n rounds together (Gaussians compose: sigma sqrt(n)).
    setUniform(p, "u_world_radius", std::max(params.filter_radius, 0.0f) * std::sqrt(static_cast<float>(iterations)));
    iterations = 1;
  }
  for (int i = 0; i < 2 * iterations; ++i) {
    const int from = i % 2, to = 1 - from;
    glBindFramebuffer(GL_FRAMEBUFFER, r.smooth_fbo[to]);
    glBindTexture(GL_TEXTURE_2D, r.smooth_depth[from]);
    setUniform(p, "u_direction", from == 0 ? glm::vec2(1, 0) : glm::vec2(0, 1));
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glBindVertexArray(0);
}

void drawScreenSpaceFluid(ScreenSpaceRenderer& r, GLuint target_fbo, const FluidCamera& camera,
                          const WaterParams& water, const ScreenSpaceParams& params) {
  if (!r.ready) return;
  const int w = r.desc.width, h = r.desc.height;
  const float radius = std::max(params.radius, 1e-5f);
  glViewport(0, 0, w, h);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE0);
  if (r.particles.count > 0) {
    // Pass 1: nearest sphere, linear depth into smooth_depth[0] with our own z-buffer.
    glBindFramebuffer(GL_FRAMEBUFFER, r.depth_fbo);
    const GLfloat empty[4] = {kEmptyDepth, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, empty);
    glClearDepth(1.0);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    const bool ellipsoids = drawsEllipsoids(r);
    const GLuint depth_program = ellipsoids ? r.ellipsoid_depth_program : r.depth_program;
    const GLuint thickness_program = ellipsoids ? r.ellipsoid_thickness_program : r.thickness_program;
    glUseProgram(depth_program);
    setParticleCamera(depth_program, camera, w, h);
    setUniform(depth_program, "u_radius", radius);
    glBindTexture(GL_TEXTURE_2D, r.scene.depth);
    setUniform(depth_program, "u_scene_depth", 0);
    drawParticles(r);
    glDisable(GL_DEPTH_TEST);
    // Pass 2: thickness, additive.
    glBindFramebuffer(GL_FRAMEBUFFER, r.thickness_fbo);
    const GLfloat zero[4] = {0, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, zero);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    glUseProgram(thickness_program);
    setParticleCamera(thickness_program, camera, w, h);
    setUniform(thickness_program, "u_radius", radius);
    setUniform(thickness_program, "u_scene_depth", 0);
    drawParticles(r);
    glDisable(GL_BLEND);
    // Pass 3: the depth filter, horizontal then vertical per iteration (ends in [0]).
    filterScreenSpaceDepth(r, camera, params);
  }
  // Scene colour into the target, then the water over it.
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glUseProgram(r.blit_program);
  glBindTexture(GL_TEXTURE_2D, r.scene.colour);
  setUniform(r.blit_program, "u_colour", 0);
  glBindVertexArray(r.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (r.particles.count > 0) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    const GLuint p = r.composite_program;
    glUseProgram(p);
    setParticleCamera(p, camera, w, h);
    setWaterShading(p, water);
    const GLuint textures[] = {r.scene.colour, r.scene.depth, r.smooth_depth[0], r.thickness};
    const char* names[] = {"u_scene_colour", "u_scene_depth", "u_fluid_depth", "u_thickness"};
    for (int i = 0; i < 4; ++i) {
      glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(i));
      glBindTexture(GL_TEXTURE_2D, textures[i]);
      setUniform(p, names[i], i);
    }
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_BLEND);
    glActiveTexture(GL_TEXTURE0);
  }
  glBindVertexArray(0);
  glUseProgram(0);  // a deleted program stays alive while current
}

// Screen-space splats as a water backend (water_backend.hpp).
namespace {
class ScreenSpaceWaterBackend final : public WaterBackend {
 public:
  explicit ScreenSpaceWaterBackend(const FluidRenderDesc& desc) { createScreenSpaceRenderer(desc, renderer_); }
  ~ScreenSpaceWaterBackend() override { destroyScreenSpaceRenderer(renderer_); }
  bool ready() const override { return renderer_.ready; }
  const std::string& error() const override { return renderer_.error; }
  GLuint upload(const WaterInput& in, std::string& error) override {
    if (!renderer_.ready) return 0;
    // Anisotropic kernels when the input carries them (one per particle): ellipsoid splats at the
    // smoothed centres.
    const bool ellipsoids = !in.kernel_g.empty() && in.kernel_g.size() == in.particles.size();
    const bool ok = ellipsoids ? uploadScreenSpaceEllipsoids(renderer_, in.kernel_centres, in.kernel_g,
                                                             in.kernel_max_axis, error)
                               : uploadScreenSpaceParticles(renderer_, in.particles, error);
    return ok ? renderer_.scene.fbo : 0;
  }
  void draw(GLuint target_fbo, const FluidCamera& camera, const WaterParams& water, const WaterInput& in) override {
    ScreenSpaceParams params;
    params.radius = 0.975f * in.rc / 3.0f;  // a lone particle's iso-surface radius in the mesh's field
    params.filter_radius = 0.5f * in.rc;
    if (!parseDepthFilter(in.ss_filter, params.filter)) params.filter = DepthFilter::bilateral;
    drawScreenSpaceFluid(renderer_, target_fbo, camera, water, params);
  }

 private:
  ScreenSpaceRenderer renderer_;
};
}  // namespace

const WaterBackendDesc& screenSpaceWaterBackend() {
  static const WaterBackendDesc desc{"screen_space",
                                     "sphere or ellipsoid splats, bilateral or narrow-range depth smoothing, thickness (Janisz 3.1 after "
                                     "van der Laan 2009; Yu & Turk 2013; Truong & Yuksel 2018)",
                                     false, [](const FluidRenderDesc& d) -> std::unique_ptr<WaterBackend> {
                                       return std::make_unique<ScreenSpaceWaterBackend>(d);
                                     }};
  return desc;
}

}  // namespace engine
