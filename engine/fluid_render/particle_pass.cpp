#include "engine/fluid_render/particle_pass.hpp"

#include "fluid/core/finite.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace engine {

const char* fluidMethodName(FluidMethod method) {
  switch (method) {
    case FluidMethod::mesh:
      return "mesh";
    case FluidMethod::screen_space:
      return "screen_space";
    case FluidMethod::raycast:
      return "raycast";
  }
  return "mesh";
}

bool parseFluidMethod(std::string_view text, FluidMethod& out) {
  for (FluidMethod m : {FluidMethod::mesh, FluidMethod::screen_space, FluidMethod::raycast}) {
    if (text == fluidMethodName(m)) {
      out = m;
      return true;
    }
  }
  return false;
}

std::size_t countLiveGlObjects(const GlObjectNames& n) {
  std::size_t live = 0;
  for (GLuint b : n.buffers) live += glIsBuffer(b) == GL_TRUE;
  for (GLuint t : n.textures) live += glIsTexture(t) == GL_TRUE;
  for (GLuint f : n.framebuffers) live += glIsFramebuffer(f) == GL_TRUE;
  for (GLuint v : n.vertex_arrays) live += glIsVertexArray(v) == GL_TRUE;
  for (GLuint p : n.programs) live += glIsProgram(p) == GL_TRUE;
  return live;
}

bool createSceneTargets(int w, int h, SceneTargets& out) {
  out.colour = createTexture2D(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr, GL_LINEAR);
  out.depth = createTexture2D(GL_DEPTH_COMPONENT24, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  glGenFramebuffers(1, &out.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, out.fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out.colour, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, out.depth, 0);
  const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return complete;
}

void destroySceneTargets(SceneTargets& t) {
  for (GLuint* x : {&t.colour, &t.depth}) {
    if (*x != 0) glDeleteTextures(1, x);
  }
  if (t.fbo != 0) glDeleteFramebuffers(1, &t.fbo);
  t = SceneTargets{};
}

void listNames(const SceneTargets& t, GlObjectNames& out) {
  out.textures.push_back(t.colour);
  out.textures.push_back(t.depth);
  out.framebuffers.push_back(t.fbo);
}

void createParticleBuffer(ParticleBuffer& buffer, GLuint& vao) {
  glGenBuffers(1, &buffer.buffer);
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, buffer.buffer);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, nullptr);
  glVertexAttribDivisor(0, 1);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

bool uploadParticles(ParticleBuffer& b, std::span<const glm::vec3> positions, std::string& error) {
  error.clear();
  b.count = 0;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!fluid::isFinite(positions[i])) {
      error = "fluid particles: position " + std::to_string(i) + " is not finite";
      return false;
    }
  }
  if (b.buffer == 0 || positions.empty()) return true;
  const std::size_t need = positions.size() * sizeof(glm::vec4);
  glBindBuffer(GL_ARRAY_BUFFER, b.buffer);
  if (need > b.capacity_bytes) b.capacity_bytes = std::max(need, b.capacity_bytes + b.capacity_bytes / 2);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(b.capacity_bytes), nullptr, GL_STREAM_DRAW);
  auto* dst = static_cast<float*>(glMapBufferRange(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(need),
                                                   GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
  if (dst == nullptr) {
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    error = "fluid particles: glMapBufferRange failed";
    return false;
  }
  for (std::size_t i = 0; i < positions.size(); ++i) {
    dst[4 * i + 0] = positions[i].x;
    dst[4 * i + 1] = positions[i].y;
    dst[4 * i + 2] = positions[i].z;
    dst[4 * i + 3] = 1.0f;
  }
  glUnmapBuffer(GL_ARRAY_BUFFER);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  b.count = static_cast<std::uint32_t>(positions.size());
  return true;
}

void createShapeBuffer(const ParticleBuffer& particles, ShapeBuffer& shapes, GLuint& vao) {
  glGenBuffers(1, &shapes.buffer);
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, particles.buffer);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, nullptr);
  glVertexAttribDivisor(0, 1);
  glBindBuffer(GL_ARRAY_BUFFER, shapes.buffer);
  for (GLuint a = 1; a <= 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 48, reinterpret_cast<const void*>(std::uintptr_t{16} * (a - 1)));
    glVertexAttribDivisor(a, 1);
  }
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

