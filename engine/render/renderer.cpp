#include "engine/render/renderer.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>

namespace engine {
namespace {

struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;
};

GLuint genBuffer() {
  GLuint id = 0;
  glGenBuffers(1, &id);
  return id;
}

GLuint genVertexArray() {
  GLuint id = 0;
  glGenVertexArrays(1, &id);
  return id;
}

GLuint genTexture() {
  GLuint id = 0;
  glGenTextures(1, &id);
  return id;
}

bool createTargets(Renderer& r, int width, int height, std::string& error) {
  r.scene_fbo.reset();
  r.scene_colour.reset();
  r.scene_depth.reset();
  r.width = std::max(width, 1);
  r.height = std::max(height, 1);
  r.scene_colour =
      GlTexture(createTexture2D(GL_RGBA8, r.width, r.height, GL_RGBA, GL_UNSIGNED_BYTE, nullptr, GL_LINEAR));
  r.scene_depth =
      GlTexture(createTexture2D(GL_DEPTH_COMPONENT24, r.width, r.height, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr));
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  r.scene_fbo = GlFramebuffer(fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, r.scene_colour.id(), 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, r.scene_depth.id(), 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "scene framebuffer " + std::to_string(r.width) + "x" + std::to_string(r.height) +
            " is incomplete (status 0x" + std::to_string(status) + ")";
    return false;
  }
  checkGl(r.errors, "creating the scene framebuffer");
  return true;
}

}  // namespace

GpuMesh uploadMesh(const MeshData& mesh) {
  GpuMesh out;
  std::vector<Vertex> vertices(mesh.positions.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    vertices[i] = {mesh.positions[i], i < mesh.normals.size() ? mesh.normals[i] : glm::vec3(0, 1, 0),
                   i < mesh.uvs.size() ? mesh.uvs[i] : glm::vec2(0.0f)};
  }
  out.vao = GlVertexArray(genVertexArray());
  out.vertices = GlBuffer(genBuffer());
  out.indices = GlBuffer(genBuffer());
  glBindVertexArray(out.vao.id());
  glBindBuffer(GL_ARRAY_BUFFER, out.vertices.id());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)), vertices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, out.indices.id());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint32_t)),
               mesh.indices.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, uv)));
  glBindVertexArray(0);
  out.index_count = static_cast<GLsizei>(mesh.indices.size());
  return out;
}

GpuTexture uploadTexture(const ImageData& image) {
  GpuTexture out;
  out.texture = GlTexture(genTexture());
  out.width = image.width;
  out.height = image.height;
  glBindTexture(GL_TEXTURE_2D, out.texture.id());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
               image.rgba.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  glBindTexture(GL_TEXTURE_2D, 0);
  return out;
}

namespace {

bool createShadowMap(Renderer& r, int size, std::string& error) {
  r.shadow_size = std::clamp(size, 256, 8192);
  r.shadow_depth = GlTexture(createTexture2D(GL_DEPTH_COMPONENT24, r.shadow_size, r.shadow_size, GL_DEPTH_COMPONENT,
                                             GL_UNSIGNED_INT, nullptr, GL_LINEAR));
  // Hardware depth comparison: sampler2DShadow lookups return the filtered lit fraction.
  glBindTexture(GL_TEXTURE_2D, r.shadow_depth.id());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glBindTexture(GL_TEXTURE_2D, 0);
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  r.shadow_fbo = GlFramebuffer(fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, r.shadow_depth.id(), 0);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "shadow map framebuffer is incomplete (status " + std::to_string(status) + ")";
    return false;
  }
  return true;
}

// Orthographic sun camera around a point ahead of the eye, snapped to the texel grid.
glm::mat4 sunViewProjection(const FrameView& view, glm::vec3 sun, float extent, int size) {
  const glm::mat4 camera_to_world = glm::inverse(view.view);
  glm::vec3 forward = -glm::vec3(camera_to_world[2]);
  forward.y = 0.0f;
  forward = glm::length(forward) > 1e-4f ? glm::normalize(forward) : glm::vec3(0, 0, -1);
  glm::vec3 focus = view.eye + forward * (0.6f * extent);
  focus.y = 0.0f;
  const glm::vec3 up = std::abs(sun.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  glm::mat4 light_view = glm::lookAt(focus + sun * (2.0f * extent), focus, up);
  // Snap the focus to whole texels in light space.
  const float texel = 2.0f * extent / static_cast<float>(size);
  const glm::vec4 origin = light_view * glm::vec4(focus, 1.0f);
  const glm::vec2 snapped = glm::floor(glm::vec2(origin) / texel) * texel;
  light_view = glm::translate(glm::mat4(1.0f), glm::vec3(snapped - glm::vec2(origin), 0.0f)) * light_view;
  const glm::mat4 projection = glm::ortho(-extent, extent, -extent, extent, 0.1f, 4.0f * extent);
  return projection * light_view;
}

}  // namespace

bool createRenderer(const std::filesystem::path& shader_dir, int width, int height, Renderer& out, std::string& error,
                    int shadow_size) {
  out.shader_dir = shader_dir;
  out.sky_program = loadProgram(shader_dir, "sky.vert", "sky.frag", error);
  if (!out.sky_program) return false;
  out.mesh_program = loadProgram(shader_dir, "mesh.vert", "mesh.frag", error);
  if (!out.mesh_program) return false;
  out.shadow_program = loadProgram(shader_dir, "shadow.vert", "shadow.frag", error);
  if (!out.shadow_program) return false;
  out.tint_program = loadProgram(shader_dir, "tint.vert", "tint.frag", error);
  if (!out.tint_program) return false;
  if (!createShadowMap(out, shadow_size, error)) return false;
  out.empty_vao = GlVertexArray(genVertexArray());
  ImageData white;
  white.width = white.height = 1;
  white.rgba = {255, 255, 255, 255};
  out.white = uploadTexture(white);
  if (!createTargets(out, width, height, error)) return false;
  checkGl(out.errors, "creating the renderer");
  return true;
}

