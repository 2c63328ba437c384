#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/water_backend.hpp"

#include "engine/gl/gl.hpp"
#include "fluid/core/finite.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace engine {

namespace {

GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

// Capacity policy: grow to max(need, 1.5 × old) so a slowly growing mesh reallocates O(log n) times.
bool ensureCapacity(GLenum target, GLuint buffer, std::size_t need, std::size_t& capacity) {
  glBindBuffer(target, buffer);
  if (need <= capacity) {
    // Orphan: the driver hands out fresh storage if the GPU still reads last frame's.
    glBufferData(target, static_cast<GLsizeiptr>(capacity), nullptr, GL_STREAM_DRAW);
    return false;
  }
  capacity = std::max(need, capacity + capacity / 2);
  glBufferData(target, static_cast<GLsizeiptr>(capacity), nullptr, GL_STREAM_DRAW);
  return true;
}

void setCamera(GLuint prog, const FluidCamera& c, const FluidRenderer& r) {
  glUniformMatrix4fv(loc(prog, "u_view"), 1, GL_FALSE, glm::value_ptr(c.view));
  glUniformMatrix4fv(loc(prog, "u_projection"), 1, GL_FALSE, glm::value_ptr(c.projection));
  glUniform3fv(loc(prog, "u_eye"), 1, glm::value_ptr(c.eye));
  glUniform2f(loc(prog, "u_near_far"), c.near_plane, c.far_plane);
  glUniform2f(loc(prog, "u_viewport"), static_cast<float>(r.desc.width), static_cast<float>(r.desc.height));
}

void setShading(GLuint prog, const WaterParams& p) {
  const glm::vec3 light =
      glm::length(p.light_direction) > 0.0f ? glm::normalize(p.light_direction) : glm::vec3(0, 1, 0);
  glUniform3fv(loc(prog, "u_absorption"), 1, glm::value_ptr(p.absorption));
  glUniform1f(loc(prog, "u_refraction"), p.refraction);
  glUniform1f(loc(prog, "u_ior"), std::max(p.ior, 1.0f));
  glUniform1f(loc(prog, "u_opacity"), std::clamp(p.opacity, 0.0f, 1.0f));
  glUniform3fv(loc(prog, "u_sky_zenith"), 1, glm::value_ptr(p.sky_zenith));
  glUniform3fv(loc(prog, "u_sky_horizon"), 1, glm::value_ptr(p.sky_horizon));
  glUniform3fv(loc(prog, "u_light"), 1, glm::value_ptr(light));
  glUniform1f(loc(prog, "u_shininess"), std::clamp(p.shininess, 1.0f, 4096.0f));
  glUniform3fv(loc(prog, "u_flash_position"), 1, glm::value_ptr(p.flash_position));
  glUniform3fv(loc(prog, "u_flash_colour"), 1, glm::value_ptr(p.flash_colour));
  glUniform3fv(loc(prog, "u_goo_colour"), 1, glm::value_ptr(p.goo_colour));
  glUniform1f(loc(prog, "u_goo_density"), std::clamp(p.goo_density, 0.0f, 1000.0f));
  glUniform1f(loc(prog, "u_goo_min_coverage"), std::clamp(p.goo_min_coverage, 0.0f, 1.0f));
}

}  // namespace

