#pragma once
// Internal to fluid/sph: the DFSPH pair loops (density + gradients, viscosity, and the two loops of
// each solver iteration, Bender & Koschier 2015 eq. 9 / 13), portable and AVX2.
//
// The per-pair gradients G[k] = m_j grad W_ij live in three float arrays (SoA, 12 bytes a pair).
// Every pair loop runs "8 lanes wide": lane l of a particle's list accumulates its pairs
// l, 8 + l, ... and the lanes are summed at the end in one fixed tree (hsum8). Where the CPU has
// AVX2 (checked at run time; the build targets baseline x86-64) the lanes are one 256-bit
// register; elsewhere a portable loop does the same IEEE operations in the same order (no FMA:
// the AVX2 target does not enable it, so nothing is contracted), so both give bit-identical
// results (tests/sph checks this through SphScratch::portable_pair_loops). The order does not
// depend on the thread count either. Neighbour positions and velocities are read from 16-byte
// copies (SphScratch::pos4 / vel4).
//
// Lane blocks: the density pass writes each particle's gradients (and its neighbours as byte
// offsets 16 j) from a multiple of 8 (PairBlocks), zero-padded to the next multiple of 8, in
// 32-byte aligned arrays. The later loops then read whole aligned blocks with no partial last
// block: a pad lane reads particle 0 and multiplies it by a zero gradient, which adds an exact
// zero (an accumulator that starts at +0 is never -0, so adding +-0 leaves it unchanged): the
// sums equal the portable loops', which stop at the last real pair.
#include "fluid/sph/kernels.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstdint>

namespace fluid::sph_step {

// Unit direction for a coincident pair, u(a, b) = -u(b, a), from a hash of the two ids.
inline glm::vec3 coincidentDirection(std::uint32_t a, std::uint32_t b) {
  const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
  std::uint32_t h = lo * 0x9E3779B1u ^ (hi + 0x7F4A7C15u) * 0x85EBCA77u;
  glm::vec3 u;
  for (int c = 0; c < 3; ++c) {
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    u[c] = static_cast<float>(h & 0xFFFFu) / 32767.5f - 1.0f;
  }
  const float len = glm::length(u);
  u = len > 1e-3f ? u / len : glm::vec3(1.0f, 0.0f, 0.0f);
  return a < b ? u : -u;
}

// Constants of the DFSPH density pass (cubic spline, kernels.hpp, in the same operation order as
// CubicSplineKernel::evaluateInside, both branches evaluated and one selected per lane).
struct DensityConsts {
  float inv_support, sigma, sigma2, c_inner, c_outer;  // sigma2 = 2 sigma, c_inner = sigma/H, c_outer = -sigma/H * 6
  float mass, r_min, steepest_mass;                    // m, coincidence radius, m W'(H/3)
  static DensityConsts make(const CubicSplineKernel& k, float m, float r_min, float steepest) {
    DensityConsts c;
    c.inv_support = k.inv_support;
    c.sigma = k.sigma;
    c.sigma2 = k.sigma * 2.0f;
    c.c_inner = k.sigma * k.inv_support;
    c.c_outer = -k.sigma * k.inv_support * 6.0f;
    c.mass = m;
    c.r_min = r_min;
    c.steepest_mass = m * steepest;
    return c;
  }
};

// Per-particle results of the density pass: sum_j W_ij, sum_j m grad W_ij, sum_j |m grad W_ij|^2.
struct DensitySums {
  float w = 0.0f;
  glm::vec3 grad{0.0f};
  float sq = 0.0f;
};

// Lanes per block of the pair arrays.
constexpr std::uint32_t kPairLanes = 8;
inline std::uint32_t roundUpToBlock(std::uint32_t count) { return (count + kPairLanes - 1) & ~(kPairLanes - 1); }

// The lane-block layout of one step's pair arrays: i's pairs sit at [start[i], start[i] + cnt[i]),
// padded to start[i + 1] (a multiple of 8 further); the arrays' 32-byte aligned views.
struct PairBlocks {
  const std::uint32_t* start;  // n + 1 entries
  float *gx, *gy, *gz;         // m_j grad W_ij; pad lanes 0
  std::uint32_t* nb16;         // 16 j (byte offset of j's 16-byte record); pad lanes 0
};

// What the viscosity and solver loops read: the blocks, the real pair counts and the 16-byte
// velocity copy.
struct IterationArgs {
  const glm::vec4* vel4;
  const float *gx, *gy, *gz;
  const std::uint32_t *nb16, *start, *cnt;
};

struct PairLoops {
  // DFSPH density pass of the particles [i0, i1) (i1 - i0 <= kGrain): i's neighbours are
  // nbr[b[i], e[i]); fills i's lane blocks of `out` (gradients and nb16, pads included) and
  // sums[i - i0].
  void (*density_range)(const DensityConsts& c, const glm::vec4* positions, const std::uint32_t* id,
                        const std::uint32_t* nbr, const std::uint32_t* b, const std::uint32_t* e, std::uint32_t i0,
                        std::uint32_t i1, const PairBlocks& out, DensitySums* sums);
  // out[i - i0] = sum_k c_j (v_ij . x_ij) / (|x_ij|^2 + eps) G[k] over i's pairs for the particles
  // [i0, i1) (i1 - i0 <= kGrain; Laplacian viscosity, see stepSph), with c_j = 10 nu / rho_j in
  // a.vel4[j].w.
  void (*viscosity_range)(const glm::vec4* positions, const IterationArgs& a, std::uint32_t i0, std::uint32_t i1,
                          float eps, glm::vec3* out);
  // The two solver-iteration loops for the particles [i0, i1) (i1 - i0 <= kGrain): out[i - i0].
  void (*divergence_range)(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out);
  // kr4[j].x = kappa_j / rho_j (16-byte records, addressed like vel4).
  void (*kappa_range)(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1, glm::vec3* out);
};

// The AVX2 loops where the CPU has AVX2 and `portable` is false, else the portable ones.
const PairLoops& pairLoops(bool portable);

}  // namespace fluid::sph_step
