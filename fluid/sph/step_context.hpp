#pragma once
// Internal to fluid/sph: the state one SPH step hands from unit to unit (neighbour search,
// boundary, solver, advection, collisions), and the deterministic parallel loops they share.
// Not part of the public API (sph.hpp).
#include "fluid/core/parallel.hpp"
#include "fluid/sph/sph.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace fluid::sph_step {

// Fixed grain: parallelDeterministicReduce splits a range the same way for any thread count,
// so every floating-point sum of the step is bit-identical for 1 and N threads.
constexpr std::size_t kGrain = 256;

using Clock = std::chrono::steady_clock;
inline float msSince(Clock::time_point t0) {
  return std::chrono::duration<float, std::milli>(Clock::now() - t0).count();
}

template <typename F>
void forEach(std::size_t n, F&& f) {
  par::parallelFor(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

template <typename T, typename F, typename J>
T reduce(std::size_t n, T identity, F&& body, J&& join) {
  return par::parallelDeterministicReduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), identity,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) body(i, acc);
        return acc;
      },
      join);
}

// Chunked variants for loops whose per-particle work is batched: f(b, e) on consecutive blocks
// of at most kGrain particles (reduceChunks: in the same blocks and order as reduce, so sums are
// bit-identical for any thread count).
template <typename F>
void forChunks(std::size_t n, F&& f) {
  par::parallelFor(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); b += kGrain) f(b, std::min(r.end(), b + kGrain));
  });
}
template <typename T, typename F, typename J>
T reduceChunks(std::size_t n, T identity, F&& body, J&& join) {
  return par::parallelDeterministicReduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), identity,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t b = r.begin(); b < r.end(); b += kGrain) body(b, std::min(r.end(), b + kGrain), acc);
        return acc;
      },
      join);
}

struct SumMax {
  double sum = 0.0;
  float max = 0.0f;
};
inline SumMax joinSumMax(SumMax a, const SumMax& b) {
  a.sum += b.sum;
  a.max = std::max(a.max, b.max);
  return a;
}
inline float maxOf(float a, float b) { return std::max(a, b); }

// Force and torque (about the collider pose's translation) the fluid exerts on one collider.
struct ForceTorque {
  glm::vec3 force{0.0f}, torque{0.0f};
};
// DFSPH sums the coupling forces of up to this many colliders in its last per-particle pass.
constexpr std::size_t kFusedColliders = 4;
struct CouplingSums {
  ForceTorque per_collider[kFusedColliders];
};

// One step's shared state. Set up by the step driver (sph_step.cpp), filled in by the units in
// step order; every field names the unit that writes it.
struct StepContext {
  SphWorld& world;
  const SphParams& params;
  SphScratch& scratch;
  ParticleStore& particles;
  SphStepStats& stats;
  std::size_t count = 0;           // SPH particles after sinks, emitters and spray transitions
  std::size_t total = 0;           // all particles: the SPH water [0, count), the spray [count, total) (spray.hpp)
  std::size_t collider_count = 0;  // world.colliders.size()
  float support = 0.0f;            // H
  float spacing = 0.0f;            // d
  float mass = 0.0f;               // m
  float rest_density = 0.0f;       // rho_0
  float max_dt = 0.0f;             // the step's upper bound (request clamped to max_time_step)
  double span = 0.0;               // stepSphWithin: time left to the caller's target (0: stepSph)
  float previous_dt = 0.0f;        // the last step's dt (max_dt before the first step)
  // Neighbour search (neighbor_step.cpp): the exact lists, i's neighbours are
  // neighbor_indices[neighbor_offsets[i] .. + neighbor_counts[i]) once the density pass ran.
  const std::uint32_t* neighbor_offsets = nullptr;
  const std::uint32_t* neighbor_counts = nullptr;
  std::uint32_t* neighbor_indices = nullptr;
  // WCSPH: the Verlet candidates of i are verlet_candidates[neighbor_offsets[i] .. candidate_end[i]);
  // DFSPH: the same array as neighbor_indices, ends neighbor_offsets[i + 1].
  const std::uint32_t* verlet_candidates = nullptr;
  const std::uint32_t* candidate_end = nullptr;
  bool filter_verlet = false;  // WCSPH: the density pass filters the Verlet list to |x_ij| < H
  // Boundary sampling (boundary.cpp): the fastest approach (collider velocity along its outward
  // normal) of collider material that could reach a particle within one maximal step.
  float wall_approach_speed = 0.0f;
  // Solver (wcsph.cpp / dfsph.cpp) outputs.
  float dt = 0.0f;
  bool dt_held_at_min = false;  // chooseTimeStep raised dt to min_time_step
  int density_iterations = 0;
  int divergence_iterations = 0;
  bool advected = false;  // DFSPH without XSPH advects in its last per-particle pass
  bool coupled = false;   // coupling holds the boundary-pressure coupling sums of every collider
  CouplingSums coupling{};
};

}  // namespace fluid::sph_step
