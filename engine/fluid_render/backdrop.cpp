// The static scene `fluiddemo render` draws a particle set over (backdrop.hpp).
#include "engine/fluid_render/backdrop.hpp"

#include "engine/gl/gl.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <vector>

namespace engine {

// A wall behind the set (seen from the camera) and a floor under it, striped, as the tests' scene.
bool createBackdrop(const std::filesystem::path& shaders, glm::vec3 lo, glm::vec3 hi, float radius, glm::vec3 eye,
                    Backdrop& b, std::string& error) {
  const std::filesystem::path dir = shaders / "fluid";
  b.program = buildProgram(std::vector<engine::ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "backdrop.vert"}},
                                                                         {GL_FRAGMENT_SHADER, {dir / "backdrop.frag"}}},
                                   "", error);
  if (b.program == 0) return false;
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float size = 4.0f * std::max(glm::length(hi - lo), 1.0f);
  const float floor_y = std::min(lo.y, 0.0f) - 3.0f * radius;  // below the lowest sphere: every method sees the bottom
  // The wall behind the set at constant x (backdrop.frag stripes it along z), on the far side
  // from the eye.
  const float wall = eye.x > centre.x ? lo.x - 0.5f : hi.x + 0.5f;
  auto wallPoint = [&](float u, float y) { return glm::vec3(wall, y, centre.z + u); };
  const float top = floor_y + size;
  const glm::vec3 w[6] = {wallPoint(-size, floor_y), wallPoint(size, floor_y), wallPoint(size, top),
                          wallPoint(-size, floor_y), wallPoint(size, top),     wallPoint(-size, top)};
  const glm::vec3 f[6] = {{centre.x - size, floor_y, centre.z - size}, {centre.x + size, floor_y, centre.z - size},
                          {centre.x + size, floor_y, centre.z + size}, {centre.x - size, floor_y, centre.z - size},
                          {centre.x + size, floor_y, centre.z + size}, {centre.x - size, floor_y, centre.z + size}};
  std::vector<glm::vec3> v(w, w + 6);
  v.insert(v.end(), f, f + 6);
  glGenVertexArrays(1, &b.vao);
  glGenBuffers(1, &b.vbo);
  glBindVertexArray(b.vao);
  glBindBuffer(GL_ARRAY_BUFFER, b.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(glm::vec3)), v.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, nullptr);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  return true;
}

void destroyBackdrop(Backdrop& b) {
  if (b.program != 0) glDeleteProgram(b.program);
  if (b.vbo != 0) glDeleteBuffers(1, &b.vbo);
  if (b.vao != 0) glDeleteVertexArrays(1, &b.vao);
  b = Backdrop{};
}

// Clears `fbo` to the sky's horizon colour and draws the backdrop with depth.
void drawBackdrop(const Backdrop& b, GLuint fbo, const FluidCamera& camera, int w, int h, glm::vec3 sky) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, w, h);
  glClearColor(sky.r, sky.g, sky.b, 1.0f);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(b.program);
  const glm::mat4 vp = camera.projection * camera.view;
  glUniformMatrix4fv(glGetUniformLocation(b.program, "u_view_projection"), 1, GL_FALSE, glm::value_ptr(vp));
  glBindVertexArray(b.vao);
  glDrawArrays(GL_TRIANGLES, 0, 12);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
}

void createColourTarget(int width, int height, ColourTarget& out) {
  out.width = width;
  out.height = height;
  out.colour = createTexture2D(GL_RGBA8, width, height, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &out.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, out.fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out.colour, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void readColourTarget(const ColourTarget& target, std::vector<std::uint8_t>& rgba) {
  rgba.resize(static_cast<std::size_t>(target.width) * static_cast<std::size_t>(target.height) * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, target.fbo);
  glReadPixels(0, 0, target.width, target.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void destroyColourTarget(ColourTarget& target) {
  if (target.fbo != 0) glDeleteFramebuffers(1, &target.fbo);
  if (target.colour != 0) glDeleteTextures(1, &target.colour);
  target = ColourTarget{};
}

void finishGpu() { glFinish(); }

}  // namespace engine