void createFluidRenderer(const FluidRenderDesc& desc, FluidRenderer& out) {
  destroyFluidRenderer(out);
  out = FluidRenderer{};
  out.desc = desc;
  if (desc.width < 1 || desc.height < 1 || desc.width > 8192 || desc.height > 8192) {
    out.error = "fluid render: size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                " out of range 1..8192";
    return;
  }
  const std::filesystem::path dir = desc.shader_dir / "fluid";
  std::string error;
  out.water_program = buildProgram(
      std::vector<ShaderStageFiles>{
          {GL_VERTEX_SHADER, {dir / "surface.vert"}},
          {GL_FRAGMENT_SHADER, {dir / "shading.glsl", dir / "depth.glsl", dir / "water.frag"}}},
      "", error);
  out.error += error;
  out.water_extent_program =
      buildProgram(std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "surface.vert"}},
                                                 {GL_FRAGMENT_SHADER, {dir / "depth.glsl", dir / "water_extent.frag"}}},
                   "", error);
  out.error += error;
  out.goo_program = buildProgram(
      std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "surface.vert"}},
                                    {GL_FRAGMENT_SHADER, {dir / "shading.glsl", dir / "depth.glsl", dir / "goo.frag"}}},
      "", error);
  out.error += error;
  out.blit_program = buildProgram(
      std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "blit.vert"}}, {GL_FRAGMENT_SHADER, {dir / "blit.frag"}}},
      "", error);
  out.error += error;
  if (!out.error.empty()) {
    out.error = "fluid rendering disabled, shader build failed:\n" + out.error;
    return;
  }
  const int w = desc.width, h = desc.height;
  out.scene_colour = createTexture2D(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr, GL_LINEAR);
  out.scene_depth = createTexture2D(GL_DEPTH_COMPONENT24, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  out.water_extent = createTexture2D(GL_RG32F, w, h, GL_RG, GL_FLOAT, nullptr);
  glGenFramebuffers(1, &out.water_extent_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, out.water_extent_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out.water_extent, 0);
  const bool extent_complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glGenFramebuffers(1, &out.scene_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, out.scene_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out.scene_colour, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, out.scene_depth, 0);
  const bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glGenVertexArrays(1, &out.vao);
  glGenBuffers(1, &out.vbo);
  glGenBuffers(1, &out.ibo);
  glGenBuffers(1, &out.attribute_vbo);
  glBindVertexArray(out.vao);
  glBindBuffer(GL_ARRAY_BUFFER, out.vbo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, out.ibo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 24, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 24, reinterpret_cast<const void*>(12));
  // Input 2 (the goo's u, v, skin weight) reads attribute_vbo only after an upload that has
  // attributes; otherwise it stays disabled and reads the constant set in drawFluid (zero).
  glBindBuffer(GL_ARRAY_BUFFER, out.attribute_vbo);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 16, nullptr);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glGenVertexArrays(1, &out.empty_vao);
  if (!complete || !extent_complete || glGetError() != GL_NO_ERROR) {
    out.error = "fluid rendering disabled: scene colour/depth framebuffer not supported";
    return;
  }
  out.ready = true;
}

void destroyFluidRenderer(FluidRenderer& r) {
  for (GLuint* t : {&r.scene_colour, &r.scene_depth, &r.water_extent}) {
    if (*t != 0) glDeleteTextures(1, t);
    *t = 0;
  }
  for (GLuint* f : {&r.scene_fbo, &r.water_extent_fbo}) {
    if (*f != 0) glDeleteFramebuffers(1, f);
    *f = 0;
  }
  for (GLuint* b : {&r.vbo, &r.ibo, &r.attribute_vbo}) {
    if (*b != 0) glDeleteBuffers(1, b);
    *b = 0;
  }
  for (GLuint* v : {&r.vao, &r.empty_vao}) {
    if (*v != 0) glDeleteVertexArrays(1, v);
    *v = 0;
  }
  for (GLuint* p : {&r.water_program, &r.water_extent_program, &r.goo_program, &r.blit_program}) {
    if (*p != 0) glDeleteProgram(*p);
    *p = 0;
  }
  r.ready = false;
}

void beginOpaquePass(FluidRenderer& r, glm::vec4 clear_colour) {
  if (!r.ready) return;
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene_fbo);
  glViewport(0, 0, r.desc.width, r.desc.height);
  glClearColor(clear_colour.r, clear_colour.g, clear_colour.b, clear_colour.a);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

bool uploadFluidMesh(FluidRenderer& r, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                     std::span<const std::uint32_t> indices, std::string& error) {
  return uploadFluidMesh(r, positions, normals, indices, {}, error);
}

