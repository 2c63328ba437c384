#pragma once
// Anisotropic kernels for drawing particle fluids (Yu & Turk 2013, "Reconstructing surfaces of
// particle-based fluids using anisotropic kernels", ACM TOG 32(1)). Per particle i:
//   - weights w_ij = 1 - (|x_i - x_j| / r)^3 for |x_i - x_j| < r, 0 beyond (§5.1, Eq. 11);
//   - the weighted mean x^w_i = sum_j w_ij x_j / sum_j w_ij (Eq. 10) and the weighted covariance
//     C_i = sum_j w_ij (x_j - x^w_i)(x_j - x^w_i)^T / sum_j w_ij (Eq. 9), j running over i itself
//     and its neighbours within r;
//   - C = R Σ R^T (Eq. 12; an exact symmetric 3x3 Jacobi solve, fixed sweep count), the
//     eigenvalues σ1 >= σ2 >= σ3 clamped to σ~k = max(σk, σ1 / k_r) (Eq. 15), so no axis is more
//     than k_r times shorter than the longest;
//   - G_i = (1/h) R Σ~^-1 R^T (Eq. 16): the kernel W(x - x̄_i, G_i) = σ det(G_i) P(|G_i (x - x̄_i)|);
//   - the kernel centre moved by one step of Laplacian smoothing, x̄_i = (1 - λ) x_i + λ x^w_i
//     (§4, Eq. 6), which pulls the lattice bumps of a flat surface in.
//
// Names (the game's scene keys fluid_surface.k_r / k_s / k_n / lambda) against the paper's:
//   k_r    = the paper's k_r (largest axis ratio, 4 in the paper);
//   k_n    = the paper's N_ε (a particle with k_n or fewer neighbours stays a sphere; 25 in the
//            paper). The paper's own k_n (the sphere's scale, Σ~ = k_n I) is 1 here: a particle
//            that stays a sphere draws exactly as the isotropic renderers draw it;
//   k_s    = the scale of the stretched axes. The paper writes Σ~ = k_s diag(σ~), σ in m^2, so its
//            k_s (1400) only fits one particle spacing; here the clamped eigenvalues are divided by
//            their geometric mean first, a_k = k_s σ~k / (σ~1 σ~2 σ~3)^(1/3), so k_s = 1 keeps the
//            ellipsoid's volume equal to the sphere's at any spacing (an interior particle, whose
//            neighbourhood is round, stays the isotropic sphere);
//   lambda = the paper's λ (0.9 in the paper).
// The output g_i = h G_i = R diag(1/a_k) R^T is dimensionless: a renderer that draws a particle
// as a sphere of radius ρ draws it as the ellipsoid { x : |g_i (x - x̄_i)| <= ρ } (semi-axes ρ a_k
// along the eigenvectors), a field that evaluates W(|x - x_i| / ρ) evaluates W(|g_i (x - x̄_i)| / ρ).
//
// Neighbours come from a fluid::NeighborGrid (neighbor_grid.hpp, the SPH's grid type) built on
// the same positions: the query walks the grid's row runs in place (no neighbour lists written).
// The SPH step's own grid describes the water at the step's start (spray excluded), so the
// convenience overload re-buckets the current positions into the scratch's grid (one counting
// sort; no search).
//
// Determinism: each particle's sums run over its neighbours in the grid's fixed order (row by
// row, then by sorted entry) and write only that particle's outputs, so the results are the same
// bits for every thread count (tests/sph/test_anisotropy.cpp).

#include "fluid/sph/neighbor_grid.hpp"

#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

struct AnisotropyParams {
  float radius = 0.0f;  // r (m) > 0: the neighbourhood of the PCA (the paper's r_i = 2h)
  float k_r = 4.0f;     // >= 1: largest ratio of the longest to the shortest axis
  float k_s = 1.0f;     // > 0: scale of a stretched kernel's axes (1: the sphere's volume)
  int k_n = 25;         // >= 0: a particle needs more than k_n neighbours to be stretched
  float lambda = 0.9f;  // in [0, 1]: centre smoothing (0: centres stay at the particles)
};

// Ranges the pass works with (out-of-range tunables are clamped, DESIGN.md habit 5).
AnisotropyParams clampAnisotropyParams(const AnisotropyParams& params);

// Per-particle results, caller-owned and reused (vectors only grow).
struct Anisotropy {
  std::vector<glm::vec3> centre;  // x̄_i (m)
  std::vector<glm::mat3> g;       // h G_i: symmetric, dimensionless, identity for a sphere
  std::vector<float> max_axis;    // largest a_k of g_i (the ellipsoid's bounding radius over ρ), >= 1 for k_s >= 1
  std::vector<std::uint32_t> neighbours;  // neighbours within r (i itself not counted)
  std::size_t stretched = 0;              // particles with more than k_n neighbours
};

struct AnisotropyScratch {
  NeighborGrid grid;              // the convenience overload's grid (cells of about r / 2)
  std::vector<float> sx, sy, sz;  // the positions in the grid's sorted order (SoA, padded)
};

// Exact eigen-decomposition of the symmetric matrix `a` by cyclic Jacobi rotations (a fixed number
// of sweeps, so the cost and the bits are fixed): eigenvalues in descending order, eigenvectors
// as the matching columns of `vectors` (orthonormal, right-handed). Non-finite input gives zero
// eigenvalues and the identity.
void symmetricEigen3(const glm::mat3& a, glm::vec3& values, glm::mat3& vectors);

// g_i for one particle from its weighted covariance and neighbour count (Eqs. 12-16 as above),
// and the largest axis factor. Identity (a sphere) for n <= k_n, a zero or non-finite covariance.
glm::mat3 anisotropyMatrix(const glm::mat3& covariance, std::uint32_t neighbours, const AnisotropyParams& params,
                           float* max_axis = nullptr);

// Every particle of `positions` (finite) with `grid` built on them (any cell size > 0); the
// scratch's position copies are used, its grid is not.
void computeAnisotropy(const NeighborGrid& grid, std::span<const glm::vec3> positions, const AnisotropyParams& params,
                       AnisotropyScratch& scratch, Anisotropy& out);
// The same with the scratch's grid rebuilt on `positions` (cells of about params.radius / 2).
// Returns false, with every particle a sphere at its own position (g = I, centre = x) and nothing
// searched, when a position is not finite (the grid needs finite positions; the renderers then
// refuse the particles by their own check).
bool computeAnisotropy(std::span<const glm::vec3> positions, const AnisotropyParams& params, AnisotropyScratch& scratch,
                       Anisotropy& out);

}  // namespace fluid
