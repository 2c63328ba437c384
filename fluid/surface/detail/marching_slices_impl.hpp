#pragma once
// Internal: the templated marching-slices core (paper Alg. 1, §3-§6) shared by
// marching_slices.cpp and fluid/surface/marching_slices_policy.hpp. Not a stable API; include
// marching_slices_policy.hpp instead.

#include "fluid/surface/detail/mesher_types.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <thread>
#include <typeindex>
#include <unordered_map>
#include <vector>

namespace fluid::detail {

// ---------------------------------------------------------------------------------------------
// The per-block algorithm, BlockMesher<Policy> (block_mesher.inl). A second copy in namespace
// avx2 is compiled for AVX2 (VEX three-operand encoding, 4-wide doubles in the cache fill) and
// chosen at run time (Setup::avx2, see runMesher). No FMA: the target is avx2 plus the integer
// BMI1/BMI2/POPCNT extensions, so every float and double operation is the same as in the portable
// copy and so are the results (a test compares both meshes bit for bit).
#include "fluid/surface/detail/block_mesher.inl"
#if defined(FLUID_SURFACE_AVX2_FILL) && defined(__GNUC__) && !defined(__clang__)
#define FLUID_SURFACE_AVX2_MESHER 1
namespace avx2 {
#pragma GCC push_options
#pragma GCC target("avx2,bmi,bmi2,popcnt")
#define FLUID_SURFACE_IN_AVX2_COPY 1  // (the target pragma does not define __AVX2__)
#include "fluid/surface/detail/block_mesher.inl"
#undef FLUID_SURFACE_IN_AVX2_COPY
#pragma GCC pop_options
}  // namespace avx2
#endif

// Runs one block with the mesher copy Setup::avx2 asks for.
template <class Policy>
void runMesher(Worker<Policy>& w, const Setup& su, const Policy& policy, BlockOut& out, bool append,
               const BlockDesc& block, std::span<const Particle> particles, BlockSeams& seams) {
#if defined(FLUID_SURFACE_AVX2_MESHER)
  if (su.avx2) {
    avx2::BlockMesher<Policy> mesher(w, su, policy, out, append);
    mesher.run(block, particles, seams);
    return;
  }
#endif
  BlockMesher<Policy> mesher(w, su, policy, out, append);
  mesher.run(block, particles, seams);
}

struct FollowWorker;  // approach 2 (baselines.hpp), defined in marching_slices.cpp

// ---------------------------------------------------------------------------------------------
struct ExtractorState {
  std::vector<Particle> particles;
  std::vector<ParticleSortKey> sortKeys;
  std::vector<StretchTerm> stretchTerms;  // SurfaceInput::stretch in the sweep frame, by input index
  struct Pair {
    std::uint64_t key;
    std::uint32_t rank;
  };
  std::vector<Pair> pairs, pairsByBlock;
  std::vector<std::uint32_t> blockCount;  // counting sort of pairs by block
  BlockSpanTables spans;  // buildBlockLists' blockSpan
  std::vector<Particle> blockParticles;
  std::vector<BlockDesc> blocks;
  std::vector<BlockOut> outs;
  BlockOut shared;  // one thread, several blocks: they append here (runBlocks), holding the mesh's arrays
  // Per-worker scratch of each policy type used with this extractor (type-erased).
  std::unordered_map<std::type_index, std::shared_ptr<void>> policyWorkers;
  std::vector<std::unique_ptr<FollowWorker>> followWorkers;
  template <class Policy>
  std::vector<std::unique_ptr<Worker<Policy>>>& workersFor() {
    using Vec = std::vector<std::unique_ptr<Worker<Policy>>>;
    std::shared_ptr<void>& slot = policyWorkers[std::type_index(typeid(Policy))];
    if (!slot) slot = std::make_shared<Vec>();
    return *static_cast<Vec*>(slot.get());
  }
  std::unique_ptr<tbb::task_arena> arena;
  int arenaThreads = 0;
  int method = 1;  // 1 = marching slices, 2 = approach 2 (baseline, see baselines.hpp)
  std::vector<std::uint32_t> vertexBase, indexBase, runBase;
  std::vector<std::uint32_t> runOrder;  // block indices, largest first (runParallelLargestFirst)
  bool firstInPlace = false;            // the mesh's arrays are in outs[0] for the run (firstBlockInPlace)
  // Seam propagation (runBlocks): per block (emission order), every block's seam squares with
  // the block that crossed them, blocks to run again, and (grid key, block) pairs sorted by key.
  std::vector<BlockSeams> seams;
  std::vector<std::pair<SeamSquare, std::uint32_t>> seamVisits;
  std::vector<std::uint32_t> rerun;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> blockByKey;
};

// Runs fn(slot, i) for i in [0, n) on the arena's workers; slot < max_concurrency identifies the
// worker (its scratch). At most n workers take part; one item (a set that fits one block) or one
// slot runs on the calling thread as slot 0, with no hand-off to a worker that would first have
// to wake up. ThreadSanitizer cannot see the synchronisation inside the uninstrumented system
// oneTBB, so TSan builds run the same per-item work on plain std::threads instead.
template <class Fn>
void parallelItems(tbb::task_arena& arena, std::size_t n, Fn&& fn) {
  const int tasks = int(std::min<std::size_t>(std::size_t(arena.max_concurrency()), n));
  if (tasks <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(0, i);
    return;
  }
#if defined(__SANITIZE_THREAD__)
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < tasks; ++t)
    pool.emplace_back([&, t] {
      for (std::size_t i = next++; i < n; i = next++) fn(t, i);
    });
  for (std::thread& th : pool) th.join();
#else
  // One task per taking part slot, each taking the next item from a shared counter as it becomes
  // free: with few, uneven items (2-4 blocks) this balances better than splitting the index range
  // in halves.
  std::atomic<std::size_t> next{0};
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(0, tasks, 1),
        [&](const tbb::blocked_range<int>&) {
          const int slot = tbb::this_task_arena::current_thread_index();
          for (std::size_t i = next++; i < n; i = next++) fn(slot, i);
        },
        tbb::simple_partitioner());
  });
