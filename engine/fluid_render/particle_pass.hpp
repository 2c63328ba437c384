#pragma once
// Shared pieces of the two particle-direct fluid renderers (screen_space.hpp, raycast.hpp): the
// opaque scene targets they read for refraction, the particle position buffer, and the list of
// GL names each renderer owns (so tests can check that destroy frees all of them).

#include "engine/fluid_render/fluid_render.hpp"
#include "engine/gl/gl.hpp"

#include <GL/gl.h>
#include <GL/glext.h>
#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace engine {

// Which renderer draws the fluid: the marching-slices mesh (fluid_render.hpp), screen-space
// splats (screen_space.hpp, Janisz §3.1 after van der Laan et al. 2009) or metaball ray casting
// over per-pixel fragment lists (raycast.hpp, Szécsi & Illés 2012).
enum class FluidMethod { mesh, screen_space, raycast };

// "mesh", "screen_space", "raycast".
const char* fluidMethodName(FluidMethod method);
// False for any other text.
bool parseFluidMethod(std::string_view text, FluidMethod& out);

// Every GL object name a renderer created, by kind (its own bookkeeping; names stay listed
// after destroy so a test can ask the driver whether they are gone).
struct GlObjectNames {
  std::vector<GLuint> buffers, textures, framebuffers, vertex_arrays, programs;
  std::size_t size() const {
    return buffers.size() + textures.size() + framebuffers.size() + vertex_arrays.size() + programs.size();
  }
};
// How many of `names` the current context still knows (glIsBuffer/glIsTexture/... true).
std::size_t countLiveGlObjects(const GlObjectNames& names);

// Opaque scene colour (RGBA8, linear filter) + depth (DEPTH24) and their framebuffer: the
// caller draws or blits the opaque scene here before drawing the fluid.
struct SceneTargets {
  GLuint fbo = 0, colour = 0, depth = 0;
};
bool createSceneTargets(int width, int height, SceneTargets& out);
void destroySceneTargets(SceneTargets& targets);
void listNames(const SceneTargets& targets, GlObjectNames& out);

// Particle centres as vec4 (xyz, w unused) in one buffer used both as an instanced vertex
// attribute and as a shader storage buffer. Grows geometrically (×1.5), orphaned every upload.
struct ParticleBuffer {
  GLuint buffer = 0;
  std::size_t capacity_bytes = 0;
  std::uint32_t count = 0;
};
// Creates the buffer and `vao`, which feeds it to attribute 0 as one vec4 per instance.
void createParticleBuffer(ParticleBuffer& buffer, GLuint& vao);
// False + error naming the particle (nothing uploaded, count 0) when a position is not finite.
bool uploadParticles(ParticleBuffer& buffer, std::span<const glm::vec3> positions, std::string& error);

// Per-particle kernel shapes for anisotropic kernels (fluid/sph/anisotropy.hpp): g's three columns
// as vec4 (the first's w = the largest semi-axis factor), 48 bytes per particle, in one buffer used
// as instanced attributes 1-3 and as a shader storage buffer. Grows like ParticleBuffer.
struct ShapeBuffer {
  GLuint buffer = 0;
  std::size_t capacity_bytes = 0;
  std::uint32_t count = 0;
};
// Creates the buffer and `vao`, which feeds `particles` to attribute 0 and the shapes to 1-3.
void createShapeBuffer(const ParticleBuffer& particles, ShapeBuffer& shapes, GLuint& vao);
// False + error (nothing uploaded, count 0) when a value is not finite, an axis is not positive
// or the sizes differ.
bool uploadShapes(ShapeBuffer& shapes, std::span<const glm::mat3> g, std::span<const float> max_axis,
                  std::string& error);
// The ellipsoid particles of screen_space and raycast: the smoothed centres and their shapes, one
// per centre. On any error both counts are 0 and `error` names it.
bool uploadEllipsoids(ParticleBuffer& particles, ShapeBuffer& shapes, std::span<const glm::vec3> centres,
                      std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error);

// Builds a program of GLSL 3.30 plus the extensions the fragment lists need (SSBOs, image
// load/store, binding layouts, and compute shaders when `compute`), all of which GL 4.3+ (and
// llvmpipe's 4.5 core) provide. `defines`: more prelude lines (e.g. "#define ELLIPSOID 1").
GLuint buildProgramWithStorage(std::span<const ShaderStageFiles> stages, bool compute, std::string& error,
                               std::string_view defines = "");

// Sets u_view, u_projection, u_inv_view_projection, u_eye, u_near_far, u_viewport.
void setParticleCamera(GLuint program, const FluidCamera& camera, int width, int height);
// Sets the shading.glsl / water_shade.glsl uniforms from `params` (the mesh's water look).
void setWaterShading(GLuint program, const WaterParams& params);

}  // namespace engine
