#pragma once
// Forward renderer. Every scene pass draws into the scene FBO (colour RGBA8 + depth texture,
// so later passes such as fluid refraction can sample both); the window only receives a blit.
// Passes in order: sun shadow map (depth only) -> lit textured meshes -> sky (full-screen
// triangle behind everything). Water and sprites follow in renderFrame (engine/render/frame.hpp),
// which owns the whole frame.
// Output is display-ready (tone-mapped, gamma-encoded) RGBA8.

#include "engine/assets/assets.hpp"
#include "engine/gl/gl.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace engine {

struct GpuMesh {
  GlVertexArray vao;
  GlBuffer vertices;  // interleaved position, normal, uv
  GlBuffer indices;
  GLsizei index_count = 0;
};

struct GpuTexture {
  GlTexture texture;
  int width = 0;
  int height = 0;
};

GpuMesh uploadMesh(const MeshData& mesh);
// sRGB colour texture with mipmaps and repeat wrapping (image rows top-first, as loaded).
GpuTexture uploadTexture(const ImageData& image);

struct DrawItem {
  const GpuMesh* mesh = nullptr;        // required
  const GpuTexture* texture = nullptr;  // null = white
  glm::mat4 model{1.0f};
  glm::vec3 tint{1.0f};    // multiplies the texture (linear)
  float uv_scale = 1.0f;   // texture repeats
  float specular = 0.15f;  // 0..1
  float shininess = 24.0f;
  bool casts_shadow = true;  // false for the ground (it only receives)
};

struct FrameView {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
  glm::vec3 eye{0.0f};
  float near_plane = 0.05f, far_plane = 400.0f;  // of `projection` (the water passes linearise depth)
};

struct Lighting {
  glm::vec3 sun_direction{0.7f, 0.62f, -0.35f};  // towards the sun, normalised on use
  glm::vec3 sun_colour{2.6f, 2.45f, 2.2f};
  glm::vec3 sky_zenith{0.09f, 0.24f, 0.66f};
  glm::vec3 sky_horizon{0.58f, 0.7f, 0.86f};
  glm::vec3 ground_ambient{0.22f, 0.2f, 0.17f};
  float fog_density = 0.008f;  // 1/m
  // Directional shadow map: an orthographic box of 2*shadow_extent metres around a point ahead
  // of the camera, snapped to whole texels so shadows do not shimmer as the camera moves.
  float shadow_extent = 16.0f;  // m; 0 disables shadows
  // A point light for an explosion's flash: radiance falls off as 1 / (1 + d^2) with the distance
  // d in metres; a zero colour is no flash.
  glm::vec3 flash_position{0.0f};
  glm::vec3 flash_colour{0.0f};
};

struct Renderer {
  std::filesystem::path shader_dir;
  GlProgram sky_program;
  GlProgram mesh_program;
  GlProgram shadow_program;
  GlProgram tint_program;  // the screen tint (FrameBatches::screen_tint)
  GlFramebuffer shadow_fbo;
  GlTexture shadow_depth;   // depth texture compared in the mesh shader (sampler2DShadow)
  int shadow_size = 2048;   // texels per side
  GlVertexArray empty_vao;  // core profile needs a VAO for attribute-less draws
  GpuTexture white;
  GlFramebuffer scene_fbo;
  GlTexture scene_colour;
  GlTexture scene_depth;
  int width = 0;
  int height = 0;
  GlErrorLog errors;
};

// Loads the shaders from `shader_dir` and creates the scene FBO and the shadow map
// (`shadow_size` texels per side, clamped to [256, 8192]). On failure returns false
// with an error naming the shader file and line, or the incomplete framebuffer.
bool createRenderer(const std::filesystem::path& shader_dir, int width, int height, Renderer& out, std::string& error,
                    int shadow_size = 2048);
bool resizeRenderer(Renderer& renderer, int width, int height, std::string& error);

// Clears the scene FBO and, when `draw_content` is true, draws meshes and sky.
// `draw_content = false` gives the "nothing drawn" frame the smoke test compares against.
void renderScene(Renderer& renderer, const FrameView& view, const Lighting& lighting, std::span<const DrawItem> items,
                 bool draw_content);

// Copies the scene FBO to the default framebuffer of size window_w x window_h.
void presentToWindow(Renderer& renderer, int window_width, int window_height);

// Reads the scene FBO: RGBA8, bottom row first, width*height*4 bytes.
void readSceneRgba(Renderer& renderer, std::vector<std::uint8_t>& out);

}  // namespace engine