#endif
}

template <class W, class Run>
void runParallel(ExtractorState& st, std::vector<std::unique_ptr<W>>& workers, Run&& run) {
  parallelItems(*st.arena, st.blocks.size(), [&](int slot, std::size_t i) { run(*workers[std::size_t(slot)], i); });
}

// Approach 1: blocks are started largest first (block particles as the cost estimate), so the
// last block to finish is a small one (longest-processing-time-first). Which thread runs a block
// never changes its output, and outputs are concatenated in emission order.
template <class W, class Run>
void runParallelLargestFirst(ExtractorState& st, std::vector<std::unique_ptr<W>>& workers, Run&& run) {
  st.runOrder.resize(st.blocks.size());
  for (std::uint32_t i = 0; i < st.runOrder.size(); ++i) st.runOrder[i] = i;
  std::sort(st.runOrder.begin(), st.runOrder.end(), [&](std::uint32_t a, std::uint32_t b) {  // no scratch buffer
    return st.blocks[a].count > st.blocks[b].count || (st.blocks[a].count == st.blocks[b].count && a < b);
  });
  parallelItems(*st.arena, st.blocks.size(),
                [&](int slot, std::size_t i) { run(*workers[std::size_t(slot)], std::size_t(st.runOrder[i])); });
}

// Which worker meets which block depends on timing, so a worker can meet a larger block than
// it has seen before in any frame. After a frame every worker's scratch is grown to the largest
// capacity any worker needed: once every block has been met by some worker, no worker allocates
// again, whatever the schedule (no allocation per frame after warm-up, for any thread count).
// Only capacities are touched; contents are rebuilt per block anyway.
template <class Policy>
void shareCapacities(std::vector<std::unique_ptr<Worker<Policy>>>& workers) {
  auto grow = [&](auto member) {
    std::size_t need = 0;
    for (const auto& w : workers) need = std::max(need, ((*w).*member).capacity());
    for (auto& w : workers) ((*w).*member).reserve(need);
  };
  grow(&Worker<Policy>::entries);
  grow(&Worker<Policy>::local);
  grow(&Worker<Policy>::rowSpans);
  grow(&Worker<Policy>::offsets);
  grow(&Worker<Policy>::splatOffsets);
  grow(&Worker<Policy>::splatCx);
  grow(&Worker<Policy>::splatInBlock);
  grow(&Worker<Policy>::splatReach);
  grow(&Worker<Policy>::splatBand);
  grow(&Worker<Policy>::splatRc2);
  grow(&Worker<Policy>::chainTouched);
  grow(&Worker<Policy>::slicePool);
  grow(&Worker<Policy>::denseIds);
  grow(&Worker<Policy>::denseBits);
  grow(&Worker<Policy>::denseCubeMask);
  for (std::size_t k = 0; k < 3; ++k) {  // the dense scan's written-slot lists
    std::size_t need = 0;
    for (const auto& w : workers) need = std::max(need, w->denseTouched[k].capacity());
    for (auto& w : workers) w->denseTouched[k].reserve(need);
  }
  // Workers share the block dimensions (Worker::resize), so todo lists and slices are alike.
  std::size_t slices = 0, corners = 0, dzs = 0, slabs = 0;
  for (const auto& w : workers) {
    slices = std::max(slices, w->slicePool.size());
    for (const auto& slice : w->slicePool) {
      corners = std::max(corners, slice->corners.capacity());
      dzs = std::max(dzs, slice->dz.capacity());
    }
    slabs = std::max(slabs, w->todo.size());
  }
  for (auto& w : workers) {
    while (w->slicePool.size() < slices) w->releaseSlice(w->acquireSliceFromNewStorage());
    for (auto& slice : w->slicePool) {
      slice->corners.reserve(corners);
      slice->dz.reserve(dzs);
    }
    w->freeSlices.reserve(slices);
  }
  for (std::size_t z = 0; z < slabs; ++z) {
    std::size_t need = 0;
    for (const auto& w : workers)
      if (z < w->todo.size()) need = std::max(need, w->todo[z].capacity());
    for (auto& w : workers)
      if (z < w->todo.size()) w->todo[z].reserve(need);
  }
}

// Whether runBlocks has the blocks append to ExtractorState::shared: one worker, several blocks,
// no exact slab order (which sorts each block's own arrays).
inline bool appendBlocks(const ExtractorState& st, const Setup& su) {
  return st.arena->max_concurrency() == 1 && st.blocks.size() > 1 && !su.exact;
}