bool uploadFluidMesh(FluidRenderer& r, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                     std::span<const std::uint32_t> indices, std::span<const glm::vec4> attributes,
                     std::string& error) {
  error.clear();
  r.index_count = 0;
  r.has_attributes = false;
  if (positions.size() != normals.size()) {
    error = "fluid mesh: " + std::to_string(positions.size()) + " positions but " + std::to_string(normals.size()) +
            " normals";
    return false;
  }
  if (!attributes.empty() && attributes.size() != positions.size()) {
    error = "fluid mesh: " + std::to_string(positions.size()) + " positions but " + std::to_string(attributes.size()) +
            " attributes";
    return false;
  }
  for (std::size_t k = 0; k < attributes.size(); ++k) {
    if (!fluid::isFinite(glm::vec3(attributes[k])) || !std::isfinite(attributes[k].w)) {
      error = "fluid mesh: attribute of vertex " + std::to_string(k) + " is not finite";
      return false;
    }
  }
  if (indices.size() % 3 != 0) {
    error = "fluid mesh: index count " + std::to_string(indices.size()) + " is not a multiple of 3";
    return false;
  }
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (indices[k] >= positions.size()) {
      error = "fluid mesh: index " + std::to_string(k) + " = " + std::to_string(indices[k]) + " >= vertex count " +
              std::to_string(positions.size());
      return false;
    }
  }
  for (std::size_t k = 0; k < positions.size(); ++k) {
    if (!fluid::isFinite(positions[k]) || !fluid::isFinite(normals[k])) {
      error = "fluid mesh: vertex " + std::to_string(k) + " is not finite";
      return false;
    }
  }
  if (!r.ready || indices.empty()) return true;
  const std::size_t vbytes = positions.size() * 24, ibytes = indices.size() * 4;
  r.reallocations += ensureCapacity(GL_ARRAY_BUFFER, r.vbo, vbytes, r.vbo_bytes) ? 1u : 0u;
  // Interleave through a mapped range of the (orphaned) buffer: no staging copy on our side.
  auto* dst = static_cast<float*>(glMapBufferRange(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(vbytes),
                                                   GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
  if (dst == nullptr) {
    error = "fluid mesh: glMapBufferRange failed";
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    return false;
  }
  for (std::size_t k = 0; k < positions.size(); ++k) {
    dst[6 * k + 0] = positions[k].x;
    dst[6 * k + 1] = positions[k].y;
    dst[6 * k + 2] = positions[k].z;
    dst[6 * k + 3] = normals[k].x;
    dst[6 * k + 4] = normals[k].y;
    dst[6 * k + 5] = normals[k].z;
  }
  glUnmapBuffer(GL_ARRAY_BUFFER);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(r.vao);  // the element buffer binding belongs to the VAO
  r.reallocations += ensureCapacity(GL_ELEMENT_ARRAY_BUFFER, r.ibo, ibytes, r.ibo_bytes) ? 1u : 0u;
  glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(ibytes), indices.data());
  if (!attributes.empty()) {
    const std::size_t abytes = attributes.size() * sizeof(glm::vec4);
    r.reallocations += ensureCapacity(GL_ARRAY_BUFFER, r.attribute_vbo, abytes, r.attribute_bytes) ? 1u : 0u;
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(abytes), attributes.data());
    glEnableVertexAttribArray(2);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    r.has_attributes = true;
  } else {
    glDisableVertexAttribArray(2);
  }
  glBindVertexArray(0);
  r.index_count = static_cast<std::uint32_t>(indices.size());
  return true;
}

