#pragma once
// View-adaptive voxelization of particles (Zirr & Dachsbacher 2015, "Memory-efficient on-the-fly
// voxelization of particle data"): the layer layout, the per-pixel ray, and a CPU reference of the
// splat (§3.1, §4.1) and the column compression (§3.1, §3.2, §4.4). The GL renderer
// (engine/fluid_render/voxel.*, shaders/voxel_*) runs the same float operations in the same
// order, so on small sets its bits and spans equal these (tests/voxel).
//
// The grid: every pixel of a width x height view is a column of `count` layers between view
// depths d_0 and d_count, layer i covering [d_i, d_{i+1}), d_i = d_0 (1 + K)^i (§4.2: constant
// ratio of cell depth to cell width, so constant angle resolution). The boundaries are one float
// table computed here in double; both sides find layers by binary search in it, not by a log,
// whose float result differs between libm and a GPU driver.
//
// A voxel (pixel, layer) is set when the pixel-centre ray's segment inside a particle sphere meets
// the layer's depth interval. Depth is view depth (−z in view space), not distance along the ray.
//
// Anisotropic kernels (Yu & Turk 2013, fluid/sph/anisotropy.hpp): a particle drawn as the sphere
// of radius ρ is drawn as the ellipsoid { x : |g (x − x̄)| <= ρ } instead. In view space that is
// |M (d·ray − c)| <= ρ with M = R g Rᵀ (R the view's rotation), i.e. the sphere of radius ρ at
// M c met by the ray M ray: the same quadratic in the view depth d, so the sphere's layer test
// runs unchanged on the mapped ray and centre (voxelEllipsoidLayers).

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

// The camera as the grid sees it. projection is a perspective matrix (glm, column-major).
struct VoxelView {
  int width = 0, height = 0;  // pixels, 1..8192
  glm::mat4 view{1.0f};       // world → view, camera looking along −z
  glm::mat4 projection{1.0f};
};

struct VoxelLayers {
  int count = 0;               // layers, a multiple of 32 (one 32-bit word holds 32 layers)
  int words = 0;               // count / 32: machine words per column
  float angle_degrees = 0.0f;  // the angle resolution α the count gives (§4.2, §5.1)
  std::vector<float> depth;    // count + 1 boundaries d_0 < d_1 < ... < d_count, view metres
};

// Layers between view depths [nearest, farthest] (nearest > 0) so that a cell's depth over its
// width is tan(angle_degrees) (§4.2: K_d = tan α · 2 tan(θ_y/2) / R_y), rounded up to a multiple
// of 32 and clamped to [32, max_layers] (then the ratio is whatever fills the range). The paper
// uses α = 14° and 16,384 layers at 1080p (§5.1).
void makeVoxelLayers(const VoxelView& view, float nearest, float farthest, float angle_degrees, int max_layers,
                     VoxelLayers& out);

// View-space direction through the centre of pixel (x, y) (x from the left, y from the bottom,
// OpenGL window convention), scaled so its z is −1: the point at view depth d is d · ray.
glm::vec3 voxelPixelRay(const VoxelView& view, int x, int y);

// The layer holding view depth d: the i with depth[i] <= d < depth[i+1]; −1 below depth[0],
// count at or past depth[count].
int voxelLayerOf(std::span<const float> depth, float d);

// The layers [first, last] (inclusive) the pixel ray `ray` meets inside the sphere (centre in
// view space, radius), clamped to the grid; false when it misses the sphere or the grid.
bool voxelSphereLayers(glm::vec3 ray, glm::vec3 centre_view, float radius, std::span<const float> depth, int& first,
                       int& last);

// The view-space kernel matrix M = R g Rᵀ of a world-space g (symmetric), computed as
// I + R (g − I) Rᵀ so that a sphere's g (the identity) gives exactly I and its ellipsoid sets
// exactly the sphere's bits. R is the upper 3x3 of `view` (a rigid transform). The GLSL side
// (shaders/voxel_splat.comp kernelMatrix) runs the same operations in the same order.
glm::mat3 voxelKernelMatrix(const glm::mat4& view, const glm::mat3& g);