// Whether runBlocks lets the first block in emission order write into the mesh's own arrays
// (several workers, or a single block; method 1 only). One worker with several blocks either
// appends (appendBlocks) or, with exact slab order, is gathered by appending block by block.
inline bool firstBlockInPlace(const ExtractorState& st) {
  return st.method == 1 && !st.blocks.empty() && (st.arena->max_concurrency() > 1 || st.blocks.size() == 1);
}

// Exchanges a block output's arrays with the mesh's (vertex data and indices; not the slab runs,
// which a block keeps with block-local index positions).
inline void swapMeshArrays(BlockOut& o, SurfaceMesh& out) {
  o.positions.swap(out.positions);
  o.normals.swap(out.normals);
  o.attributes.swap(out.attributes);
  o.keys.swap(out.edgeKeys);
  o.indices.swap(out.indices);
}

// A block's position in the block grid as one number (extractImpl's block key).
inline std::uint64_t gridKey(const Setup& su, int bx, int by, int bz) {
  return (std::uint64_t(bz) * std::uint64_t(su.nb[1]) + std::uint64_t(by)) * std::uint64_t(su.nb[0]) +
         std::uint64_t(bx);
}

// Seam propagation (BlockMesher::seedFromNeighbours): pairs up the seam squares the blocks'
// last runs crossed. A square crossed from one side only becomes a seed of the block on the
// other side (the corners are interior to both, so that block's march crosses it too once
// seeded). Returns whether any block got new seeds (listed in st.rerun, emission order).
inline bool collectSeamSeeds(ExtractorState& st, const Setup& su) {
  auto& all = st.seamVisits;
  all.clear();
  for (std::uint32_t i = 0; i < st.blocks.size(); ++i)
    for (const SeamSquare& sq : st.seams[i].visits) all.push_back({sq, i});
  std::sort(all.begin(), all.end());
  st.rerun.clear();
  for (std::size_t k = 0; k < all.size();) {
    std::size_t e = k + 1;
    while (e < all.size() && all[e].first == all[k].first) ++e;
    if (e - k == 1) {
      const SeamSquare& sq = all[k].first;
      const BlockDesc& from = st.blocks[all[k].second];
      int bc[3] = {from.bx, from.by, from.bz};
      const int a = sq.axis;
      bc[a] += sq.g[a] == su.lattice0[a] + std::int64_t(bc[a]) * su.b[a] ? -1 : 1;
      if (st.blockByKey.empty()) {  // (grid key, block index), built when first needed
        for (std::uint32_t i = 0; i < st.blocks.size(); ++i)
          st.blockByKey.push_back({gridKey(su, st.blocks[i].bx, st.blocks[i].by, st.blocks[i].bz), i});
        std::sort(st.blockByKey.begin(), st.blockByKey.end());
      }
      const std::uint64_t key = gridKey(su, bc[0], bc[1], bc[2]);
      const auto it = std::lower_bound(st.blockByKey.begin(), st.blockByKey.end(), std::make_pair(key, 0u));
      // The square's corners are interior to that block too, and an inside one is reached by a
      // particle, which then belongs to that block as well (blockSpan): it exists.
      assert(it != st.blockByKey.end() && it->first == key);
      std::vector<SeamSquare>& seeds = st.seams[it->second].seeds;
      // Seeded before, yet not crossed by that block's run: the two blocks disagree on the field
      // at the square's corners, which the shared lattice arithmetic rules out.
      assert(!std::binary_search(seeds.begin(), seeds.end(), sq));
      if (st.rerun.empty() || st.rerun.back() != it->second) st.rerun.push_back(it->second);
      seeds.push_back(sq);
    }
    k = e;
  }
  std::sort(st.rerun.begin(), st.rerun.end());
  st.rerun.erase(std::unique(st.rerun.begin(), st.rerun.end()), st.rerun.end());
  for (std::uint32_t i : st.rerun) std::sort(st.seams[i].seeds.begin(), st.seams[i].seeds.end());
  return !st.rerun.empty();
}

// runBlocks' one-worker pass over all blocks, appending to the mesh's arrays (appendBlocks).
template <class Policy, class Span>
void appendPass(ExtractorState& st, const Setup& su, const Policy& policy,
                std::vector<std::unique_ptr<Worker<Policy>>>& workers, SurfaceMesh& out, Span&& blockSpan) {
  BlockOut& sh = st.shared;
  // The mesh's arrays become the shared block output's for the run; the same swap hands them back.
  // The slab runs go along: appended blocks write theirs with mesh index positions. (Cleared after
  // the swap: a second pass drops what the first one appended.)
  auto swapArrays = [&] {
    swapMeshArrays(sh, out);
    sh.runs.swap(out.slabRuns);
  };
  swapArrays();
  sh.reset();
  for (std::size_t i = 0; i < st.blocks.size(); ++i) {
    runMesher(*workers[0], su, policy, sh, true, st.blocks[i], blockSpan(i), st.seams[i]);
    BlockOut& o = st.outs[i];
    o.reset();
    o.stats = sh.stats;
    o.cornerBytes = sh.cornerBytes;
    o.particleBytes = sh.particleBytes;
    o.vertexCount = sh.vertexCount;
    o.indexCount = sh.indexCount;
    o.runCount = sh.runCount;
  }
  swapArrays();
}

