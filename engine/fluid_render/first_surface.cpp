#include "engine/fluid_render/first_surface.hpp"

#include "fluid/collide/collide.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace engine {
namespace {

void resetSurface(int width, int height, FirstSurface& out) {
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  out.width = width;
  out.height = height;
  out.hit.assign(pixels, 0);
  out.point.assign(pixels, glm::vec3(0.0f));
  out.normal.assign(pixels, glm::vec3(0.0f));
}

glm::vec2 pixelNdc(int x, int y, int width, int height) {
  return {(static_cast<float>(x) + 0.5f) / static_cast<float>(width) * 2.0f - 1.0f,
          (static_cast<float>(y) + 0.5f) / static_cast<float>(height) * 2.0f - 1.0f};
}

std::vector<float> readFloatTexture(GLuint texture, int width, int height, int channels) {
  std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                            static_cast<std::size_t>(channels));
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  glBindTexture(GL_TEXTURE_2D, texture);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTexImage(GL_TEXTURE_2D, 0, channels == 4 ? GL_RGBA : GL_RED, GL_FLOAT, values.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  return values;
}

template <class T>
std::vector<T> readBuffer(GLuint buffer, std::size_t count) {
  std::vector<T> values(count);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(count * sizeof(T)), values.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  return values;
}

// voxel_common.glsl's decodeNormal: the two snorm16s of its octahedron code are the L1
// parametrization of the colliders' normal index (fluid::l1Decode, Kolb et al. §4.2 eq. (3)) on [-1, 1]².
glm::vec3 decodeOctahedron(std::uint32_t code) {
  auto snorm = [](std::uint32_t bits) {
    const auto v = static_cast<std::int16_t>(static_cast<std::uint16_t>(bits & 0xffffu));
    return std::clamp(static_cast<float>(v) / 32767.0f, -1.0f, 1.0f);
  };
  return fluid::l1Decode(glm::vec2(snorm(code), snorm(code >> 16)) * 0.5f + 0.5f);
}

}  // namespace

void readRaycastFirstSurface(const RaycastRenderer& r, const FluidCamera& camera, FirstSurface& out) {
  const int w = r.desc.base.width, h = r.desc.base.height;
  resetSurface(w, h, out);
  const std::vector<float> hits = readFloatTexture(r.hits, w, h, 4);
  // rc_cast.comp's ray: from the pixel centre's near point towards its far point (ray.glsl pixelRay).
  const glm::mat4 clip_to_world = glm::inverse(camera.projection * camera.view);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      const float distance = hits[4 * i + 3];
      if (!(distance >= 0.0f)) continue;
      const glm::vec2 ndc = pixelNdc(x, y, w, h);
      const glm::vec4 a = clip_to_world * glm::vec4(ndc, -1.0f, 1.0f), b = clip_to_world * glm::vec4(ndc, 1.0f, 1.0f);
      const glm::vec3 dir = glm::normalize(glm::vec3(b) / b.w - glm::vec3(a) / a.w);
      out.hit[i] = 1;
      out.point[i] = camera.eye + distance * dir;
      out.normal[i] = glm::normalize(glm::vec3(hits[4 * i], hits[4 * i + 1], hits[4 * i + 2]));
    }
}

void readVoxelFirstSurface(const VoxelRenderer& r, const FluidCamera& camera, FirstSurface& out) {
  const int w = r.view.width, h = r.view.height;
  resetSurface(w, h, out);
  if (w <= 0 || h <= 0 || r.depth_final == 0) return;
  const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t spans = pixels * static_cast<std::size_t>(r.desc.max_spans);
  const std::vector<glm::uvec4> meta = readBuffer<glm::uvec4>(r.meta, pixels);
  const std::vector<glm::vec2> depths = readBuffer<glm::vec2>(r.depth_final, spans);
  const std::vector<glm::uvec2> normals = readBuffer<glm::uvec2>(r.normals, spans);
  const glm::mat4& p = r.view.projection;
  const glm::mat3 view_to_world = glm::transpose(glm::mat3(r.view.view));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      if (meta[i].x == 0u) continue;
      const std::size_t first = i * static_cast<std::size_t>(r.desc.max_spans);
      // voxel_common.glsl columnRay: the view-space ray whose z is −1, scaled by the span's depth.
      const glm::vec2 ndc = pixelNdc(x, y, w, h);
      const glm::vec3 ray((ndc.x + p[2][0]) / p[0][0], (ndc.y + p[2][1]) / p[1][1], -1.0f);
      out.hit[i] = 1;
      out.point[i] = camera.eye + view_to_world * (depths[first].x * ray);
      out.normal[i] = decodeOctahedron(normals[first].x);
    }
}

void readScreenSpaceFirstSurface(const ScreenSpaceRenderer& r, const FluidCamera& camera, FirstSurface& out) {
  const int w = r.desc.width, h = r.desc.height;
  resetSurface(w, h, out);
  const std::vector<float> z = readFloatTexture(r.smooth_depth[0], w, h, 1);
  constexpr float kEmpty = 1e20f;
  auto depthAt = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= w || y >= h) return kEmpty;
    return z[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)];
  };
  auto viewAt = [&](int x, int y, float d) {
    const glm::vec2 ndc = pixelNdc(x, y, w, h);
    return glm::vec3(ndc.x * d / camera.projection[0][0], ndc.y * d / camera.projection[1][1], -d);
  };
  // ss_composite.frag's tangent: the one-sided difference with the smaller depth jump.
  auto tangent = [&](int x, int y, glm::vec3 centre, int dx, int dy) {
    const float zf = depthAt(x + dx, y + dy), zb = depthAt(x - dx, y - dy);
    if (zf >= kEmpty && zb >= kEmpty) return glm::vec3(static_cast<float>(dx), static_cast<float>(dy), 0.0f);
    const glm::vec3 forward = viewAt(x + dx, y + dy, zf) - centre, backward = centre - viewAt(x - dx, y - dy, zb);
    const bool use_forward = zf < kEmpty && (zb >= kEmpty || std::abs(forward.z) <= std::abs(backward.z));
    return use_forward ? forward : backward;
  };
  const glm::mat3 view_to_world = glm::transpose(glm::mat3(camera.view));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float d = depthAt(x, y);
      if (d >= kEmpty) continue;
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      const glm::vec3 centre = viewAt(x, y, d);
      glm::vec3 n = glm::normalize(glm::cross(tangent(x, y, centre, 1, 0), tangent(x, y, centre, 0, 1)));
      if (glm::dot(n, -centre) < 0.0f) n = -n;
      out.hit[i] = 1;
      out.point[i] = camera.eye + view_to_world * centre;
      out.normal[i] = glm::normalize(view_to_world * n);
    }
}

}  // namespace engine