bool uploadShapes(ShapeBuffer& s, std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error) {
  error.clear();
  s.count = 0;
  if (max_axis.size() != g.size()) {
    error = "fluid ellipsoids: " + std::to_string(g.size()) + " matrices, " + std::to_string(max_axis.size()) + " axes";
    return false;
  }
  for (std::size_t i = 0; i < g.size(); ++i) {
    bool finite = std::isfinite(max_axis[i]) && max_axis[i] > 0.0f;
    for (int c = 0; c < 3; ++c) finite = finite && fluid::isFinite(g[i][c]);
    if (!finite) {
      error = "fluid ellipsoids: matrix " + std::to_string(i) + " is not finite";
      return false;
    }
  }
  if (s.buffer == 0 || g.empty()) return true;
  const std::size_t need = g.size() * 3 * sizeof(glm::vec4);
  glBindBuffer(GL_ARRAY_BUFFER, s.buffer);
  if (need > s.capacity_bytes) s.capacity_bytes = std::max(need, s.capacity_bytes + s.capacity_bytes / 2);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(s.capacity_bytes), nullptr, GL_STREAM_DRAW);
  auto* dst = static_cast<glm::vec4*>(glMapBufferRange(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(need),
                                                       GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
  if (dst == nullptr) {
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    error = "fluid ellipsoids: glMapBufferRange failed";
    return false;
  }
  for (std::size_t i = 0; i < g.size(); ++i) {
    dst[3 * i + 0] = glm::vec4(g[i][0], max_axis[i]);
    dst[3 * i + 1] = glm::vec4(g[i][1], 0.0f);
    dst[3 * i + 2] = glm::vec4(g[i][2], 0.0f);
  }
  glUnmapBuffer(GL_ARRAY_BUFFER);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  s.count = static_cast<std::uint32_t>(g.size());
  return true;
}

bool uploadEllipsoids(ParticleBuffer& particles, ShapeBuffer& shapes, std::span<const glm::vec3> centres,
                      std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error) {
  shapes.count = 0;
  particles.count = 0;
  if (g.size() != centres.size()) {
    error =
        "fluid ellipsoids: " + std::to_string(centres.size()) + " centres, " + std::to_string(g.size()) + " matrices";
    return false;
  }
  if (!uploadShapes(shapes, g, max_axis, error)) return false;
  if (uploadParticles(particles, centres, error)) return true;
  shapes.count = 0;
  return false;
}

GLuint buildProgramWithStorage(std::span<const ShaderStageFiles> stages, bool compute, std::string& error,
                               std::string_view defines) {
  // The engine's programs are GLSL 3.30; the storage features come in as extensions so the
  // shared shading files (shading.glsl, depth.glsl) compile unchanged.
  const std::string prelude = std::string(compute ? "#extension GL_ARB_compute_shader : require\n" : "") +
                              "#extension GL_ARB_shader_storage_buffer_object : require\n"
                              "#extension GL_ARB_shader_image_load_store : require\n"
                              "#extension GL_ARB_shading_language_420pack : require\n" +
                              std::string(defines);
  return buildProgram(stages, prelude, error);
}

void setParticleCamera(GLuint prog, const FluidCamera& c, int width, int height) {
  setUniform(prog, "u_view", c.view);
  setUniform(prog, "u_projection", c.projection);
  setUniform(prog, "u_inv_view_projection", glm::inverse(c.projection * c.view));
  setUniform(prog, "u_eye", c.eye);
  setUniform(prog, "u_near_far", glm::vec2(c.near_plane, c.far_plane));
  setUniform(prog, "u_viewport", glm::vec2(static_cast<float>(width), static_cast<float>(height)));
}

void setWaterShading(GLuint prog, const WaterParams& p) {
  const glm::vec3 light =
      glm::length(p.light_direction) > 0.0f ? glm::normalize(p.light_direction) : glm::vec3(0, 1, 0);
  setUniform(prog, "u_absorption", p.absorption);
  setUniform(prog, "u_refraction", p.refraction);
  setUniform(prog, "u_ior", std::max(p.ior, 1.0f));
  setUniform(prog, "u_opacity", std::clamp(p.opacity, 0.0f, 1.0f));
  setUniform(prog, "u_sky_zenith", p.sky_zenith);
  setUniform(prog, "u_sky_horizon", p.sky_horizon);
  setUniform(prog, "u_light", light);
  setUniform(prog, "u_shininess", std::clamp(p.shininess, 1.0f, 4096.0f));
  setUniform(prog, "u_flash_position", p.flash_position);
  setUniform(prog, "u_flash_colour", p.flash_colour);
}

}  // namespace engine