// `out`: the mesh, whose arrays the blocks append to directly when appendBlocks() (swapped into
// ExtractorState::shared for the run and back after it; extractImpl then copies nothing).
template <class Policy>
void runBlocks(ExtractorState& st, const Setup& su, const Policy& policy,
               std::vector<std::unique_ptr<Worker<Policy>>>& workers, SurfaceMesh& out) {
  const int slots = st.arena->max_concurrency();
  if (int(workers.size()) < slots) workers.resize(slots);
  for (auto& w : workers) {
    if (!w) w = std::make_unique<Worker<Policy>>();
    w->resize(su.n);
    w->setPlanes(su.splat, su.m, su.dense, su.valueOnly);
    w->peakBytes = 0;
  }
  if (st.seams.size() < st.blocks.size()) st.seams.resize(st.blocks.size());
  st.blockByKey.clear();
  for (std::size_t i = 0; i < st.blocks.size(); ++i) st.seams[i].seeds.clear();
  auto blockSpan = [&](std::size_t i) {
    return std::span<const Particle>(st.blockParticles.data() + st.blocks[i].first, st.blocks[i].count);
  };
  if (appendBlocks(st, su)) {
    // One thread: the blocks in emission order, each appending to the mesh's own arrays. The
    // same vertices and indices as concatenating per-block outputs (ids continue from the
    // blocks before), without the copy. When seam propagation asks for more, every block runs
    // again in turn (each with the same seeds as before but those blocks' new ones: the same output).
    do appendPass(st, su, policy, workers, out, blockSpan);
    while (collectSeamSeeds(st, su));
    return;
  }
  // Several workers (or one block): the first block in emission order writes into the mesh's own
  // arrays (its vertex ids and index positions start at 0 there too), so extractImpl neither
  // copies nor zero-fills its part; the other blocks are copied in after it (firstInPlace).
  st.firstInPlace = firstBlockInPlace(st);
  if (st.firstInPlace) swapMeshArrays(st.outs[0], out);
  runParallelLargestFirst(st, workers, [&](Worker<Policy>& w, std::size_t i) {
    runMesher(w, su, policy, st.outs[i], false, st.blocks[i], blockSpan(i), st.seams[i]);
  });
  // Seam propagation: the blocks handed seeds run again (each replaces its output) until no
  // seam square is crossed from one side only.
  while (collectSeamSeeds(st, su))
    parallelItems(*st.arena, st.rerun.size(), [&](int slot, std::size_t k) {
      const std::size_t i = st.rerun[k];
      runMesher(*workers[std::size_t(slot)], su, policy, st.outs[i], false, st.blocks[i], blockSpan(i), st.seams[i]);
    });
  if (workers.size() > 1) shareCapacities(workers);
}

inline void planBlocks(const std::vector<Particle>& ps, const SurfaceParams& params, int autoCubes, Setup& su) {
  double lo[3] = {ps[0].x, ps[0].y, ps[0].z}, hi[3] = {ps[0].x, ps[0].y, ps[0].z};
  for (const Particle& p : ps) {
    lo[0] = std::min(lo[0], p.x), hi[0] = std::max(hi[0], p.x);
    lo[1] = std::min(lo[1], p.y), hi[1] = std::max(hi[1], p.y);
    lo[2] = std::min(lo[2], p.z), hi[2] = std::max(hi[2], p.z);
  }
  // Auto: blocks of up to max(autoCubes, 12 r) cubes, r = ceil(Rc/S), keep the margins (about r
  // cubes each side, traversed but not emitted, §3) a modest share of the work; a set that fits
  // one such block is cut in two along its longest axis when both halves stay at least 5 r wide,
  // so mid-size sets still have two blocks to run in parallel. Depends on the data, S and Rc only.
  // (r, not the margin marginCubes(): the plan does not depend on the seeding's extra half cube.)
  const bool autoSize = params.blockCubes <= 0;
  const int r = std::max(1, int(std::ceil(su.rcMax / su.s)));
  const int maxBlock = autoSize ? std::max(autoCubes, 12 * r) : params.blockCubes;
  std::int64_t extent[3];
  for (int a = 0; a < 3; ++a) {
    const std::int64_t c0 = floorDiv(lo[a] - su.rcMax, su.s) - 1;
    const std::int64_t c1 = floorDiv(hi[a] + su.rcMax, su.s) + 2;
    extent[a] = std::max<std::int64_t>(1, c1 - c0);
    su.nb[a] = int((extent[a] + maxBlock - 1) / maxBlock);
    su.lattice0[a] = c0;
  }
  if (autoSize && su.nb[0] * su.nb[1] * su.nb[2] == 1) {
    int a = extent[0] >= extent[1] && extent[0] >= extent[2] ? 0 : (extent[1] >= extent[2] ? 1 : 2);
    // The dense scan's splat pays per particle and slice, then per disc row: a cut across the
    // sweep (z) splits a seam particle's slices between the halves, a cut across y its rows, a cut
    // across x every row it writes. So it cuts the first axis of z, y, x that is wide enough.
    if (su.dense)
      for (int b : {2, 1, 0})
        if ((extent[b] + 1) / 2 >= 5 * r) {
          a = b;
          break;
        }
    if ((extent[a] + 1) / 2 >= 5 * r) su.nb[a] = 2;
  }
  for (int a = 0; a < 3; ++a) {
    su.b[a] = int((extent[a] + su.nb[a] - 1) / su.nb[a]);
    su.n[a] = su.b[a] + 2 * su.m;
  }
}

