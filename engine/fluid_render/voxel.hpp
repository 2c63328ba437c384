#pragma once
// View-adaptive voxelization of particles (Zirr & Dachsbacher 2015, "Memory-efficient on-the-fly
// voxelization of particle data"), the fourth way to draw the water. Per frame, on GL 4.3+
// compute (llvmpipe's 4.5 core runs it):
//   (a) splat, tile by tile (§3.1, §4.1): the screen is split into tiles whose perspective bit grid
//       (1 bit per voxel, up to max_layers logarithmic depth layers, §4.2) fits tile_budget_bytes;
//       each particle sphere sets the bits its pixels' rays cross (atomicOr, shaders/voxel_splat.comp);
//   (b) compress (§3.1, §3.2, §4.3–4.4): each column scanned word by word into up to max_spans
//       spans [entry, exit) with the minimum-gap bridging; only the spans outlive the tile;
//   (c) connect (§3.3, Listing 1): spans of the four neighbour columns linked where they overlap;
//   (d) filter (§3.4, §4.6): iterations of a 3x3 kernel on 1/depth along the links, their count
//       from the distance (a world-space radius);
//   (e) normals (§3.4, §4.5): Sobel along the links, octahedron-encoded;
//   (f) shade (§3.5): first surface, water length along a refracted ray marched through the spans
//       (or the column's span lengths), the other methods' water look (fluid/water_shade.glsl).
// The bits and spans are those of fluid/surface/voxel_reference.hpp's CPU reference.
//
// Anisotropic kernels (Yu & Turk 2013, fluid/sph/anisotropy.hpp): uploadVoxelEllipsoids gives each
// particle its matrix g; the splat then sets the voxels the pixel rays cross inside the ellipsoid
// { x : |g (x − x̄)| <= radius } (the ray and centre mapped by g onto the sphere test, tile and
// pixel bounds from the bounding sphere radius · max axis). The later stages work on the bits and
// do not change. uploadVoxelParticles draws spheres.
//
// Frame as in screen_space.hpp: beginVoxelOpaquePass() (or draw/blit into `scene.fbo`) → the
// caller draws the opaque scene → uploadVoxelParticles() → drawVoxelFluid(). Needs the creating
// context current. A renderer whose shaders failed is `ready == false` and its calls do nothing.

#include "engine/fluid_render/particle_pass.hpp"
#include "fluid/surface/voxel_reference.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace engine {

struct VoxelDesc {
  FluidRenderDesc base;
  int max_spans = 4;  // spans stored per pixel, 1..7 (the paper stores 7, §5.2)
  // Bytes of the temporary bit grid of one tile (§3.1, §5.2: 1 GiB for 1024x512x16384 there).
  // The tile is the largest run of whole rows that fits (or one row's part); >= 4 KiB.
  std::size_t tile_budget_bytes = std::size_t{64} << 20;
  int tile_width = 0, tile_height = 0;  // > 0: this tile size instead (Table 1's trade-off, tests)
  int max_layers = 4096;                // depth layers per column at most, 32..16384 (§5.1: 16384)
};

struct VoxelParams {
  float radius = 0.05f;           // particle sphere radius, metres (> 0): the iso radius of a lone particle
  float min_gap = 0.05f;          // §3.2: empty gaps shorter than this along the ray are bridged, metres
  float angle_degrees = 14.0f;    // §4.2, §5.1: angle resolution that sets the layer count (then max_layers)
  float filter_radius = 0.04f;    // §4.6: world radius of the depth filter, metres (0 = off)
  int max_filter_iterations = 8;  // 0..20 (the paper's views need up to 20)
  bool refraction_rays = true;    // §3.5: march a refracted ray through the spans (else span lengths)
  int max_ray_steps = 32;         // columns the refracted ray may cross, 1..256
  float max_ray_length = 2.0f;    // metres
  bool time_stages = false;       // glFinish after each stage and time it into VoxelStats
};

// The last frame, for the F1 overlay and `fluiddemo render`.
struct VoxelStats {
  int layers = 0, words = 0;              // per column
  float angle_degrees = 0.0f;             // the angle resolution the layers give
  float nearest = 0.0f, farthest = 0.0f;  // the grid's depth range, view metres (fitted to the particles)
  int tiles = 0, tile_width = 0, tile_height = 0;
  std::uint32_t particles = 0, splatted = 0;  // uploaded; splatted after the inner-cell pre-pass (§4.3)
  std::uint32_t inner_cells = 0;              // spheres standing for the full inner cells left out
  bool ellipsoids = false;                    // the particles are anisotropic kernels
  std::uint64_t tile_grid_bytes = 0;          // the temporary bit grid (one tile)
  std::uint64_t span_bytes = 0;               // what outlives the tiles: spans, counts, links, depths, normals
  std::uint64_t dense_grid_bytes = 0;         // one bit per voxel of the whole screen at the same layers
  std::uint64_t stored_spans = 0, overflow_columns = 0;  // (read back only with time_stages)
  double splat_ms = 0, compress_ms = 0, connect_ms = 0, filter_ms = 0, normals_ms = 0, shade_ms = 0;
};

