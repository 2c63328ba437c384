#pragma once
// The ways to draw the water, each a backend behind one small interface (Dear ImGui's renderer
// backends are the model): created for a frame size, handed the frame's water (upload), drawn into
// the scene (draw), destroyed with the object. engine/render/frame.cpp keeps one per water batch,
// made by name from the registry and made again when the size or the method changes; the game's
// `fluid_surface.method` choices are the registry's names. A new renderer is one file (its
// backend class and a function returning its WaterBackendDesc) and its line in water_backends.cpp.

#include "engine/fluid_render/fluid_render.hpp"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace engine {

// This frame's water as a backend reads it. The spans stay valid until the draw returns.
struct WaterInput {
  // A mesh backend: the surface, triangles in draw order (back-to-front for blending), and the goo
  // skin's per-vertex (u, v, weight, -) (empty, or one per position).
  std::span<const glm::vec3> positions, normals;
  std::span<const std::uint32_t> indices;
  std::span<const glm::vec4> attributes;
  // A particle backend: the centres, and the field the mesh is extracted from (the same surface
  // whatever the method): cutoff radius Rc (m) and iso level T.
  std::span<const glm::vec3> particles;
  float rc = 0.1f;
  float threshold = 0.2f;
  // Anisotropic kernels (fluid/sph/anisotropy.hpp; empty: spheres at `particles`), one per particle:
  // h G (symmetric, positive definite), its largest semi-axis factor and the smoothed centre x̄.
  // A backend that draws particles draws { x : |g (x - x̄)| <= ρ } where it drew the sphere of ρ.
  std::span<const glm::mat3> kernel_g;
  std::span<const float> kernel_max_axis;
  std::span<const glm::vec3> kernel_centres;
  std::string_view ss_filter = "bilateral";  // screen_space's depth filter: bilateral | narrow_range
};

// What a backend tells about its last frame; zero where it has nothing to tell. The ray caster's
// fragment lists (Szecsi & Illes 2012): records asked for, dropped for a full pool, the pool's size
// and the most it may grow to (records of 16 bytes).
struct WaterStats {
  std::uint64_t records = 0, dropped = 0, pool = 0, pool_bound = 0;
};

class WaterBackend {
 public:
  virtual ~WaterBackend() = default;  // frees its GL objects (the context current)
  // False when its shaders or targets failed; error() says why and the frame goes on without it.
  virtual bool ready() const = 0;
  virtual const std::string& error() const = 0;
  // Takes the frame's water; returns the FBO whose colour + depth targets must hold the opaque scene
  // (the water's background) before draw, or 0 when the input was refused (error set).
  virtual GLuint upload(const WaterInput& input, std::string& error) = 0;
  // Draws the water into `target_fbo` (the renderer's scene FBO), its background already copied.
  virtual void draw(GLuint target_fbo, const FluidCamera& camera, const WaterParams& water,
                    const WaterInput& input) = 0;
  virtual WaterStats stats() const { return {}; }
};

struct WaterBackendDesc {
  std::string_view name;  // the scene key's value: "mesh", "screen_space", ...
  std::string_view doc;
  bool needs_mesh = false;  // draws the CPU marching-slices mesh (the game meshes only for these)
  std::unique_ptr<WaterBackend> (*create)(const FluidRenderDesc& desc);
};

// Every backend, in the overlay's order (water_backends.cpp).
std::span<const WaterBackendDesc* const> waterBackends();
const WaterBackendDesc* findWaterBackend(std::string_view name);
// Their names, for a scene key's choices (lives as long as the program).
std::span<const std::string_view> waterBackendNames();

}  // namespace engine