void drawFluid(FluidRenderer& r, GLuint target_fbo, const FluidCamera& camera, const WaterParams& params) {
  if (!r.ready) return;
  glDisable(GL_CULL_FACE);  // both sides: back faces are seen through the fluid or from inside it
  const bool goo = params.style == FluidStyle::goo;
  if (r.index_count > 0) {
    // The fluid's extent along each pixel (water_extent.frag): MAX blending keeps the nearest
    // entry (as its negative) and the farthest surface in front of the scene depth. Water absorbs
    // through it; goo takes its coverage and glow from it.
    glBindFramebuffer(GL_FRAMEBUFFER, r.water_extent_fbo);
    glViewport(0, 0, r.desc.width, r.desc.height);
    const GLfloat no_water[4] = {-1e30f, 0.0f, 0.0f, 0.0f};  // no entry, no far surface
    glClearBufferfv(GL_COLOR, 0, no_water);                  // leaves the caller's clear colour alone
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendEquation(GL_MAX);
    glUseProgram(r.water_extent_program);
    setCamera(r.water_extent_program, camera, r);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r.scene_depth);
    glUniform1i(loc(r.water_extent_program, "u_scene_depth"), 0);
    glBindVertexArray(r.vao);
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.index_count), GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    glBlendEquation(GL_FUNC_ADD);
    glDisable(GL_BLEND);
  }
  // Scene colour into the target.
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glViewport(0, 0, r.desc.width, r.desc.height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glUseProgram(r.blit_program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, r.scene_colour);
  glUniform1i(loc(r.blit_program, "u_colour"), 0);
  glBindVertexArray(r.empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  if (r.index_count > 0) {
    // Blended "over" in the order given (back-to-front from the extractor); the scene depth test
    // is done in the shader (the target may have no depth buffer).
    const GLuint program = goo ? r.goo_program : r.water_program;
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(program);
    setCamera(program, camera, r);
    setShading(program, params);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r.scene_colour);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, r.scene_depth);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, r.water_extent);
    glUniform1i(loc(program, "u_scene_colour"), 0);
    glUniform1i(loc(program, "u_scene_depth"), 1);
    glUniform1i(loc(program, "u_water_extent"), 2);
    if (goo) {
      const bool textured = r.has_attributes && params.goo_texture != 0;
      glActiveTexture(GL_TEXTURE3);
      glBindTexture(GL_TEXTURE_2D, textured ? params.goo_texture : 0);
      glUniform1i(loc(program, "u_goo_texture"), 3);
      glUniform1i(loc(program, "u_goo_textured"), textured ? 1 : 0);
    }
    glBindVertexArray(r.vao);
    if (!r.has_attributes) glVertexAttrib4f(2, 0.0f, 0.0f, 0.0f, 0.0f);  // no skin anywhere
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.index_count), GL_UNSIGNED_INT, nullptr);
    glDisable(GL_BLEND);
    glActiveTexture(GL_TEXTURE0);
  }
  glBindVertexArray(0);
}

OutOfOrder countOutOfOrderPairs(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                glm::vec3 eye) {
  OutOfOrder out;
  std::vector<float> d;
  d.reserve(indices.size() / 3);
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::vec3 c = (positions[indices[t]] + positions[indices[t + 1]] + positions[indices[t + 2]]) / 3.0f;
    d.push_back(glm::length(c - eye));
    if (d.size() > 1 && d.back() > d[d.size() - 2]) ++out.adjacent;
  }
  out.triangles = d.size();
  // Inversions of a sequence that should be non-increasing: pairs i < j with d[j] > d[i].
  std::vector<float> tmp(d.size());
  for (std::size_t width = 1; width < d.size(); width *= 2) {
    for (std::size_t lo = 0; lo < d.size(); lo += 2 * width) {
      const std::size_t mid = std::min(lo + width, d.size()), hi = std::min(lo + 2 * width, d.size());
      std::size_t i = lo, j = mid, o = lo;
      while (i < mid && j < hi) {
        if (d[j] > d[i]) {  // a later, farther triangle passes every remaining earlier one
          out.pairs += mid - i;
          tmp[o++] = d[j++];
        } else {
          tmp[o++] = d[i++];
        }
      }
      while (i < mid) tmp[o++] = d[i++];
      while (j < hi) tmp[o++] = d[j++];
    }
    d.swap(tmp);
  }
  return out;
}

// The mesh as a water backend (water_backend.hpp): the CPU marching-slices surface, blended in its
// emitted order.
namespace {
class MeshWaterBackend final : public WaterBackend {
 public:
  explicit MeshWaterBackend(const FluidRenderDesc& desc) { createFluidRenderer(desc, renderer_); }
  ~MeshWaterBackend() override { destroyFluidRenderer(renderer_); }
  bool ready() const override { return renderer_.ready; }
  const std::string& error() const override { return renderer_.error; }
  GLuint upload(const WaterInput& in, std::string& error) override {
    if (!renderer_.ready) return 0;
    return uploadFluidMesh(renderer_, in.positions, in.normals, in.indices, in.attributes, error) ? renderer_.scene_fbo
                                                                                                 : 0;
  }
  void draw(GLuint target_fbo, const FluidCamera& camera, const WaterParams& water, const WaterInput&) override {
    drawFluid(renderer_, target_fbo, camera, water);
  }

 private:
  FluidRenderer renderer_;
};
}  // namespace

const WaterBackendDesc& meshWaterBackend() {
  static const WaterBackendDesc desc{
      "mesh", "the marching-slices mesh (Rosenberg & Birdwell 2008), blended back-to-front", true,
      [](const FluidRenderDesc& d) -> std::unique_ptr<WaterBackend> { return std::make_unique<MeshWaterBackend>(d); }};
  return desc;
}

}  // namespace engine