struct VoxelRenderer {
  bool ready = false;
  std::string error;
  VoxelDesc desc;
  SceneTargets scene;
  GLuint vao = 0, empty_vao = 0;
  ParticleBuffer particles;
  // Anisotropic kernels: g per particle (particle_pass.hpp ShapeBuffer, read as a storage buffer),
  // splatted when shapes.count == particles.count; max_axis = the largest over the particles.
  ShapeBuffer shapes;
  float max_axis = 1.0f;
  GLuint selection = 0;  // §4.3 pre-pass: indices of the particles to splat
  std::uint32_t selection_count = 0;
  GLuint inner_cells = 0;  // §4.3 pre-pass: one sphere (centre, radius) per full inner cell
  std::uint32_t inner_count = 0;
  bool use_selection = false;
  glm::vec3 bounds_lo{0.0f}, bounds_hi{-1.0f};  // world box of the uploaded particles (empty: lo > hi)
  GLuint layer_table = 0;                       // float[layers + 1] boundaries
  GLuint tile_bits = 0;                         // the tile's bit grid
  std::size_t tile_bits_bytes = 0;
  GLuint spans = 0, meta = 0, links = 0, depth_raw = 0, depth_ping = 0, depth_pong = 0, normals = 0;
  GLuint depth_final = 0;  // one of depth_raw/ping/pong: the last filter output
  GLuint splat_program = 0, compress_program = 0, connect_program = 0, filter_program = 0, normals_program = 0,
         shade_program = 0, blit_program = 0;
  fluid::VoxelLayers layers;  // this frame's layers (voxelBeginFrame)
  fluid::VoxelView view;
  VoxelStats stats;
};

// The extension lines every voxel program's stages start with (compute only where a stage is one).
std::string voxelShaderPrelude(std::span<const ShaderStageFiles> stages);
void createVoxelRenderer(const VoxelDesc& desc, VoxelRenderer& out);
void destroyVoxelRenderer(VoxelRenderer& renderer);
GlObjectNames glNames(const VoxelRenderer& renderer);

void beginVoxelOpaquePass(VoxelRenderer& renderer, glm::vec4 clear_colour);

// False + error (nothing uploaded) when a position is not finite. Empty = no fluid.
bool uploadVoxelParticles(VoxelRenderer& renderer, std::span<const glm::vec3> positions, std::string& error);
// The same, leaving full inner cells out of the splat (§3.1, §4.3): cells of edge `cell` metres
// holding at least `full_count` particles whose 26 neighbours are full too (fluid::dropInnerCellParticles;
// full_count <= 0: from the set's median cell); each inner cell is splatted as its circumscribed
// sphere instead, so the body stays filled. cell <= 0: keep all.
bool uploadVoxelParticles(VoxelRenderer& renderer, std::span<const glm::vec3> positions, float cell, int full_count,
                          std::string& error);
// Anisotropic kernels: `centres` (the smoothed kernel centres x̄), `g` (h G per particle: symmetric,
// dimensionless) and its largest semi-axis factor (fluid::Anisotropy), one each per centre; every
// particle is the ellipsoid { x : |g (x − x̄)| <= VoxelParams::radius }. False + error (nothing
// uploaded) when a value is not finite, an axis is not positive or the sizes differ. `cell`,
// `full_count`: as above (the inner cells of the centres stay spheres).
bool uploadVoxelEllipsoids(VoxelRenderer& renderer, std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                           std::span<const float> max_axis, std::string& error);
bool uploadVoxelEllipsoids(VoxelRenderer& renderer, std::span<const glm::vec3> centres, std::span<const glm::mat3> g,
                           std::span<const float> max_axis, float cell, int full_count, std::string& error);

// Copies the scene colour into `target_fbo` (viewport = desc size) and blends the water over it.
void drawVoxelFluid(VoxelRenderer& renderer, GLuint target_fbo, const FluidCamera& camera, const WaterParams& water,
                    const VoxelParams& params);

// The stages one by one, for tests and benchmarks (drawVoxelFluid runs them in this order).
// Fits the layers to the particles' depth range in this view, uploads their table, sizes the
// buffers and lists the tiles; false when no particle can be in view (nothing to draw).
bool voxelBeginFrame(VoxelRenderer& renderer, const FluidCamera& camera, const VoxelParams& params,
                     std::vector<fluid::VoxelTile>& tiles);
void voxelSplatTile(VoxelRenderer& renderer, const VoxelParams& params, fluid::VoxelTile tile);
void voxelCompressTile(VoxelRenderer& renderer, const VoxelParams& params, fluid::VoxelTile tile);
// After every tile: connect, filter, normals.
void voxelSurfaces(VoxelRenderer& renderer, const VoxelParams& params);
// Reads the current tile grid (layout of fluid::voxelizeReference for `tile`).
void readVoxelTileBits(const VoxelRenderer& renderer, fluid::VoxelTile tile, std::vector<std::uint32_t>& words);
// Reads every pixel's spans (max_spans per pixel, row-major from the bottom row) and columns.
void readVoxelSpans(const VoxelRenderer& renderer, std::vector<fluid::VoxelSpan>& spans,
                    std::vector<fluid::VoxelColumn>& columns);

}  // namespace engine
