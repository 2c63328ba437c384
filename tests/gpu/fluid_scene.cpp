#include "tests/gpu/fluid_scene.hpp"

#include "engine/gl/gl.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <fstream>

namespace gputest {

ColourTarget::ColourTarget(int width, int height, GLenum format) {
  texture = engine::createTexture2D(format, width, height, GL_RGBA, format == GL_RGBA8 ? GL_UNSIGNED_BYTE : GL_FLOAT,
                                    nullptr);
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

ColourTarget::~ColourTarget() {
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &texture);
}

bool createFluidScene(FluidScene& s, int width, int height, glm::vec3 eye, std::string& error) {
  s.width = width;
  s.height = height;
  const std::filesystem::path dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders" / "fluid";
  s.backdrop_program =
      engine::buildProgram(std::vector<engine::ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "backdrop.vert"}},
                                                                 {GL_FRAGMENT_SHADER, {dir / "backdrop.frag"}}},
                           "", error);
  if (s.backdrop_program == 0) return false;
  // Wall at x = −1.2 and floor at y = 0 (two quads); the camera looks along −x, across the
  // extractor's default +z sweep, so the unsorted order is really unsorted for it.
  const float v[] = {-1.2f, -1, -4, -1.2f, -1, 4,  -1.2f, 4, 4, -1.2f, -1, -4, -1.2f, 4, 4, -1.2f, 4, -4,
                     -1.2f, 0,  -4, 4,     0,  -4, 4,     0, 4, -1.2f, 0,  -4, 4,     0, 4, -1.2f, 0, 4};
  glGenVertexArrays(1, &s.backdrop_vao);
  glGenBuffers(1, &s.backdrop_vbo);
  glBindVertexArray(s.backdrop_vao);
  glBindBuffer(GL_ARRAY_BUFFER, s.backdrop_vbo);
  glBufferData(GL_ARRAY_BUFFER, sizeof(v), v, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, nullptr);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  // Blob: lattice points (step 0.1) within 0.4 of (0, 0.5, 0), plus a smaller blob behind it
  // so several water layers overlap on screen.
  auto blob = [&](glm::vec3 c, float r) {
    for (int i = -6; i <= 6; ++i)
      for (int j = -6; j <= 6; ++j)
        for (int k = -6; k <= 6; ++k) {
          const glm::vec3 p = c + 0.1f * glm::vec3(i, j, k);
          if (glm::length(p - c) > r) continue;
          s.particles.push_back(p);
        }
  };
  blob({0.0f, 0.5f, 0.0f}, 0.4f);
  blob({-0.5f, 0.45f, 0.35f}, 0.3f);
  s.camera.eye = eye;
  s.camera.near_plane = 0.05f;
  s.camera.far_plane = 20.0f;
  s.camera.view = glm::lookAt(eye, kFluidTarget, glm::vec3(0, 1, 0));
  s.camera.projection = glm::perspective(glm::radians(45.0f), static_cast<float>(width) / static_cast<float>(height),
                                         s.camera.near_plane, s.camera.far_plane);
  return true;
}

void destroyFluidScene(FluidScene& s) {
  if (s.backdrop_program != 0) glDeleteProgram(s.backdrop_program);
  if (s.backdrop_vbo != 0) glDeleteBuffers(1, &s.backdrop_vbo);
  if (s.backdrop_vao != 0) glDeleteVertexArrays(1, &s.backdrop_vao);
  s.backdrop_program = s.backdrop_vbo = s.backdrop_vao = 0;
}

bool extractMesh(FluidScene& s, fluid::SurfaceOrder order, bool exact_slabs, std::string& error) {
  fluid::SurfaceParams p;
  p.rc = 0.2f;
  p.threshold = 0.2f;
  p.cube = 0.04f;
  p.threads = 1;
  p.order = order;
  p.eye = s.camera.eye;
  p.viewDir = kFluidTarget - s.camera.eye;
  p.exactSlabOrder = exact_slabs;
  const fluid::SurfaceStatus st = s.extractor.extract({fluid::pointView(s.particles)}, p, s.mesh);
  error = st.error;
  return st.ok();
}

void drawBackdrop(const FluidScene& s) {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(s.backdrop_program);
  const glm::mat4 vp = s.camera.projection * s.camera.view;
  glUniformMatrix4fv(glGetUniformLocation(s.backdrop_program, "u_view_projection"), 1, GL_FALSE, glm::value_ptr(vp));
  glBindVertexArray(s.backdrop_vao);
  glDrawArrays(GL_TRIANGLES, 0, 12);
  glBindVertexArray(0);
  glDisable(GL_DEPTH_TEST);
}

std::vector<unsigned char> renderFrame(FluidScene& s, engine::FluidRenderer& r, GLuint target_fbo,
                                       const engine::WaterParams& params, bool with_mesh) {
  engine::beginOpaquePass(r, glm::vec4(0.1f, 0.1f, 0.12f, 1.0f));
  drawBackdrop(s);
  std::string error;
  if (with_mesh) {
    engine::uploadFluidMesh(r, s.mesh.positions, s.mesh.normals, s.mesh.indices, error);
  } else {
    engine::uploadFluidMesh(r, {}, {}, {}, error);
  }
  engine::drawFluid(r, target_fbo, s.camera, params);
  std::vector<unsigned char> px(static_cast<std::size_t>(s.width) * static_cast<std::size_t>(s.height) * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glReadPixels(0, 0, s.width, s.height, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return px;
}

bool writePpm(const std::filesystem::path& path, int w, int h, const std::vector<unsigned char>& rgba) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return false;
  out << "P6\n" << w << " " << h << "\n255\n";
  for (int y = h - 1; y >= 0; --y) {  // top row first
    for (int x = 0; x < w; ++x) {
      const std::size_t k =
          (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 4;
      out.write(reinterpret_cast<const char*>(&rgba[k]), 3);
    }
  }
  return static_cast<bool>(out);
}

bool readPpm(const std::filesystem::path& path, int& w, int& h, std::vector<unsigned char>& rgb, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int maxval = 0;
  if (!(in >> magic >> w >> h >> maxval) || magic != "P6" || maxval != 255 || w <= 0 || h <= 0 || w > 4096 ||
      h > 4096) {
    error = path.string() + ": not a binary 8-bit PPM (P6 w h 255)";
    return false;
  }
  in.get();
  rgb.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
  if (!in.read(reinterpret_cast<char*>(rgb.data()), static_cast<std::streamsize>(rgb.size()))) {
    error = path.string() + ": truncated pixel data";
    return false;
  }
  return true;
}

}  // namespace gputest