bool resizeRenderer(Renderer& renderer, int width, int height, std::string& error) {
  if (width == renderer.width && height == renderer.height) return true;
  return createTargets(renderer, width, height, error);
}

void renderScene(Renderer& r, const FrameView& view, const Lighting& lighting, std::span<const DrawItem> items,
                 bool draw_content) {
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene_fbo.id());
  glViewport(0, 0, r.width, r.height);
  glDepthMask(GL_TRUE);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (!draw_content) {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    checkGl(r.errors, "clearing the scene");
    return;
  }
  const glm::mat4 view_projection = view.projection * view.view;
  const glm::vec3 sun = glm::normalize(lighting.sun_direction);

  // Sun shadow map: depth of every mesh seen from the sun.
  const bool shadows = lighting.shadow_extent > 0.0f;
  const glm::mat4 light_view_projection =
      shadows ? sunViewProjection(view, sun, lighting.shadow_extent, r.shadow_size) : glm::mat4(1.0f);
  glBindFramebuffer(GL_FRAMEBUFFER, r.shadow_fbo.id());
  glViewport(0, 0, r.shadow_size, r.shadow_size);
  glClear(GL_DEPTH_BUFFER_BIT);
  if (shadows) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 2.0f);
    const GLuint shadow = r.shadow_program.id();
    glUseProgram(shadow);
    setUniform(shadow, "u_light_view_projection", light_view_projection);
    for (const DrawItem& item : items) {
      if (item.mesh == nullptr || item.mesh->index_count == 0 || !item.casts_shadow) continue;
      setUniform(shadow, "u_model", item.model);
      glBindVertexArray(item.mesh->vao.id());
      glDrawElements(GL_TRIANGLES, item.mesh->index_count, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
  }
  checkGl(r.errors, "shadow pass");
  glBindFramebuffer(GL_FRAMEBUFFER, r.scene_fbo.id());
  glViewport(0, 0, r.width, r.height);

  // Opaque lit meshes.
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  const GLuint mesh = r.mesh_program.id();
  glUseProgram(mesh);
  setUniform(mesh, "u_view_projection", view_projection);
  setUniform(mesh, "u_eye", view.eye);
  setUniform(mesh, "u_sun_direction", sun);
  setUniform(mesh, "u_sun_colour", lighting.sun_colour);
  setUniform(mesh, "u_sky_zenith", lighting.sky_zenith);
  setUniform(mesh, "u_sky_horizon", lighting.sky_horizon);
  setUniform(mesh, "u_ground_ambient", lighting.ground_ambient);
  setUniform(mesh, "u_fog_density", lighting.fog_density);
  setUniform(mesh, "u_flash_position", lighting.flash_position);
  setUniform(mesh, "u_flash_colour", lighting.flash_colour);
  setUniform(mesh, "u_albedo", 0);
  setUniform(mesh, "u_shadow_map", 1);
  setUniform(mesh, "u_shadow_texel", 1.0f / static_cast<float>(r.shadow_size));
  setUniform(mesh, "u_light_view_projection", light_view_projection);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, r.shadow_depth.id());
  glActiveTexture(GL_TEXTURE0);
  for (const DrawItem& item : items) {
    if (item.mesh == nullptr || item.mesh->index_count == 0) continue;
    setUniform(mesh, "u_model", item.model);
    setUniform(mesh, "u_normal_matrix", glm::mat4(glm::transpose(glm::inverse(glm::mat3(item.model)))));
    setUniform(mesh, "u_tint", item.tint);
    setUniform(mesh, "u_uv_scale", item.uv_scale);
    setUniform(mesh, "u_specular", item.specular);
    setUniform(mesh, "u_shininess", item.shininess);
    glBindTexture(GL_TEXTURE_2D, item.texture != nullptr ? item.texture->texture.id() : r.white.texture.id());
    glBindVertexArray(item.mesh->vao.id());
    glDrawElements(GL_TRIANGLES, item.mesh->index_count, GL_UNSIGNED_INT, nullptr);
  }
  glDisable(GL_CULL_FACE);
  checkGl(r.errors, "mesh pass");


  // Sky last: a full-screen triangle at the far plane, depth-tested with LEQUAL so it only
  // shades the pixels nothing else covered (no overdraw under the ground).
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  const GLuint sky = r.sky_program.id();
  glUseProgram(sky);
  setUniform(sky, "u_inverse_view_projection", glm::inverse(view_projection));
  setUniform(sky, "u_eye", view.eye);
  setUniform(sky, "u_sun_direction", sun);
  setUniform(sky, "u_sun_colour", lighting.sun_colour);
  setUniform(sky, "u_sky_zenith", lighting.sky_zenith);
  setUniform(sky, "u_sky_horizon", lighting.sky_horizon);
  setUniform(sky, "u_ground_ambient", lighting.ground_ambient);
  glBindVertexArray(r.empty_vao.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  checkGl(r.errors, "sky pass");

  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glBindVertexArray(0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void presentToWindow(Renderer& r, int window_width, int window_height) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.scene_fbo.id());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, r.width, r.height, 0, 0, window_width, window_height, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl(r.errors, "blit to window");
}

void readSceneRgba(Renderer& r, std::vector<std::uint8_t>& out) {
  out.resize(static_cast<std::size_t>(r.width) * r.height * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.scene_fbo.id());
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, r.width, r.height, GL_RGBA, GL_UNSIGNED_BYTE, out.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl(r.errors, "reading the scene back");
}

}  // namespace engine
