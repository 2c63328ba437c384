#pragma once
// Fluid surface rendering: the marching-slices mesh (fluid/surface) drawn over an opaque scene,
// blended in the order the extractor emitted (back-to-front), as transparent water (refraction,
// Beer–Lambert absorption, Fresnel sky reflection, a specular highlight) or as translucent goo
// (a subsurface look: wrapped diffuse, coverage and glow from the thickness through the body,
// optionally textured by per-vertex (u, v) where the vertex's tentacle share says so).
//
// Frame: beginOpaquePass() → caller draws the opaque scene into colour + depth textures →
// uploadFluidMesh() → drawFluid() into the caller's framebuffer. All calls need the creating
// GL context current. A renderer whose shaders failed is `ready == false`; its calls are
// no-ops and drawFluid() leaves the target untouched (the game runs on without the effect).

#include <GL/gl.h>
#include <GL/glext.h>
#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace engine {

struct FluidRenderDesc {
  int width = 256, height = 256;     // scene targets, px (1..8192)
  std::filesystem::path shader_dir;  // folder holding fluid/*.vert, *.frag
};

enum class FluidStyle { water, goo };

struct FluidCamera {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};  // perspective; near/far below must match it
  glm::vec3 eye{0.0f};
  float near_plane = 0.05f, far_plane = 100.0f;
};

struct WaterParams {
  FluidStyle style = FluidStyle::water;
  // Beer–Lambert σ per metre, RGB (transmit exp(−σ·d)): the water of every scene unless it says
  // otherwise (fluid_surface.absorption defaults to it; reds go first, a deep pool turns blue-green).
  glm::vec3 absorption{1.6f, 0.45f, 0.25f};
  float refraction = 0.08f;                  // screen-uv offset per metre of thickness along the refracted ray
  float ior = 1.33f;                         // index of refraction (water 1.33)
  float opacity = 0.85f;                     // blend alpha of one water layer (Fresnel raises it to 1)
  glm::vec3 sky_zenith{0.25f, 0.45f, 0.85f};
  glm::vec3 sky_horizon{0.85f, 0.9f, 0.95f};
  glm::vec3 light_direction{0.3f, 1.0f, 0.4f};  // towards the light, world (normalised inside)
  float shininess = 96.0f;
  // An explosion's flash (engine::Lighting's point light): its position and radiance at 1 m;
  // zero colour = none.
  glm::vec3 flash_position{0.0f};
  glm::vec3 flash_colour{0.0f};
  glm::vec3 goo_colour{0.35f, 0.8f, 0.2f};
  // Goo: extinction per metre of body along the pixel's ray (coverage 1 − exp(−density·d), at
  // least `opacity`'s floor below), clamped 0..1000.
  float goo_density = 12.0f;
  float goo_min_coverage = 0.35f;  // thin edges never fade out entirely (0..1)
  // Goo skin, a texture sampled at the mesh's per-vertex (u, v) (the attributes given to
  // uploadFluidMesh: x = u around, y = v along, z = weight of the skin over goo_colour); 0 or no
  // attributes uploaded = plain goo. The renderer only samples it (the caller owns it).
  GLuint goo_texture = 0;
};

struct FluidRenderer {
  bool ready = false;
  std::string error;
  FluidRenderDesc desc;
  GLuint scene_fbo = 0, scene_colour = 0, scene_depth = 0;  // opaque pass: RGBA8 + DEPTH24
  // Water only: per pixel, -(nearest entry) and the farthest water surface in front of the
  // scene, metres (RG32F), from which each fragment's water thickness is taken.
  GLuint water_extent_fbo = 0, water_extent = 0;
  GLuint vao = 0, vbo = 0, ibo = 0, attribute_vbo = 0, empty_vao = 0;
  std::size_t vbo_bytes = 0, ibo_bytes = 0, attribute_bytes = 0;  // buffer capacities
  bool has_attributes = false;  // the last upload carried per-vertex attributes (vertex input 2)
  std::uint32_t index_count = 0;
  std::uint32_t reallocations = 0;  // capacity growths so far (geometric: ×1.5 + what is needed)
  GLuint water_program = 0, water_extent_program = 0, goo_program = 0, blit_program = 0;
};

void createFluidRenderer(const FluidRenderDesc& desc, FluidRenderer& out);
void destroyFluidRenderer(FluidRenderer& renderer);

// Binds the scene framebuffer (viewport = desc size) and clears colour and depth.
void beginOpaquePass(FluidRenderer& renderer, glm::vec4 clear_colour);

// Uploads one frame's mesh (positions, unit normals, triangles in draw order). Buffers are
// orphaned and refilled each frame, and grow geometrically, so sizes that vary frame to frame
// cause no reallocation churn. False + error (nothing uploaded, previous mesh dropped) when the
// sizes differ, an index is out of range, or a position/normal is not finite. Empty = no fluid.
// `attributes` (optional: empty, or one per vertex, finite) is the goo's (u, v, skin weight, −):
// fluid/surface's SurfaceMesh::attributes, e.g. from fluid/blob/tentacle_uv.hpp.
bool uploadFluidMesh(FluidRenderer& renderer, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                     std::span<const std::uint32_t> indices, std::span<const glm::vec4> attributes, std::string& error);
bool uploadFluidMesh(FluidRenderer& renderer, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                     std::span<const std::uint32_t> indices, std::string& error);

// Copies the scene colour into `target_fbo` (0 = default framebuffer, viewport = desc size)
// and draws the uploaded mesh blended in index order, fragments behind the scene depth
// discarded. A first pass of the mesh records, per pixel, the nearest entry and farthest surface
// in front of the scene: water absorbs through that extent (not up to the scene behind), goo
// takes its coverage and glow from it.
void drawFluid(FluidRenderer& renderer, GLuint target_fbo, const FluidCamera& camera, const WaterParams& params);

// Triangle pairs (s, t), s drawn before t, where t's centroid is farther from `eye` than s's:
// the pairs out of back-to-front order (the inversion count of the centroid distances, by merge
// sort, O(n log n)). `adjacent` gets the same count over consecutive pairs only. Triangles of
// `indices` are consecutive triples (each index < positions.size()).
struct OutOfOrder {
  std::uint64_t pairs = 0, adjacent = 0, triangles = 0;
};
OutOfOrder countOutOfOrderPairs(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                glm::vec3 eye);

}  // namespace engine
