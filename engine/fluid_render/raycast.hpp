#pragma once
// Metaball ray casting with per-pixel fragment lists (Szécsi & Illés 2012): each particle's
// support sphere (radius Rc) appends a record to its pixel's linked list (one SSBO pool, an
// atomic counter, an r32ui head image; GL 4.3+ features, which llvmpipe's 4.5 core has); a
// compute pass sorts each list, sweeps the exact piecewise-quartic sum of the mesh's field
// (fluid/surface: f = (u − 1/2)^2, u = r^2/(2 Rc^2), surface at T) along the ray, takes the
// first crossing as the surface and a full-screen pass shades it with the mesh's water look (water_shade.glsl).
//
// The pool is bounded: records past it are dropped and counted (RaycastRenderer::dropped), the
// overflow the paper trades against memory (§6). By default it sizes itself: a frame whose gather
// asks for more records than the pool holds enlarges the pool (to 1.25x the demand, at most
// max_pool_per_pixel) and gathers again, so only demand above the bound is dropped. Frame as in
// screen_space.hpp.
//
// Anisotropic kernels (Yu & Turk 2013, fluid/sph/anisotropy.hpp): uploadRaycastEllipsoids gives each
// particle its matrix g; the metaballs become ellipsoidal, f_j = (u − 1/2)^2 with
// u = |g_j (x − x̄_j)|^2 / (2 Rc^2): |g (x − x̄)|^2 is still quadratic along a ray, so each record
// still adds an exact quartic, over the ray's interval through the ellipsoid |g (x − x̄)| < Rc.

#include "engine/fluid_render/particle_pass.hpp"

namespace engine {

struct RaycastDesc {
  FluidRenderDesc base;
  // Pool records (16 bytes each) per viewport pixel at creation; 0 < pool_per_pixel <= 64. The
  // pool is max(1, round(pool_per_pixel * width * height)) records.
  float pool_per_pixel = 2.0f;
  // Most records per pixel the pool may grow to (RaycastParams::grow_pool); values below
  // pool_per_pixel mean pool_per_pixel (a fixed pool). 32 per pixel is 112.5 MiB at 640x360 and
  // 450 MiB at 1280x720; the game's fountain asks for far less (docs/render.md).
  float max_pool_per_pixel = 32.0f;
};

struct RaycastParams {
  float rc = 0.16f;           // cutoff radius Rc, metres (the mesh's SurfaceParams::rc)
  float threshold = 0.2f;     // iso level T (the mesh's SurfaceParams::threshold), in (0, 0.25)
  bool read_counters = true;  // read back used/dropped after the frame (waits for the GPU)
  // Enlarge a pool the gather overflowed and gather again in the same frame (reads the counter
  // back between the passes, a GPU wait); false = a fixed pool whose overflow is only counted.
  bool grow_pool = true;
};

struct RaycastRenderer {
  bool ready = false;
  std::string error;
  RaycastDesc desc;
  SceneTargets scene;
  GLuint heads = 0;                // r32ui, one list head per pixel
  GLuint nodes = 0, counters = 0;  // SSBO pool (uvec4 records), SSBO {used, dropped}
  std::uint32_t pool_records = 0;  // current pool size
  std::uint32_t max_pool_records = 0;
  std::uint64_t pool_growths = 0;  // times the pool was enlarged since creation
  GLuint hits = 0, thickness = 0;  // cast output: RGBA32F (outward normal, hit distance), R32F
  GLuint vao = 0, empty_vao = 0;
  ParticleBuffer particles;
  GLuint gather_program = 0, cast_program = 0, shade_program = 0, blit_program = 0;
  // Ellipsoidal metaballs: g per particle (particle_pass.hpp), drawn when shapes.count ==
  // particles.count; the same gather and cast shaders built with ELLIPSOID.
  ShapeBuffer shapes;
  GLuint ellipsoid_vao = 0, ellipsoid_gather_program = 0, ellipsoid_cast_program = 0;
  // Last frame (when RaycastParams::read_counters): records asked for and records dropped (by the
  // final gather, after any growth).
  std::uint64_t used = 0, dropped = 0;
};

void createRaycastRenderer(const RaycastDesc& desc, RaycastRenderer& out);
void destroyRaycastRenderer(RaycastRenderer& renderer);
GlObjectNames glNames(const RaycastRenderer& renderer);

void beginRaycastOpaquePass(RaycastRenderer& renderer, glm::vec4 clear_colour);
bool uploadRaycastParticles(RaycastRenderer& renderer, std::span<const glm::vec3> positions, std::string& error);
// Ellipsoidal metaballs at the smoothed centres, g = h G and its largest semi-axis factor per
// particle (fluid/sph/anisotropy.hpp), all the same size. False + error (nothing uploaded) when a
// value is not finite or the sizes differ.
bool uploadRaycastEllipsoids(RaycastRenderer& renderer, std::span<const glm::vec3> centres,
                             std::span<const glm::mat3> g, std::span<const float> max_axis, std::string& error);
void drawRaycastFluid(RaycastRenderer& renderer, GLuint target_fbo, const FluidCamera& camera, const WaterParams& water,
                      const RaycastParams& params);

}  // namespace engine