// The layers [first, last] the pixel ray meets inside the ellipsoid { p : |m (p − centre_view)|
// <= radius } (view space, m from voxelKernelMatrix), clamped to the grid; false when it misses.
bool voxelEllipsoidLayers(glm::vec3 ray, glm::vec3 centre_view, const glm::mat3& m, float radius,
                          std::span<const float> depth, int& first, int& last);

// A rectangle of pixels: one tile of the screen (§3.1).
struct VoxelTile {
  int x = 0, y = 0, width = 0, height = 0;
};

// The tile's bit grid: words[(ly * tile.width + lx) * layers.words + w], bit b of word w = layer
// 32 w + b of pixel (tile.x + lx, tile.y + ly). Every particle against every pixel of the tile
// (the reference, for small sets; the GPU walks each sphere's screen bounds instead).
void voxelizeReference(std::span<const glm::vec3> centres, float radius, const VoxelView& view,
                       const VoxelLayers& layers, VoxelTile tile, std::vector<std::uint32_t>& words);
// The same for anisotropic kernels: particle i is the ellipsoid { x : |g[i] (x − centres[i])| <=
// radius } (g.size() == centres.size(); the smoothed centres x̄ of fluid/sph/anisotropy.hpp).
void voxelizeReference(std::span<const glm::vec3> centres, std::span<const glm::mat3> g, float radius,
                       const VoxelView& view, const VoxelLayers& layers, VoxelTile tile,
                       std::vector<std::uint32_t>& words);

// One span of a column: set layers [entry, exit) (exit exclusive), gaps shorter than the minimum
// bridged (§3.2, §4.4).
struct VoxelSpan {
  std::uint32_t entry = 0, exit = 0;
};
// A compressed column: the first `stored` spans (at most max_spans); `total` spans were found;
// past max_spans the last stored span is extended to the last exit and the empty depth inside
// it kept in `hidden_gap` (view metres), so absorption stays right (§3.1, Fig. 8).
struct VoxelColumn {
  std::uint32_t stored = 0, total = 0;
  float hidden_gap = 0.0f;
};

// Scans one column's words (layers.words of them) word by word for runs of set bits (§4.3) and
// joins runs whose empty gap, as a length along the pixel ray (depth difference × ray_length,
// ray_length = |voxelPixelRay|), is below min_gap (§3.2, §4.4). `spans` has max_spans entries.
void compressColumnReference(std::span<const std::uint32_t> column, const VoxelLayers& layers, float min_gap,
                             float ray_length, int max_spans, VoxelSpan* spans, VoxelColumn& meta);

// The particles worth splatting (§3.1, §4.3, §5): those not in a full inner cell. Cells are cubes
// of edge `cell` on a grid at the origin; a cell with at least `full_count` particles is full, and
// a full cell whose 26 neighbours are all full is inner: its particles add no surface. They are
// replaced by one sphere per inner cell (its centre, radius kInnerCellRadius · cell: the cell's
// circumscribed sphere, which reaches only into full neighbours), so the body stays filled for the
// compression: without them its inside would be a hollow the minimum gap cannot bridge (the paper
// marches the simulation grid during extraction instead, §4.3). full_count <= 0: 1/2 of the
// median count of the occupied cells (a settled body's cells where the set has one; the paper takes
// it from the simulation's constraints). Appends the kept indices, in input order, to `kept` and
// the inner cells' centres to `inner_cells`.
inline constexpr float kInnerCellRadius = 0.87f;  // > sqrt(3) / 2
void dropInnerCellParticles(std::span<const glm::vec3> positions, float cell, int full_count,
                            std::vector<std::uint32_t>& kept, std::vector<glm::vec3>& inner_cells);

}  // namespace fluid