// Whether the blocks sum their fields by slice splat (SurfaceFieldRoute). automatic: always, with
// the dense scan (block_dense_scan.inl): measured on the four sets (docs/surface.md, "Field
// routes"), splat plus scan does fewer instructions and takes less time than the §6 cache walk and
// than the splat with the walk on every one of them, spray's large sparse blocks included (their
// slices are cleared only where the splat wrote, and two slices are alive, so it also holds less
// memory than the cache). The choice never depends on the thread count, and all routes give the
// same vertex bits.
inline bool useSliceSplat(SurfaceFieldRoute route) {
  return route == SurfaceFieldRoute::automatic || route == SurfaceFieldRoute::sliceSplat ||
         route == SurfaceFieldRoute::denseScan || route == SurfaceFieldRoute::valueScan;
}

// Approach 2's block pass and its memory figure (marching_slices.cpp).
void runFollow(ExtractorState& st, const Setup& su);
std::uint64_t followPeakBytes(const ExtractorState& st);

// The sweep frame, flags, origin and view of one extract() call (the rest of Setup is filled by
// extractImpl from the particles: rcMax, margin, block grid, octant).
inline Setup setupFromParams(const SurfaceParams& params) {
  Setup su;
  su.s = params.cube;
  su.threshold = params.threshold;
  su.frame = chooseFrame(params);
  su.plainFrame = su.frame.axis[0] == 0 && su.frame.axis[1] == 1 && su.frame.axis[2] == 2 && su.frame.sign[0] == 1 &&
                  su.frame.sign[1] == 1 && su.frame.sign[2] == 1;
  su.flip = su.frame.flipsWinding();
  su.avx2 = detectFillAvx2(params);
  su.exact = params.order != SurfaceOrder::none && params.exactSlabOrder;
  su.origin[0] = params.originX;
  su.origin[1] = params.originY;
  su.origin[2] = params.originZ;
  {
    const float e[3] = {params.eye.x, params.eye.y, params.eye.z};
    const float d[3] = {params.viewDir.x, params.viewDir.y, params.viewDir.z};
    for (int a = 0; a < 3; ++a) {
      su.eyeRel[a] = double(e[a]) - su.origin[a];
      su.view[a] = params.order == SurfaceOrder::frontToBack ? -double(d[a]) : double(d[a]);
    }
  }
  return su;
}

// View octant in the sweep frame, for the in-cube order tables (§5).
inline int viewOctant(const SurfaceParams& params, const SweepFrame& frame) {
  const float d[3] = {params.viewDir.x, params.viewDir.y, params.viewDir.z};
  double ld[3];
  for (int a = 0; a < 3; ++a) ld[a] = frame.sign[a] * double(d[frame.axis[a]]);
  if (params.order == SurfaceOrder::frontToBack)
    for (double& v : ld) v = -v;
  return params.order == SurfaceOrder::none ? 0 : (ld[0] < 0) | ((ld[1] < 0) << 1) | ((ld[2] < 0) << 2);
}

