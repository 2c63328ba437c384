// The step's neighbour search (neighbor_step.hpp).
#include "fluid/sph/neighbor_step.hpp"

#include <algorithm>

namespace fluid::sph_step {
namespace {

// WCSPH Verlet-list skin as a fraction of the support H.
constexpr float kWcsphSkin = 0.2f;

// Re-sorts the particle data by grid cell in one pass, which also writes the 16-byte copies the
// pair loops read, the search's SoA copies of the sorted positions (findNeighbors with
// positions_copied) and the grid's keys in the new order (markGridReordered).
void resortByCell(StepContext& context, NeighborLists& lists) {
  SphScratch& scratch = context.scratch;
  ParticleStore& store = context.particles;
  const std::size_t n = context.count;
  std::uint32_t* const order = scratch.grid.order.data();
  const std::uint32_t* const old_keys = scratch.grid.particle_key.data();
  scratch.sorted_keys.resize(n);
  for (auto* v : {&lists.sx, &lists.sy, &lists.sz}) v->resize(n + NeighborLists::kPad);
  float* const soa_x = lists.sx.data();
  float* const soa_y = lists.sy.data();
  float* const soa_z = lists.sz.data();
  scratch.vec_a.resize(n);
  scratch.vec_b.resize(n);
  scratch.u32_tmp.resize(n);
  scratch.float_tmp.resize(n);
  scratch.pos4.resize(n);
  scratch.vel4.resize(n);
  SphScratch::SampleCarry& carry = scratch.carry;
  carry.index_tmp.resize(n);
  forEach(n, [&](std::size_t e) {
    const std::uint32_t o = order[e];
    const glm::vec3 x = store.position[o], v = store.velocity[o];
    scratch.vec_a[e] = x;
    scratch.vec_b[e] = v;
    scratch.u32_tmp[e] = store.id[o];
    scratch.float_tmp[e] = scratch.warm_kappa[o];
    scratch.pos4[e] = glm::vec4(x, 0.0f);
    scratch.vel4[e] = glm::vec4(v, 0.0f);
    scratch.sorted_keys[e] = old_keys[o];
    carry.index_tmp[e] = carry.index[o];
    soa_x[e] = x.x;
    soa_y[e] = x.y;
    soa_z[e] = x.z;
    order[e] = static_cast<std::uint32_t>(e);  // only this iteration reads order[e]
  });
  // The spray after the SPH water (spray.hpp) keeps its place.
  const std::size_t total = context.total;
  for (auto* v : {&scratch.vec_a, &scratch.vec_b}) v->resize(total);
  scratch.u32_tmp.resize(total);
  scratch.float_tmp.resize(total);
  carry.index_tmp.resize(total);
  for (std::size_t i = n; i < total; ++i) {
    scratch.vec_a[i] = store.position[i];
    scratch.vec_b[i] = store.velocity[i];
    scratch.u32_tmp[i] = store.id[i];
    scratch.float_tmp[i] = scratch.warm_kappa[i];
    carry.index_tmp[i] = carry.index[i];
  }
  store.position.swap(scratch.vec_a);
  store.velocity.swap(scratch.vec_b);
  store.id.swap(scratch.u32_tmp);
  scratch.warm_kappa.swap(scratch.float_tmp);
  carry.index.swap(carry.index_tmp);
  markGridReordered(scratch.grid, scratch.sorted_keys);
}

}  // namespace

// WCSPH keeps a Verlet list (Verlet 1967; radius H + skin) over several steps: its step is
// bounded by the sound speed, so a particle moves about 0.4 d v/c_s <= 0.04 d per step (Mach 0.1),
// and the lists (and the data order) are rebuilt only once some particle has moved skin/2 since
// the last build: no pair within H can be missing before that. Each step filters the Verlet list
// to the exact list (|x_ij| < H), so the solver sees the same pairs as with a fresh search, in a
// fixed order. DFSPH moves up to cfl d per step and rebuilds every step (skin 0).
void updateNeighbours(StepContext& context, bool store_changed) {
  SphScratch& scratch = context.scratch;
  ParticleStore& store = context.particles;
  const SphParams& params = context.params;
  const std::size_t n = context.count;
  const float support = context.support;
  const auto t_start = Clock::now();
  const float verlet_skin = params.solver == SphSolverKind::wcsph ? kWcsphSkin * support : 0.0f;
  bool rebuild = verlet_skin == 0.0f || !scratch.verlet_valid || store_changed || scratch.verlet_position.size() != n ||
                 scratch.verlet_radius != support + verlet_skin;
  if (!rebuild) {
    const float moved = reduce(
        n, 0.0f,
        [&](std::size_t i, float& acc) {
          acc = std::max(acc, glm::length(store.position[i] - scratch.verlet_position[i]));
        },
        [](float a, float b) { return std::max(a, b); });
    rebuild = !(2.0f * moved < verlet_skin);
  }
  if (rebuild) {
    // Cells 0.2 % wider than the search radius: the query then reaches one cell on each side
    // (neighborReach), with room for float slack at coordinates up to ~400 H from the origin.
    const std::span<const glm::vec3> water(store.position.data(), n);
    buildNeighborGrid(scratch.grid, water, 1.002f * (support + verlet_skin), params.domain_min,
                      params.domain_max);
    resortByCell(context, verlet_skin > 0.0f ? scratch.verlet : scratch.neighbors);
    if (verlet_skin > 0.0f) {
      findNeighbors(scratch.grid, water, support + verlet_skin, scratch.verlet, true);
      scratch.verlet_position.resize(n);
      forEach(n, [&](std::size_t i) { scratch.verlet_position[i] = store.position[i]; });
      scratch.verlet_radius = support + verlet_skin;
      scratch.verlet_valid = true;
    } else {
      findNeighbors(scratch.grid, water, support, scratch.neighbors, true);
      scratch.verlet_valid = false;
    }
  }
  context.stats.neighbor_ms = msSince(t_start);
  // Exact lists: the neighbours of i are indices[offsets[i] .. offsets[i] + counts[i]). DFSPH: the
  // fresh search (offsets[i] + counts[i] = offsets[i + 1]). WCSPH: its density pass filters each
  // particle's Verlet candidates to |x_ij| < H and writes them to the front of the same range of
  // neighbors.indices (counts in neighbors.counts), so no separate filter pass runs.
  const bool filter_verlet = verlet_skin > 0.0f;
  if (filter_verlet) {
    scratch.neighbors.offsets.assign(scratch.verlet.offsets.begin(), scratch.verlet.offsets.end());
    scratch.neighbors.counts.resize(n);
    scratch.neighbors.indices.resize(scratch.verlet.indices.size());
  }
  context.filter_verlet = filter_verlet;
  context.neighbor_offsets = scratch.neighbors.offsets.data();
  context.neighbor_counts = scratch.neighbors.counts.data();
  context.neighbor_indices = scratch.neighbors.indices.data();
  context.verlet_candidates = filter_verlet ? scratch.verlet.indices.data() : context.neighbor_indices;
  context.candidate_end = filter_verlet ? scratch.verlet.offsets.data() + 1 : context.neighbor_offsets + 1;
  // 16-byte copies of the step-start positions and velocities for the pair loops (the re-sort
  // wrote them when it ran).
  if (!rebuild) {
    scratch.pos4.resize(n);
    scratch.vel4.resize(n);
    forEach(n, [&](std::size_t i) {
      scratch.pos4[i] = glm::vec4(store.position[i], 0.0f);
      scratch.vel4[i] = glm::vec4(store.velocity[i], 0.0f);
    });
  }
}

}  // namespace fluid::sph_step
