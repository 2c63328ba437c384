#pragma once
// Screen-space fluid rendering (Janisz thesis §3.1, after van der Laan, Green & Sainz 2009): the
// particles drawn directly, no mesh. Passes: nearest sphere per pixel as linear depth (exact
// ray-sphere hits on camera-facing billboards), `smoothing_iterations` rounds of a separable
// bilateral filter on that depth, additive sphere thickness, then one full-screen pass that
// rebuilds normals from the smoothed depth and shades with the mesh's water look
// (shaders/fluid/water_shade.glsl: refraction, Beer–Lambert absorption, Fresnel sky, highlight).
//
// Anisotropic kernels (Yu & Turk 2013, fluid/sph/anisotropy.hpp): uploadScreenSpaceEllipsoids
// gives each particle its matrix g; passes 1 and 2 then draw ellipsoid splats: a square covering
// the ellipsoid's bounding sphere, depth and chord from the ray-ellipsoid intersection (the ray
// mapped by g onto the unit sphere, ray.glsl rayEllipsoid). uploadScreenSpaceParticles draws spheres.
// The depth filter is the bilateral one or the narrow-range filter (Truong & Yuksel 2018,
// shaders/fluid/ss_narrow.frag), ScreenSpaceParams::filter.
//
// Frame: beginScreenSpaceOpaquePass() (or blit into `scene.fbo`) → caller draws the opaque scene
// → uploadScreenSpaceParticles() → drawScreenSpaceFluid(). Needs the creating context current.
// A renderer whose shaders failed is `ready == false` and its calls do nothing.

#include "engine/fluid_render/particle_pass.hpp"

namespace engine {

enum class DepthFilter { bilateral, narrow_range };
// "bilateral" / "narrow_range" (the scene key fluid_surface.ss_filter); false for anything else.
bool parseDepthFilter(std::string_view text, DepthFilter& out);

struct ScreenSpaceParams {
  float radius = 0.05f;          // sphere radius of one particle, metres (> 0); ellipsoids: ρ of g
  int smoothing_iterations = 3;  // filter rounds (each horizontal + vertical), 0..32
  float filter_radius = 0.1f;    // filter half-width, metres (projected per pixel, 1..24 px)
  float depth_falloff = 0.05f;   // bilateral range sigma, metres
  DepthFilter filter = DepthFilter::bilateral;
  // Narrow-range filter, in particle radii (`radius`): the depth range's half-width and the depth
  // behind the pixel that farther samples are clamped to. 10.5 and 1 are the values of the
  // paper authors' demo (github.com/ttnghia/RealTimeFluidRendering, filter-narrow-range).
  float narrow_threshold = 10.5f;
  float narrow_clamp = 1.0f;
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
  // Ellipsoid splats: per particle g (particle_pass.hpp ShapeBuffer), fed with the centres to
  // `ellipsoid_vao`; drawn when shapes.count == particles.count.
  ShapeBuffer shapes;
  GLuint ellipsoid_vao = 0;
  GLuint ellipsoid_depth_program = 0, ellipsoid_thickness_program = 0, narrow_program = 0;
};

void createScreenSpaceRenderer(const FluidRenderDesc& desc, ScreenSpaceRenderer& out);
void destroyScreenSpaceRenderer(ScreenSpaceRenderer& renderer);
// Every GL name the renderer holds (empty when nothing was created).
GlObjectNames glNames(const ScreenSpaceRenderer& renderer);

void beginScreenSpaceOpaquePass(ScreenSpaceRenderer& renderer, glm::vec4 clear_colour);
// False + error (nothing uploaded) when a position is not finite. Empty = no fluid.
bool uploadScreenSpaceParticles(ScreenSpaceRenderer& renderer, std::span<const glm::vec3> positions,
                                std::string& error);
// Ellipsoid splats: `centres` (the smoothed kernel centres x̄), `g` (h G per particle: symmetric,
// positive definite) and `max_axis` (g's largest semi-axis factor), all the same size. False +
// error (nothing uploaded) when a value is not finite or the sizes differ.
bool uploadScreenSpaceEllipsoids(ScreenSpaceRenderer& renderer, std::span<const glm::vec3> centres,
                                 std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error);
// Pass 3 alone: params.smoothing_iterations rounds of params.filter over the linear depth in
// smooth_depth[0] (R32F, 1e30 = empty), the result back in smooth_depth[0]. drawScreenSpaceFluid
// calls it; tests call it on a depth image of their own.
void filterScreenSpaceDepth(ScreenSpaceRenderer& renderer, const FluidCamera& camera, const ScreenSpaceParams& params);
// Copies the scene colour into `target_fbo` (viewport = desc size) and blends the water over it.
void drawScreenSpaceFluid(ScreenSpaceRenderer& renderer, GLuint target_fbo, const FluidCamera& camera,
                          const WaterParams& water, const ScreenSpaceParams& params);

}  // namespace engine