// Block lists (§3) and the blocks' emission order (§5), into st.blocks / st.blockParticles.
inline void buildBlockLists(ExtractorState& st, const Setup& su, const SurfaceParams& params) {
  // Block lists (§3): each particle goes to every block with an interior corner within its reach
  // (blockSpan). Sorting (block, rank) pairs keeps each block's particles in (z, index) order. The
  // pairs are made in rank order, so a stable counting sort by block gives that order in one pass
  // when the block grid is not much larger than the pair list (otherwise a comparison sort).
  st.pairs.clear();
  st.spans.build(su);
  double reachRc2 = -1.0;  // particleReach of the last Rc_i^2 seen (one sqrt per distinct Rc_i)
  int reach = 0;
  for (std::uint32_t r = 0; r < st.particles.size(); ++r) {
    const Particle& p = st.particles[r];
    // valueScan also sums the corners one cube around the interior (block_value_splat.inl).
    if (p.rc2 != reachRc2) reach = particleReach(p, su.s) + int(su.valueOnly), reachRc2 = p.rc2;
    assert(reach <= su.m);  // Rc_i <= rcMax, so ceil(Rc_i / S) (+ 1) <= m (extractImpl)
    int b0[3], b1[3];
    for (int a = 0; a < 3; ++a) {
      st.spans.span(su, a, p.anchor[a], reach, b0[a], b1[a]);
      b0[a] = std::max(b0[a], 0);
      b1[a] = std::min(b1[a], su.nb[a] - 1);
    }
    for (int bz = b0[2]; bz <= b1[2]; ++bz)
      for (int by = b0[1]; by <= b1[1]; ++by)
        for (int bx = b0[0]; bx <= b1[0]; ++bx)
          st.pairs.push_back(
              {(std::uint64_t(bz) * std::uint64_t(su.nb[1]) + std::uint64_t(by)) * std::uint64_t(su.nb[0]) +
                   std::uint64_t(bx),
               r});
  }
  const std::uint64_t gridBlocks = std::uint64_t(su.nb[0]) * std::uint64_t(su.nb[1]) * std::uint64_t(su.nb[2]);
  if (gridBlocks <= 4 * std::uint64_t(st.pairs.size()) + 64) {
    st.blockCount.assign(std::size_t(gridBlocks) + 1, 0u);
    for (const ExtractorState::Pair& pr : st.pairs) ++st.blockCount[std::size_t(pr.key) + 1];
    for (std::size_t b = 1; b <= std::size_t(gridBlocks); ++b) st.blockCount[b] += st.blockCount[b - 1];
    st.pairsByBlock.resize(st.pairs.size());
    for (const ExtractorState::Pair& pr : st.pairs) st.pairsByBlock[st.blockCount[std::size_t(pr.key)]++] = pr;
    st.pairs.swap(st.pairsByBlock);
  } else {
    std::sort(st.pairs.begin(), st.pairs.end(), [](const ExtractorState::Pair& a, const ExtractorState::Pair& b) {
      return a.key < b.key || (a.key == b.key && a.rank < b.rank);
    });
  }
  st.blocks.clear();
  st.blockParticles.resize(st.pairs.size());
  for (std::size_t i = 0; i < st.pairs.size(); ++i) {
    st.blockParticles[i] = st.particles[st.pairs[i].rank];
    if (i == 0 || st.pairs[i].key != st.pairs[i - 1].key) {
      const std::uint64_t k = st.pairs[i].key;
      BlockDesc b;
      b.bx = std::int32_t(k % std::uint64_t(su.nb[0]));
      b.by = std::int32_t((k / std::uint64_t(su.nb[0])) % std::uint64_t(su.nb[1]));
      b.bz = std::int32_t(k / (std::uint64_t(su.nb[0]) * std::uint64_t(su.nb[1])));
      b.first = std::uint32_t(i);
      b.count = 0;
      b.sortKey = 0;
      st.blocks.push_back(b);
    }
    ++st.blocks.back().count;
  }
  // Emission order (§5): blocks by distance of their centre to the eye (farthest first for
  // back-to-front); ties and the plain order by lattice position.
  if (params.order != SurfaceOrder::none) {
    const float e[3] = {params.eye.x, params.eye.y, params.eye.z};
    double le[3];
    for (int a = 0; a < 3; ++a) le[a] = su.frame.sign[a] * double(e[su.frame.axis[a]]);
    for (BlockDesc& b : st.blocks) {
      const int bc[3] = {b.bx, b.by, b.bz};
      double d2 = 0;
      for (int a = 0; a < 3; ++a) {
        const double c = (double(su.lattice0[a]) + (bc[a] + 0.5) * su.b[a]) * su.s;
        d2 += (c - le[a]) * (c - le[a]);
      }
      b.sortKey = params.order == SurfaceOrder::backToFront ? -d2 : d2;
    }
    std::stable_sort(st.blocks.begin(), st.blocks.end(),
                     [](const BlockDesc& a, const BlockDesc& b) { return a.sortKey < b.sortKey; });
  }
}

