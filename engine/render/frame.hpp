#pragma once
// The engine owns the frame. The game describes what to draw as batches (FrameBatches) and calls
// renderFrame; it never calls GL. Passes, in order, all into the renderer's scene FBO:
//   1. shadow map, opaque meshes, sky    renderScene (renderer.hpp)
//   2. water, one pass per WaterBatch    the opaque colour + depth are copied into the water
//      renderer's own targets (its background), then the water is drawn back into the scene FBO:
//      the marching-slices mesh blended in the order it was emitted (back-to-front) as water or
//      translucent goo, or the particles straight (screen-space splats, ray-cast metaballs)
//      (engine/fluid_render)
//   3. sprites, one pass per system      a few odd-even merge-sort passes for the eye (Kolb 2004
//      §3.3.3), then point sprites depth-tested against the scene, not written
//   4. screen tint                       a full-screen colour blended over it all (when alpha > 0)
// Every pass keeps the scene's alpha at 1 (PNG screenshots would otherwise turn see-through).
// The UI (engine/ui) is drawn over the window after presentToWindow.

#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/water_backend.hpp"
#include "engine/gpu_particles/gpu_particles.hpp"
#include "engine/render/renderer.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace engine {

// One body of water. The spans must stay valid until renderFrame returns.
struct WaterBatch {
  // The water backend that draws it, by its registry name (water_backend.hpp); an unknown name
  // draws nothing (the error printed once).
  std::string_view method = "mesh";
  FluidStyle style = FluidStyle::water;  // mesh: refractive water, or translucent goo
  glm::vec3 goo_colour{0.35f, 0.8f, 0.2f};
  float goo_density = 12.0f;  // goo: extinction per metre of body (WaterParams::goo_density)
  // Goo skin (method mesh, style goo): per vertex (u, v, skin weight, -), empty or one per
  // position (SurfaceMesh::attributes, fluid/blob/tentacle_uv.hpp), and the texture sampled at
  // (u, v) (null, or never uploaded: plain goo). The texture must outlive renderFrame.
  std::span<const glm::vec4> attributes;
  const GpuTexture* goo_texture = nullptr;
  bool visible = true;  // false: not drawn, but its renderer's GL objects are kept for later frames
  // method mesh: the surface, triangles in draw order (back-to-front for blending).
  std::span<const glm::vec3> positions, normals;
  std::span<const std::uint32_t> indices;
  // particle methods (screen_space, raycast, ...): the particle centres.
  std::span<const glm::vec3> particles;
  float rc = 0.1f;         // field cutoff (m): the same field for all three methods
  float threshold = 0.2f;  // iso level of that field (raycast)
  // Particle methods, anisotropic kernels (fluid/sph/anisotropy.hpp; empty: spheres): per particle
  // h G, its largest semi-axis factor and the smoothed kernel centre (WaterInput's kernel_*).
  std::span<const glm::mat3> kernel_g;
  std::span<const float> kernel_max_axis;
  std::span<const glm::vec3> kernel_centres;
  std::string_view ss_filter = "bilateral";  // screen_space's depth filter: bilateral | narrow_range
  float refraction = 0.08f, opacity = 0.85f;
  glm::vec3 absorption = WaterParams{}.absorption;  // Beer–Lambert σ per metre, RGB
};

struct FrameBatches {
  std::vector<DrawItem> opaque;        // pass 1, in draw order
  std::vector<WaterBatch> water;       // pass 2
  std::vector<GpuParticles*> sprites;  // pass 3: ready systems only
  // Pass 4: one colour blended over the whole frame by its alpha (0: no pass), e.g. the screen
  // turning red while the blob holds the player. The strongest submitted tint wins.
  glm::vec4 screen_tint{0.0f};
  void clear() {
    opaque.clear();
    water.clear();
    sprites.clear();
    screen_tint = glm::vec4(0.0f);
  }
};

// The water backend of one water slot: created on first need, recreated when the frame size or the
// method changes. A backend whose shaders failed stays unready: the frame goes on without that
// water (the error printed once).
struct WaterSlot {
  std::unique_ptr<WaterBackend> backend;  // null until first drawn, and after a release
  std::string method;                     // the backend's name
  int width = 0, height = 0;
  WaterStats stats;  // the backend's account of its last frame (zero when it drew nothing)
};

struct FramePasses {
  std::filesystem::path shader_dir;  // fluid/*.vert, *.frag live below it
  std::vector<WaterSlot> water;      // slot i draws FrameBatches::water[i]
};

// Draws the whole frame into renderer.scene_fbo. Needs the GL context current. Water slots
// beyond this frame's batches are released.
void renderFrame(Renderer& renderer, FramePasses& passes, const FrameView& view, const Lighting& lighting,
                 const FrameBatches& batches);

// Frees every water renderer (context current).
void releaseFramePasses(FramePasses& passes);

// What the last renderFrame tells back, per water batch in submission order (zero stats for a
// slot that drew nothing), into the caller's `out` (reused: no allocation once it has grown). The
// game reads it; the engine writes nothing into game state.
void lastWaterStats(const FramePasses& passes, std::vector<WaterStats>& out);

}  // namespace engine
