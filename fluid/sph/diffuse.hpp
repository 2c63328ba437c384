#pragma once
// Diffuse material of a particle fluid: spray, foam and air bubbles after Ihmsen, Akinci, Gissler &
// Teschner 2012, "Unified spray, foam and air bubbles for particle-based fluids", The Visual
// Computer 28 (6-8). Per SPH particle i, over its neighbours j within h (the SPH support):
//   - weighting W(x_ij, h) = 1 - |x_ij| / h for |x_ij| <= h, 0 beyond (§3, the radially symmetric
//     weight of the potentials; x_ij = x_i - x_j, v_ij = v_i - v_j);
//   - trapped air (§3.1, eq. 4): I_ta = sum_j |v_ij| (1 - v^_ij . x^_ij) W(x_ij, h): large where
//     neighbours approach each other (v^ . x^ = -1 gives 2 |v_ij|), 0 where they separate;
//   - wave crest (§3.2, eqs. 5-6): the surface curvature kappa_i = sum_j (1 - n^_i . n^_j) W(x_ij, h),
//     counting only neighbours j with x^_ji . n^_i < 0 (the surface is convex there) and only
//     when the particle moves along its normal (v^_i . n^_i >= 0.6); I_wc = that kappa;
//   - kinetic energy (§3.3): E_k = 1/2 |v_i|^2, the specific energy (J/kg), so the thresholds do not
//     depend on the particle size (the paper uses 1/2 m |v|^2);
//   - each potential clamped to [0, 1] by eq. 1: Phi(I, tmin, tmax) = (min(I, tmax) - min(I, tmin)) / (tmax - tmin);
//   - diffuse particles per step (eq. 2): n_d = I_k (k_ta I_ta + k_wc I_wc) dt, sampled in the
//     cylinder spanned by v_i dt around x_i (§4.1, eq. 3);
//   - classes by fluid-neighbour count (§4.2): spray below 6, bubbles above 20, foam between.
// Simplifications (said where they are made): the normals are the direction of a weighted count
// gradient, n_i = normalize(sum_j W(x_ij) x^_ij), which is -grad of the colour field for equal
// particle volumes; a particle whose neighbours surround it (|sum_j W x^_ij| / sum_j W below
// `surface_threshold`) has no normal, no wave-crest potential, and is not counted as a curvature
// neighbour (the paper computes the curvature at the surface only). A birth's class is taken
// from its parent's neighbour count (the birth point lies within r of the parent).
//
// Neighbours come from a fluid::NeighborGrid built on the positions by the convenience call (cells
// of h / 2; the SPH step's own grid describes the water at the step's start). Determinism: each
// particle's sums run over its neighbours in the grid's fixed order and write that particle's
// outputs only, so the results are the same bits for every thread count; births use a hash of
// (seed, particle index), not a shared random stream.

#include "fluid/sph/neighbor_grid.hpp"

#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

enum class DiffuseClass : std::uint8_t { spray = 0, foam = 1, bubble = 2 };

struct DiffuseParams {
  float radius = 0.0f;  // h (m) > 0: the neighbourhood (the SPH support)
  // tau ranges of eq. 1 (the paper's values are for its own units; see docs/appearance.md).
  float ta_min = 2.0f, ta_max = 10.0f;     // I_ta, m/s
  float wc_min = 0.1f, wc_max = 1.0f;      // I_wc, dimensionless
  float k_min = 2.0f, k_max = 15.0f;       // I_k on 1/2 |v|^2, J/kg
  float k_ta = 40.0f, k_wc = 40.0f;        // diffuse particles per second at I = 1
  float surface_threshold = 0.15f;         // |sum W x^| / sum W above which a particle has a normal
  int spray_below = 6, bubble_above = 20;  // §4.2 neighbour counts
};

// Clamped to workable ranges (DESIGN.md habit 5): tau_max >= tau_min, rates >= 0, counts ordered.
DiffuseParams clampDiffuseParams(const DiffuseParams& params);

// Eq. 1; a degenerate range (tmax <= tmin) is a step at tmax.
float clampPotential(float value, float tmin, float tmax);

// §4.2: spray with fewer than spray_below neighbours, bubble with more than bubble_above, else
// foam. `neighbours` may be an estimate (a density times the neighbourhood's volume); NaN is spray.
DiffuseClass classifyDiffuse(float neighbours, int spray_below = 6, int bubble_above = 20);

// One pair's trapped-air term of eq. 4, |v_ij| (1 - v^_ij . x^_ij) W(x_ij, h) (0 beyond h and for
// coincident positions or equal velocities).
float trappedAirTerm(glm::vec3 xi, glm::vec3 vi, glm::vec3 xj, glm::vec3 vj, float h);

// Per-particle results, caller-owned and reused.
struct DiffusePotentials {
  std::vector<glm::vec3> normal;          // unit outward normal, or 0 inside the water
  std::vector<std::uint32_t> neighbours;  // within h, i itself not counted
  std::vector<float> trapped_air;         // I_ta (raw, m/s)
  std::vector<float> wave_crest;          // I_wc (raw)
  std::vector<float> kinetic;             // E_k = 1/2 |v|^2 (J/kg)
};

struct DiffuseScratch {
  NeighborGrid grid;
  std::vector<float> sx, sy, sz;      // positions in the grid's sorted order
  std::vector<std::uint8_t> need;     // per sorted entry: 1 active (I_k > 0), 2 a neighbour of one
  std::vector<std::uint32_t> active;  // sorted entries with I_k > 0
};

// Potentials of every particle that can generate (I_k > 0, eq. 2 multiplies by it): the others
// keep zero potentials, and their normal and neighbour count are computed only when they lie within
// h of such a particle (the wave crest needs its neighbours' normals). In the fountain about 1 %
// of the water moves fast enough, so the pass costs a fraction of a full neighbour sweep. Returns false (outputs zero,
// nothing searched) when a position or velocity is not finite, or the sizes differ.
bool computeDiffusePotentials(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                              const DiffuseParams& params, DiffuseScratch& scratch, DiffusePotentials& out);

struct DiffuseBirth {
  glm::vec3 position{0.0f}, velocity{0.0f};
  DiffuseClass type = DiffuseClass::foam;
};

// Eq. 2 and §4.1: appends the births of one step of `dt` (at most `max_births`) to `out`, the
// fractional n_d rounded per particle by a hash of (seed, i). Returns the number appended.
std::size_t generateDiffuse(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                            const DiffusePotentials& potentials, const DiffuseParams& params, float dt,
                            std::uint64_t seed, std::size_t max_births, std::vector<DiffuseBirth>& out);

// The coarse grid the GPU sprites read each step (engine setFluidGrid): per cell the sum of the
// fluid velocities (xyz, m/s) and the particle count (w), over a box around the particles padded
// by one cell; cells of `cell_size` (grown so no axis has more than `max_cells`). The GPU
// interpolates both trilinearly and takes v = sum / count (a count-weighted mean), and estimates a
// point's fluid-neighbour count as count * (4/3 pi h^3) / cell^3 (`neighbour_scale`): the density
// the cell holds times the volume of the neighbourhood the paper counts in (§4.2).
struct FluidCellGrid {
  glm::ivec3 size{0};
  glm::vec3 origin{0.0f};
  float cell = 0.0f;
  std::vector<glm::vec4> cells;  // size.x * size.y * size.z, x fastest
  float neighbour_scale = 0.0f;
};
// False (grid emptied, size 0) when there is no finite particle.
bool buildFluidCellGrid(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities, float cell_size,
                        float radius, int max_cells, FluidCellGrid& out);

}  // namespace fluid