// Joins the block outputs into `out` in emission order and fills the block ranges and the summed
// statistics (not the triangle, vertex and memory totals, which extractImpl sets).
// `user`: the policy has per-vertex attributes (Policy::kHasUser, method 1).
inline SurfaceStatus gatherBlocks(ExtractorState& st, const Setup& su, bool user, SurfaceMesh& out) {
  // Concatenate block outputs in emission order (prefix sums, then a parallel copy; one block's
  // buffers are swapped in whole, and one worker appends the blocks in turn, which spares the
  // zero-fill of resize()). When the blocks appended to the mesh's arrays themselves
  // (appendBlocks), only the block ranges are left to fill in; when the first block wrote into
  // them (firstInPlace), only the later blocks are appended.
  const std::size_t nb = st.blocks.size();
  const bool appended = st.method != 2 && appendBlocks(st, su);
  auto counts = [&](std::size_t i, std::uint64_t c[3]) {
    const BlockOut& o = st.outs[i];
    const bool inMesh = i == 0 && st.firstInPlace;
    c[0] = appended ? o.vertexCount : inMesh ? out.positions.size() : o.positions.size();
    c[1] = appended ? o.indexCount : inMesh ? out.indices.size() : o.indices.size();
    c[2] = appended ? o.runCount : o.runs.size();
  };
  st.vertexBase.resize(nb + 1);
  st.indexBase.resize(nb + 1);
  st.runBase.resize(nb + 1);
  st.vertexBase[0] = st.indexBase[0] = st.runBase[0] = 0;
  SurfaceStats& stats = out.stats;
  for (std::size_t i = 0; i < nb; ++i) {
    const BlockOut& o = st.outs[i];
    std::uint64_t c[3];
    counts(i, c);
    if (std::uint64_t(st.vertexBase[i]) + c[0] > 0xffffffffull ||
        std::uint64_t(st.indexBase[i]) + c[1] > 0xffffffffull) {
      out.clear();
      return {"surface: mesh exceeds 2^32 vertices or indices"};
    }
    st.vertexBase[i + 1] = st.vertexBase[i] + std::uint32_t(c[0]);
    st.indexBase[i + 1] = st.indexBase[i] + std::uint32_t(c[1]);
    st.runBase[i + 1] = st.runBase[i] + std::uint32_t(c[2]);
    stats.cubesVisited += o.stats.cubesVisited;
    stats.cornersEvaluated += o.stats.cornersEvaluated;
    stats.seedEvaluations += o.stats.seedEvaluations;
    stats.particlesLookedUp += o.stats.particlesLookedUp;
    stats.maxActiveSlices = std::max(stats.maxActiveSlices, o.stats.maxActiveSlices);
    stats.slabReversals += o.stats.slabReversals;
    stats.splatBlocks += o.stats.splatBlocks;
    stats.scannedBlocks += o.stats.scannedBlocks;
    stats.cacheBuildMs += o.stats.cacheBuildMs;
    stats.seedMs += o.stats.seedMs;
    stats.marchMs += o.stats.marchMs;
    stats.cornerCacheBytesPeakBlock = std::max(stats.cornerCacheBytesPeakBlock, o.cornerBytes);
    stats.particleCacheBytesPeakBlock = std::max(stats.particleCacheBytesPeakBlock, o.particleBytes);
  }
  // 0: parallel copy into resized arrays; 1: one block, swapped; 2: appended block by block;
  // 3: the blocks wrote into the mesh's arrays (appendBlocks); 4: block 0 wrote into them
  // (firstInPlace), the others are appended after it as in 2.
  const int gather = appended ? 3 : st.firstInPlace ? 4 : nb == 1 ? 1 : (st.arena->max_concurrency() == 1 ? 2 : 0);
  if (gather == 1) {
    BlockOut& o = st.outs[0];
    out.positions.swap(o.positions);
    out.normals.swap(o.normals);
    out.edgeKeys.swap(o.keys);
    if (user) out.attributes.swap(o.attributes);
    out.indices.swap(o.indices);  // vertex base 0: no rebasing
  } else if (gather == 2 || gather == 4) {
    // Appended in turn (4: after block 0, which is in place): insert copies without the zero-fill
    // a resize would do first, and with block 0 in place there is little left to share out.
    for (std::size_t i = gather == 4 ? 1 : 0; i < nb; ++i) {
      const BlockOut& o = st.outs[i];
      out.positions.insert(out.positions.end(), o.positions.begin(), o.positions.end());
      out.normals.insert(out.normals.end(), o.normals.begin(), o.normals.end());
      out.edgeKeys.insert(out.edgeKeys.end(), o.keys.begin(), o.keys.end());
      if (user) out.attributes.insert(out.attributes.end(), o.attributes.begin(), o.attributes.end());
      out.indices.insert(out.indices.end(), o.indices.begin(), o.indices.end());
      const std::uint32_t vb = st.vertexBase[i];
      // Local bounds and pointer: out.indices may alias st.indexBase (both uint32) as far as the
      // compiler knows, which would keep it from vectorising the loop.
      std::uint32_t* dst = out.indices.data() + st.indexBase[i];
      const std::size_t count = o.indices.size();
      for (std::size_t k = 0; k < count; ++k) dst[k] += vb;
    }
  } else if (gather == 0) {
    out.positions.resize(st.vertexBase[nb]);
    out.normals.resize(st.vertexBase[nb]);
    out.edgeKeys.resize(st.vertexBase[nb]);
    if (user) out.attributes.resize(st.vertexBase[nb]);
    out.indices.resize(st.indexBase[nb]);
  }
  out.slabRuns.resize(st.runBase[nb]);
  out.blocks.resize(nb);
  parallelItems(*st.arena, nb, [&](int, std::size_t i) {
    const BlockOut& o = st.outs[i];
    const std::uint32_t vb = st.vertexBase[i], ib = st.indexBase[i], rb = st.runBase[i];
    if (gather == 0) {
      std::copy(o.positions.begin(), o.positions.end(), out.positions.begin() + vb);
      std::copy(o.normals.begin(), o.normals.end(), out.normals.begin() + vb);
      std::copy(o.keys.begin(), o.keys.end(), out.edgeKeys.begin() + vb);
      if (user) std::copy(o.attributes.begin(), o.attributes.end(), out.attributes.begin() + vb);
      std::uint32_t* dst = out.indices.data() + ib;  // local pointers, as in the append path
      const std::uint32_t* src = o.indices.data();
      const std::size_t count = o.indices.size();
      for (std::size_t k = 0; k < count; ++k) dst[k] = src[k] + vb;
    }
    if (gather != 3)  // (appended runs are in place already, with mesh index positions)
      for (std::size_t k = 0; k < o.runs.size(); ++k) {
        SurfaceSlabRun r = o.runs[k];
        r.indices.first += ib;
        out.slabRuns[rb + k] = r;
      }
    SurfaceBlockRange& br = out.blocks[i];
    br.bx = st.blocks[i].bx;
    br.by = st.blocks[i].by;
    br.bz = st.blocks[i].bz;
    const int bc[3] = {br.bx, br.by, br.bz};
    for (int a = 0; a < 3; ++a) {
      const double c0 = double(su.lattice0[a] + std::int64_t(bc[a]) * su.b[a]) * su.s;
      const double c1 = c0 + double(su.b[a]) * su.s;
      const int wa = su.frame.axis[a];
      const double w0 = su.frame.sign[a] * c0, w1 = su.frame.sign[a] * c1;
      br.boundsMin[wa] = float(std::min(w0, w1) - su.origin[wa]);
      br.boundsMax[wa] = float(std::max(w0, w1) - su.origin[wa]);
    }
    br.indices = {ib, st.indexBase[i + 1] - ib};  // from the prefix sums: a swapped block's arrays are gone
    br.firstVertex = vb;
    br.vertexCount = st.vertexBase[i + 1] - vb;
    br.firstSlabRun = rb;
    br.slabRunCount = st.runBase[i + 1] - rb;
  });
  return {};
}

