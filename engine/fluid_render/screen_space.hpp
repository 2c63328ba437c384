#pragma once
// Screen-space fluid rendering (Janisz thesis §3.1, after van der Laan, Green & Sainz 2009): the
// particles drawn directly, no mesh. Passes: nearest sphere per pixel as linear depth (exact
// ray-sphere hits on camera-facing billboards), `smoothing_iterations` rounds of a separable
// bilateral filter on that depth, additive sphere thickness, then one full-screen pass that
// rebuilds normals from the smoothed depth and shades with the mesh's water look
// (shaders/fluid/water_shade.glsl: refraction, Beer–Lambert absorption, Fresnel sky, highlight).
//
// Frame: beginScreenSpaceOpaquePass() (or blit into `scene.fbo`) → caller draws the opaque scene
// → uploadScreenSpaceParticles() → drawScreenSpaceFluid(). Needs the creating context current.
// A renderer whose shaders failed is `ready == false` and its calls do nothing.

#include "engine/fluid_render/particle_pass.hpp"

namespace engine {

struct ScreenSpaceParams {
  float radius = 0.05f;          // sphere radius of one particle, metres (> 0)
  int smoothing_iterations = 3;  // bilateral rounds (each horizontal + vertical), 0..32
  float filter_radius = 0.1f;    // bilateral half-width, metres (projected per pixel, 1..24 px)
  float depth_falloff = 0.05f;   // bilateral range sigma, metres
};

struct ScreenSpaceRenderer {
  bool ready = false;
  std::string error;
  FluidRenderDesc desc;
  SceneTargets scene;
  GLuint depth_fbo = 0, depth_buffer = 0;                   // pass 1: R32F linear depth + its own DEPTH24 z-buffer
  GLuint smooth_fbo[2] = {0, 0}, smooth_depth[2] = {0, 0};  // ping-pong R32F; [0] is pass 1's target
  GLuint thickness_fbo = 0, thickness = 0;                  // R32F, additive
  GLuint vao = 0, empty_vao = 0;
  ParticleBuffer particles;
  GLuint depth_program = 0, thickness_program = 0, smooth_program = 0, composite_program = 0, blit_program = 0;
};

void createScreenSpaceRenderer(const FluidRenderDesc& desc, ScreenSpaceRenderer& out);
void destroyScreenSpaceRenderer(ScreenSpaceRenderer& renderer);
// Every GL name the renderer holds (empty when nothing was created).
GlObjectNames glNames(const ScreenSpaceRenderer& renderer);

void beginScreenSpaceOpaquePass(ScreenSpaceRenderer& renderer, glm::vec4 clear_colour);
// False + error (nothing uploaded) when a position is not finite. Empty = no fluid.
bool uploadScreenSpaceParticles(ScreenSpaceRenderer& renderer, std::span<const glm::vec3> positions,
                                std::string& error);
// Copies the scene colour into `target_fbo` (viewport = desc size) and blends the water over it.
void drawScreenSpaceFluid(ScreenSpaceRenderer& renderer, GLuint target_fbo, const FluidCamera& camera,
                          const WaterParams& water, const ScreenSpaceParams& params);

}  // namespace engine