template <class Policy>
SurfaceStatus extractImpl(ExtractorState& st, const SurfaceInput& input, const SurfaceParams& params,
                          const Policy& policy, SurfaceMesh& out) {
  if constexpr (!isAnisotropic<Policy>())
    if (!input.stretch.empty()) return extractImpl(st, input, params, AnisotropicPolicy<Policy>(policy), out);
  const PhaseClock::time_point start = PhaseClock::now();
  out.clear();
  SurfaceStatus status = validateSurface(input, params);
  if (!status.ok()) return status;
  if (isAnisotropic<Policy>() && st.method == 2)
    return {"surface input: stretch (anisotropic kernels) is supported by marching slices only, not the approach-2 "
            "baseline"};

  Setup su = setupFromParams(params);

  prepareParticles(input, params, su.frame, st.particles, su.rcMax, &st.sortKeys,
                   isAnisotropic<Policy>() ? &st.stretchTerms : nullptr);
  if constexpr (isAnisotropic<Policy>()) su.stretch = st.stretchTerms.data();
  if (st.particles.empty()) return {};
  su.m = marginCubes(su.rcMax, su.s);
  // Marching slices keeps only a few slices per block, so its auto blocks can be as large as the
  // paper's (~100^3, §3): 128 cubes, where the margins cost about 15% of the cubes (64: ~30%).
  // Approach 2 holds a full 3D corner array per block, so it keeps 64 (its memory grows with the
  // cube of the block edge; 128 would make it a strawman).
  // The slice splat sums the sphere's terms only (anisotropic kernels take the §6 cache).
  su.splat = st.method != 2 && !Policy::kHasUser && !isAnisotropic<Policy>() && useSliceSplat(params.fieldRoute);
  su.dense = su.splat && params.fieldRoute != SurfaceFieldRoute::sliceSplat;
  su.valueOnly = su.dense && params.fieldRoute == SurfaceFieldRoute::valueScan;
  // Central differences read one corner beyond the interior, whose particles reach one cube
  // farther: their anchors must stay in the expanded block (blockSpan's invariant).
  if (su.valueOnly) su.m = std::max(su.m, int(std::ceil(su.rcMax / su.s)) + 1);
  planBlocks(st.particles, params, st.method == 2 ? 64 : 128, su);
  if (su.n[0] + 1 > 32000 || su.n[1] + 1 > 32000 || su.n[2] + 1 > 32000)
    return {"surface params: blockCubes + 2 ceil(rc / cube + 1/2) is too large"};
  su.octant = viewOctant(params, su.frame);

  buildBlockLists(st, su, params);
  if (st.outs.size() < st.blocks.size()) st.outs.resize(st.blocks.size());

  // 0: what the caller's task arena allows (all cores outside one; asyncMeshSlots on AsyncSurfaceExtractor's
  // worker, 1 on 2 cores).
  const int threads = surfaceThreads(params);
  if (!st.arena || st.arenaThreads != threads) {
    st.arena = std::make_unique<tbb::task_arena>(threads);
    st.arenaThreads = threads;
  }
  st.firstInPlace = false;
  const PhaseClock::time_point prepared = PhaseClock::now();
  if (st.method == 2)
    runFollow(st, su);
  else
    runBlocks(st, su, policy, st.workersFor<Policy>(), out);
  const PhaseClock::time_point meshed = PhaseClock::now();
  if (st.firstInPlace) swapMeshArrays(st.outs[0], out);  // block 0's vertices and indices, at base 0

  const bool user = Policy::kHasUser && st.method == 1;
  if (SurfaceStatus gathered = gatherBlocks(st, su, user, out); !gathered.ok()) return gathered;
  SurfaceStats& stats = out.stats;
  const std::size_t nb = st.blocks.size();
  stats.triangles = out.indices.size() / 3;
  stats.vertices = out.positions.size();
  stats.blocks = std::uint32_t(nb);
  std::uint64_t workBytes = st.method == 2 ? followPeakBytes(st) : 0;
  if (st.method != 2)
    for (auto& w : st.workersFor<Policy>())
      if (w) workBytes += w->peakBytes;
  stats.workingBytesAllWorkers = workBytes;
  stats.prepareMs = phaseMs(start, prepared);
  stats.gatherMs = phaseMs(meshed, PhaseClock::now());
  return {};
}

}  // namespace fluid::detail
