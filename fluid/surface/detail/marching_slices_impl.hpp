#pragma once
// Internal: the templated marching-slices core (paper Alg. 1, §3-§6) shared by
// marching_slices.cpp and fluid/surface/marching_slices_policy.hpp. Not a stable API; include
// marching_slices_policy.hpp instead.

#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mc_tables.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <thread>
#include <typeindex>
#include <unordered_map>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// The particle-cache fill has a 4-wide AVX2 twin of its SSE2 path, chosen at run time
// (Setup::avx2): the same double operations lane by lane (no FMA), so the same bits.
#if defined(__x86_64__) && defined(__SSE2__)
#define FLUID_SURFACE_AVX2_FILL 1
#include <immintrin.h>
#endif

namespace fluid::detail {

// ---------------------------------------------------------------------------------------------
// Policies: compile-time field/vertex routines (paper §2 "custom user-defined isosurface field and
// vertex calculation routines"). No virtual call per corner.
struct PlainPolicy {
  struct CornerData {};
  static constexpr bool kHasUser = false;
  void add(CornerData&, std::uint32_t, float) const {}
  glm::vec4 vertex(const CornerData&, const CornerData&, float) const { return {}; }
};

// Per-particle vec4 weighted by each particle's field contribution, normalised at the corner,
// then interpolated linearly along the edge like positions and normals (the paper's tentacle
// texturing: per-particle data interpolated onto the surface). Used when SurfaceInput::user is set.
struct Vec4Policy {
  struct CornerData {
    float v[4] = {0, 0, 0, 0};
    float weight = 0;
  };
  static constexpr bool kHasUser = true;
  const glm::vec4* user = nullptr;
  void add(CornerData& c, std::uint32_t particle, float w) const {
    const glm::vec4 u = user[particle];
    c.v[0] += w * u.x;
    c.v[1] += w * u.y;
    c.v[2] += w * u.z;
    c.v[3] += w * u.w;
    c.weight += w;
  }
  glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const {
    auto norm = [](const CornerData& c) { return glm::vec4(c.v[0], c.v[1], c.v[2], c.v[3]) / c.weight; };
    // A corner with no particle (weight 0) takes the other end's value.
    if (!(a.weight > 0)) return b.weight > 0 ? norm(b) : glm::vec4(0.0f);
    if (!(b.weight > 0)) return norm(a);
    const glm::vec4 va = norm(a), vb = norm(b);
    return va + t * (vb - va);
  }
};

// ---------------------------------------------------------------------------------------------
// Data structures of Figure 3 and §6.

// One element of a column list of the projection slice (§6): the particle influences corners
// min_z..max_z of this column. Lists are stored as contiguous z-sorted arrays (CSR) instead of
// doubly linked lists: the same walk, better locality. 12 bytes, so a block's cache is smaller
// than the paper's 16-byte elements (§6: "If each of these is 16 bytes"); everything else the
// field sum needs (the paper's "pointer to the particle", mid_z included) lives once per particle
// in CacheParticle, read in z order along the walk.
//
// Lookup bounds: reachMax is the largest max_z of this and every earlier element of the column,
// reachMin the smallest min_z of this and every later one (empty ranges left out). Both are
// non-decreasing along the list, so the walk for corner z can start at the first element with
// reachMax >= z and stop at the first with reachMin > z: exactly the elements the §6 window walk
// (mid_z within z -/+ ceil(Rc/S)) would return, in the same order, without stepping over the
// window's misses at either end.
//
// The range min_z..max_z is packed into one word (zKey, see columnKey) so that the walk's test
// "min_z <= z <= max_z" is one add and one mask test (coversCorner) instead of two loads, two
// subtractions and a compare per element passed.
struct ColumnEntry {
  std::uint32_t zKey;  // columnKey(min_z, max_z); 0 for an empty range (no corner falls in it)
  std::int16_t reachMax;
  std::uint16_t reachMinB;  // 0x8000 - reachMin (the stop test reachMin > z is reachMinB < 0x8000 - z)
  std::uint32_t particle8;  // 8 x (index into Worker::local): the byte offset into a slice's dz
                            // table, and a quarter of the one into Worker::local (atParticle8)
};
static_assert(sizeof(ColumnEntry) == 12);

// zKey = (max_z << 16) | (0x8000 - min_z) for 0 <= min_z <= max_z <= 31999 (the fill gives
// min_z >= 1); cornerKey(z) = ((0x8000 - z) << 16) + z for 0 <= z <= 31999. Their sum has
// (0x8000 + z - min_z) in the low half and (0x8000 + max_z - z) in the high half, each in
// [1, 0xffff] (no carry between them), so bit 15 is set iff z >= min_z and bit 31 iff z <= max_z.
// An empty key (0) leaves bit 15 clear (z < 0x8000).
inline std::uint32_t columnKey(int lo, int hi) { return (std::uint32_t(hi) << 16) | std::uint32_t(0x8000 - lo); }
inline std::uint32_t cornerKey(int z) { return (std::uint32_t(0x8000 - z) << 16) + std::uint32_t(z); }
inline bool coversCorner(std::uint32_t zKey, std::uint32_t cKey) {
  return ((zKey + cKey) & 0x80008000u) == 0x80008000u;
}

// A block's particle as the field sum reads it: the offset from the particle to local corner c
// along an axis is off[c + na] - rest with off[d] = float(d S), i.e. latticeOffset() of field.hpp
// (bit for bit), from a small table instead of a multiply and two conversions per use. The anchor
// is stored negated so the index is one add; 16 bits suffice (0 <= anchor - corner 0 <= n < 32000),
// which makes the record 32 bytes, so one never straddles two cache lines.
// The input index (user data) is read from the block's Particle records instead (same local
// index), which leaves room for 4 s, a factor of the gradient term formed once per particle.
struct CacheParticle {
  float rest[3];       // Particle::rest
  float k, s;          // 1 / (2 Rc_i^2), strength
  float s4;            // 4.0f * s (exact; the first product of accumulate()'s gradient factor)
  std::int16_t na[3];  // minus (anchor - the block's local corner 0); -mid_z for z (§6)
};
static_assert(sizeof(CacheParticle) == 32);

template <class Policy>
struct Corner {
  float value;
  float g[3];             // field gradient (normals are -g)
  std::uint32_t vert[3];  // Ix, Iy, Iz: vertex index + 1 on the edge to +x, +y, +z (0 = none)
  std::int16_t x, y;      // for clearing the index array when the slice is returned (§4)
  [[no_unique_address]] typename Policy::CornerData user;
};

struct SliceCell {
  std::uint32_t corner = 0;  // corner index + 1 (0 = not evaluated)
  std::uint8_t doneAbove = 0, doneBelow = 0;
  // Cube (x, y) of the slab above (below) this slice is already in a todo list. Not in Alg. 1:
  // it only keeps a cube from being pushed again before it is popped (the done flags still
  // decide at the pop). Every queued cube is popped before its slice can be returned, and
  // popping evaluates this cell's corner, so returning the slice clears the flag too.
  std::uint8_t queuedAbove = 0, queuedBelow = 0;
};

// Offset along z from a block particle to this slice's corners, and its square: the same for every
// column, so the field sums read them from the slice instead of working them out per lookup.
struct SliceDz {
  float dz, dz2;  // latticeOffset() along z, and dz * dz (the float product accumulate() forms)
};
static_assert(sizeof(SliceDz) == 8);

// Element i of a per-particle array of 8- or 32-byte records from p8 = 8 i: one scaled-index
// address instead of a multiply and an add per array (ColumnEntry::particle8).
template <class T>
inline const T& atParticle8(const T* base, std::uint32_t p8) {
  static_assert(sizeof(T) == 8 || sizeof(T) == 32);
  return *reinterpret_cast<const T*>(reinterpret_cast<const char*>(base) + std::size_t(p8) * (sizeof(T) / 8));
}

template <class Policy>
struct Slice {
  std::vector<SliceCell> cells;  // (Nx+1)(Ny+1) corner index array
  std::vector<Corner<Policy>> corners;
  std::vector<SliceDz> dz;  // per block particle; filled for those a lookup at this z can walk
};

struct BlockDesc {
  std::int32_t bx, by, bz;
  std::uint32_t first, count;  // into ExtractorState::blockParticles
  double sortKey;
};

// One block's output. Normally each block has its own (blocks run concurrently, then
// extractImpl concatenates them). On one thread with several blocks the blocks instead append,
// in emission order, to one shared BlockOut holding the SurfaceMesh's own arrays (see
// runBlocks: no copy), and the block's own BlockOut keeps only its counts and statistics.
struct BlockOut {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec4> attributes;
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> indices;
  std::vector<std::int32_t> triSlab;  // slab of each triangle (for runs / exact order)
  std::vector<std::uint32_t> sortScratch;
  std::vector<std::pair<float, std::uint32_t>> depthScratch;
  std::vector<SurfaceSlabRun> runs;
  SurfaceStats stats;
  std::uint64_t cornerBytes = 0, particleBytes = 0;
  // This block's vertices, indices and slab runs (also when they went to a shared BlockOut).
  std::uint32_t vertexCount = 0, indexCount = 0, runCount = 0;
  void reset() {
    positions.clear();
    normals.clear();
    attributes.clear();
    keys.clear();
    indices.clear();
    triSlab.clear();
    runs.clear();
    stats = {};
    cornerBytes = particleBytes = 0;
    vertexCount = indexCount = runCount = 0;
  }
};

// Block grid and everything else fixed for one extract() call.
struct Setup {
  double s = 1;
  float threshold = 0.2f;
  double rcMax = 3;
  int m = 3;                             // margin cubes, ceil(Rc/S) (§3)
  int b[3] = {32, 32, 32};               // interior cubes per block, per axis
  int n[3] = {38, 38, 38};               // expanded cubes per block, b + 2m
  int nb[3] = {1, 1, 1};                 // blocks per axis
  std::int64_t lattice0[3] = {0, 0, 0};  // lattice index where block 0's interior starts
  int octant = 0;
  bool exact = false;
  bool flip = false;
  SweepFrame frame;
  bool plainFrame = false;       // frame is the identity (no view ordering): cheaper vertex output
  bool avx2 = false;             // the CPU has AVX2 and SurfaceParams::portableKernels is off
  double origin[3] = {0, 0, 0};  // world origin subtracted from output positions
  double eyeRel[3] = {0, 0, 0};  // eye minus origin (world axes), for the exact in-slab order
  double view[3] = {0, 0, 1};    // view direction; depth sign flipped for front-to-back
};

// Per-worker scratch, reused across blocks and frames.
template <class Policy>
struct Worker {
  int nx = -1, ny = -1, nz = -1;  // expanded cubes per axis; corners 0..n
  std::vector<std::uint32_t> colStart, cursor;
  std::vector<std::int16_t> runMax;  // cache build: running max_z per column
  std::vector<ColumnEntry> entries;
  std::vector<CacheParticle> local;
  std::vector<std::array<std::int16_t, 2>> rowSpans;  // cache build: x0, x1 of each disc row
  std::vector<float> offsets;                         // float(d S), d in [-offsetRange, offsetRange]
  std::vector<double> cx, cy, cz;                     // corner coordinates of local indices
  std::vector<std::uint64_t> kx, ky, kz;              // edgeKey() parts of local indices
  std::vector<std::int16_t> chainLo, chainHi;         // seeding memo per column
  std::vector<std::uint32_t> chainTouched;
  std::vector<std::unique_ptr<Slice<Policy>>> slicePool;
  std::vector<Slice<Policy>*> freeSlices;
  std::vector<Slice<Policy>*> active;            // per slice z (0..nz)
  std::vector<std::vector<std::uint32_t>> todo;  // per slab z (0..nz-1)
  std::vector<std::uint32_t> slabCount;
  std::uint64_t peakBytes = 0;

  std::size_t columns() const { return std::size_t(nx + 1) * std::size_t(ny + 1); }
  void resize(const int dims[3]) {
    if (dims[0] == nx && dims[1] == ny && dims[2] == nz) return;
    nx = dims[0], ny = dims[1], nz = dims[2];
    const std::size_t cols = columns();
    colStart.assign(cols + 1, 0);
    cursor.assign(cols, 0);
    runMax.assign(cols, 0);
    cx.assign(nx + 4, 0);  // 3 past the last corner: the 4-wide fill loads cx[x .. x + 3]
    kx.assign(nx + 1, 0);
    ky.assign(ny + 1, 0);
    kz.assign(nz + 1, 0);
    cy.assign(ny + 1, 0);
    cz.assign(nz + 1, 0);
    chainLo.assign(cols, 0);
    chainHi.assign(cols, -1);
    chainTouched.clear();
    slicePool.clear();
    freeSlices.clear();
    active.assign(nz + 1, nullptr);
    todo.resize(nz);
    for (auto& t : todo) t.clear();
    slabCount.assign(nz + 1, 0);
  }

  Slice<Policy>* acquireSlice() {
    if (freeSlices.empty()) return acquireSliceFromNewStorage();
    Slice<Policy>* s = freeSlices.back();
    freeSlices.pop_back();
    return s;
  }
  // A fresh slice, added to the pool (its cells cleared).
  Slice<Policy>* acquireSliceFromNewStorage() {
    slicePool.push_back(std::make_unique<Slice<Policy>>());
    slicePool.back()->cells.assign(columns(), SliceCell{});
    return slicePool.back().get();
  }
  // Returns a slice to the pool, clearing only the entries it touched (§4).
  void releaseSlice(Slice<Policy>* s) {
    for (const Corner<Policy>& c : s->corners) s->cells[std::size_t(c.y) * std::size_t(nx + 1) + c.x] = SliceCell{};
    s->corners.clear();
    freeSlices.push_back(s);
  }
};

// Whether the particle-cache fill takes its AVX2 path (Setup::avx2).
inline bool detectFillAvx2(const SurfaceParams& params) {
#if defined(FLUID_SURFACE_AVX2_FILL)
  return !params.portableKernels && __builtin_cpu_supports("avx2");
#else
  (void)params;
  return false;
#endif
}

// Lattice origin of a block's expanded region (local corner 0).
inline void blockOrigin(const Setup& su, const BlockDesc& block, std::int64_t g0[3]) {
  const int bc[3] = {block.bx, block.by, block.bz};
  for (int a = 0; a < 3; ++a) g0[a] = su.lattice0[a] + std::int64_t(bc[a]) * su.b[a] - su.m;
}

// Vertex on the edge from corner A (lattice index gi, value va, gradient ga) along `axis` to B.
// The default vertex routine of §2: linear interpolation of position and normal. Positions in
// double from the global lattice index, so every block computes the same bits.
struct VertexOut {
  glm::vec3 position, normal;
};
// `local` = corner A's coordinates, double(gi) * S per axis (any caller computes them that way).
inline VertexOut makeVertexAt(const Setup& su, double local[3], int axis, float va, const float ga[3], float vb,
                              const float gb[3]) {
  const double tt = (double(su.threshold) - double(va)) / (double(vb) - double(va));
  local[axis] += tt * su.s;
  const float tf = float(tt);
  float g[3];
  for (int i = 0; i < 3; ++i) g[i] = ga[i] + tf * (gb[i] - ga[i]);
  const float len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  float nl[3] = {0, 0, 0};
  if (len2 > 1e-30f && std::isfinite(len2)) {
#if defined(__SSE2__)
    // The IEEE square root without std::sqrt's errno branch (len2 > 0 here).
    const float inv = -1.0f / _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(len2)));
#else
    const float inv = -1.0f / std::sqrt(len2);
#endif
    for (int i = 0; i < 3; ++i) nl[i] = g[i] * inv;
  } else {
    // Flat gradient (symmetric cancellation): point along the edge, inside -> outside.
    nl[axis] = va > su.threshold ? 1.0f : -1.0f;
  }
  if (su.plainFrame)  // the general form below with axis[a] = a, sign[a] = +1 (same bits)
    return {glm::vec3(float(local[0] - su.origin[0]), float(local[1] - su.origin[1]), float(local[2] - su.origin[2])),
            glm::vec3(nl[0], nl[1], nl[2])};
  float pos[3], nrm[3];
  for (int a = 0; a < 3; ++a) {
    const int wa = su.frame.axis[a];
    pos[wa] = float(su.frame.sign[a] * local[a] - su.origin[wa]);
    nrm[wa] = float(su.frame.sign[a]) * nl[a];
  }
  return {glm::vec3(pos[0], pos[1], pos[2]), glm::vec3(nrm[0], nrm[1], nrm[2])};
}
inline VertexOut makeVertex(const Setup& su, const std::int64_t gi[3], int axis, float va, const float ga[3], float vb,
                            const float gb[3]) {
  double local[3] = {double(gi[0]) * su.s, double(gi[1]) * su.s, double(gi[2]) * su.s};
  return makeVertexAt(su, local, axis, va, ga, vb, gb);
}

inline void buildRuns(BlockOut& out) {
  for (std::size_t i = 0; i < out.triSlab.size(); ++i) {
    const std::int32_t s = out.triSlab[i];
    if (out.runs.empty() || out.runs.back().slab != s)
      out.runs.push_back(SurfaceSlabRun{s, IndexRange{std::uint32_t(3 * i), 0}});
    out.runs.back().indices.count += 3;
  }
}

// ---------------------------------------------------------------------------------------------
// The per-block algorithm.
template <class Policy>
class BlockMesher {
 public:
  // `append`: add to `out`'s arrays after what earlier blocks put there (vertex ids and index
  // positions continue from theirs; not with exact slab order), instead of replacing them.
  BlockMesher(Worker<Policy>& w, const Setup& setup, const Policy& policy, BlockOut& out, bool append = false)
      : w_(w),
        su_(setup),
        pol_(policy),
        out_(out),
        nx_(setup.n[0]),
        ny_(setup.n[1]),
        nz_(setup.n[2]),
        stride_(setup.n[0] + 1),
        append_(append) {
    assert(!(append && setup.exact));
  }

  void run(const BlockDesc& block, std::span<const Particle> particles) {
    particles_ = particles;
    if (append_) {
      out_.stats = {};
      out_.cornerBytes = out_.particleBytes = 0;
    } else {
      out_.reset();
    }
    vertexBase_ = std::uint32_t(out_.positions.size());
    indexBase_ = out_.indices.size();
    runBase_ = out_.runs.size();
    vertexCount_ = vertexBase_;
    nIndices_ = indexBase_;
    begin(block);
    buildParticleCache(particles);
    seed(particles);
    march();
    if (su_.exact) {  // otherwise polygonize() built the runs as it went
      sortBySlab();
      buildRuns(out_);
    }
    out_.indexCount = std::uint32_t(out_.indices.size() - indexBase_);
    out_.vertexCount = std::uint32_t(out_.positions.size() - vertexBase_);
    out_.runCount = std::uint32_t(out_.runs.size() - runBase_);
    out_.stats.triangles = out_.indexCount / 3;
    out_.stats.vertices = out_.vertexCount;
    out_.particleBytes = std::uint64_t(w_.columns()) * (2 * sizeof(std::uint32_t) + sizeof(std::int16_t)) +
                         std::uint64_t(w_.entries.size()) * sizeof(ColumnEntry) +
                         std::uint64_t(w_.local.size()) * sizeof(CacheParticle) +
                         std::uint64_t(w_.rowSpans.size()) * sizeof(w_.rowSpans[0]);
    out_.cornerBytes = peakCornerBytes_;
    w_.peakBytes = std::max(w_.peakBytes, out_.particleBytes + out_.cornerBytes);
  }

  // Test hook (detail/testing.hpp): build the particle cache only, then look up corners.
  void prepareCache(const BlockDesc& block, std::span<const Particle> particles) {
    particles_ = particles;
    begin(block);
    buildParticleCache(particles);
  }
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
    found.clear();
    forEachInfluencing<false>(x, y, z, nullptr, [&](const CacheParticle& p, float, float, float, float) {
      found.push_back(indexOf(p));
      return false;
    });
  }

 private:
  Worker<Policy>& w_;
  const Setup& su_;
  const Policy& pol_;
  BlockOut& out_;
  const int nx_, ny_, nz_, stride_;
  std::int64_t g0_[3] = {0, 0, 0};
  int offsetRange_ = 0;  // offsets table half-width: m + 2 >= |corner - anchor| of any influence
  int activeSlices_ = 0;
  std::uint64_t peakCornerBytes_ = 0;
  std::span<const Particle> particles_;  // the block's particles; CacheParticle i is particles_[i]
  const bool append_;
  std::uint32_t vertexBase_ = 0;         // out_'s vertices before this block (0 unless append_)
  std::size_t indexBase_ = 0, runBase_ = 0;  // likewise its indices and slab runs
  std::uint32_t vertexCount_ = 0;        // vertex id of the next vertex (out_.positions.size())
  std::size_t nIndices_ = 0;             // used length of out_.indices while marching (polygonize)
  // The particle cache's arrays, set once it is built (they do not move while the block runs).
  const std::uint32_t* colStart_ = nullptr;
  std::uint32_t* cursor_ = nullptr;
  const ColumnEntry* entries_ = nullptr;
  const float* off0_ = nullptr;  // offsets table at d = 0
  const CacheParticle* parts_ = nullptr;
  std::uint32_t indexOf(const CacheParticle& p) const { return particles_[std::size_t(&p - w_.local.data())].index; }
  int lowestTodo_ = std::numeric_limits<int>::max();

  std::size_t col(int x, int y) const { return std::size_t(y) * std::size_t(stride_) + std::size_t(x); }

  void begin(const BlockDesc& block) {
    blockOrigin(su_, block, g0_);
    for (int i = 0; i <= nx_ + 3; ++i) w_.cx[i] = double(g0_[0] + i) * su_.s;  // + 3: padding (resize)
    for (int i = 0; i <= ny_; ++i) w_.cy[i] = double(g0_[1] + i) * su_.s;
    for (int i = 0; i <= nz_; ++i) w_.cz[i] = double(g0_[2] + i) * su_.s;
    // edgeKey(i, j, k, axis) = kx[i] | ky[j] | kz[k] | axis for the block's lattice indices.
    for (int i = 0; i <= nx_; ++i) w_.kx[i] = edgeKey(g0_[0] + i, 0, 0, 0);
    for (int i = 0; i <= ny_; ++i) w_.ky[i] = edgeKey(0, g0_[1] + i, 0, 0);
    for (int i = 0; i <= nz_; ++i) w_.kz[i] = edgeKey(0, 0, g0_[2] + i, 0);
  }

  // §6: particles arrive sorted by (z, index); insert one element per column of the projection
  // slice within Rc_i. Skip boundary columns and clamp min_z/max_z to [1, Nz-1] so the field is
  // zero on the outer boundary of the expanded block (§3) and every surface is closed.
  // Two passes over the same disc rows (count, then fill in place) build the CSR arrays directly.
  //
  // The column range of one row of the disc, widened by 1e-6 cubes against rounding; the fill
  // pass applies the exact predicate (an element whose z range comes out empty is never returned).
  struct DiscRow {
    int x0, x1;
    double dy;
  };
  DiscRow discRow(const Particle& p, int y, double inv) const {
    const double dy = w_.cy[y] - p.y;
    const double hx = std::sqrt(std::max(0.0, p.rc2 - dy * dy));
    return {std::max(1, iceil((p.x - hx) * inv - double(g0_[0]) - 1e-6)),
            std::min(nx_ - 1, ifloor((p.x + hx) * inv - double(g0_[0]) + 1e-6)), dy};
  }
  void discRows(const Particle& p, double inv, int& y0, int& y1) const {
    const double rc = std::sqrt(p.rc2);
    y0 = std::max(1, iceil((p.y - rc) * inv - double(g0_[1]) - 1e-6));
    y1 = std::min(ny_ - 1, ifloor((p.y + rc) * inv - double(g0_[1]) + 1e-6));
  }

  void buildParticleCache(std::span<const Particle> particles) {
    const std::size_t cols = w_.columns();
    const std::size_t stride = std::size_t(stride_);
    const double inv = 1.0 / su_.s;
    // Offsets float(d S): |corner - anchor| <= m + 1 for every influence (m = ceil(Rc_max / S)).
    offsetRange_ = su_.m + 2;
    w_.offsets.resize(std::size_t(2 * offsetRange_ + 1));
    for (int d = -offsetRange_; d <= offsetRange_; ++d)
      w_.offsets[std::size_t(d + offsetRange_)] = float(double(d) * su_.s);
    // Count pass as a difference array along x (two updates per disc row), then prefix sums.
    // The rows' column ranges are kept for the fill pass (rowSpans, in the same order).
    std::uint32_t* start = w_.colStart.data();
    std::fill(start, start + cols + 1, 0u);
    w_.rowSpans.clear();
    auto addRow = [&](int y, int x0, int x1) {
      w_.rowSpans.push_back({std::int16_t(x0), std::int16_t(x1)});
      if (x0 > x1) return;
      ++start[std::size_t(y) * stride + std::size_t(x0) + 1];
      --start[std::size_t(y) * stride + std::size_t(x1) + 2];  // x1 + 1 <= nx: same row
    };
    const double* cyRow = w_.cy.data();
    for (const Particle& p : particles) {
      int y0, y1;
      discRows(p, inv, y0, y1);
      int y = y0;
#if defined(__SSE2__)
      // Two rows at once: discRow()'s double expressions lane by lane, and its iceil / ifloor as
      // truncation plus the same one-step correction, so the spans come out identical.
      const __m128d vpx = _mm_set1_pd(p.x), vpy = _mm_set1_pd(p.y), vrc2 = _mm_set1_pd(p.rc2);
      const __m128d vinv = _mm_set1_pd(inv), vg0 = _mm_set1_pd(double(g0_[0])), eps = _mm_set1_pd(1e-6);
      for (; y + 1 <= y1; y += 2) {
        const __m128d dy = _mm_sub_pd(_mm_loadu_pd(cyRow + y), vpy);
        const __m128d hx = _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(vrc2, _mm_mul_pd(dy, dy)), _mm_setzero_pd()));
        const __m128d a = _mm_sub_pd(_mm_sub_pd(_mm_mul_pd(_mm_sub_pd(vpx, hx), vinv), vg0), eps);
        const __m128d b = _mm_add_pd(_mm_sub_pd(_mm_mul_pd(_mm_add_pd(vpx, hx), vinv), vg0), eps);
        const __m128i ta = _mm_cvttpd_epi32(a), tb = _mm_cvttpd_epi32(b);
        // Lane masks (all ones = -1) of a > trunc(a) and b < trunc(b), low 32 bits of each lane.
        const __m128i up =
            _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmpgt_pd(a, _mm_cvtepi32_pd(ta))), _MM_SHUFFLE(2, 0, 2, 0));
        const __m128i down =
            _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmplt_pd(b, _mm_cvtepi32_pd(tb))), _MM_SHUFFLE(2, 0, 2, 0));
        const __m128i c = _mm_sub_epi32(ta, up), f = _mm_add_epi32(tb, down);  // iceil(a), ifloor(b)
        addRow(y, std::max(1, _mm_cvtsi128_si32(c)), std::min(nx_ - 1, _mm_cvtsi128_si32(f)));
        addRow(y + 1, std::max(1, _mm_cvtsi128_si32(_mm_shuffle_epi32(c, 1))),
               std::min(nx_ - 1, _mm_cvtsi128_si32(_mm_shuffle_epi32(f, 1))));
      }
#endif
      for (; y <= y1; ++y) {
        const DiscRow r = discRow(p, y, inv);
        addRow(y, r.x0, r.x1);
      }
    }
    for (std::size_t c = 1; c <= cols; ++c) start[c] += start[c - 1];  // per-column counts
    for (std::size_t c = 1; c <= cols; ++c) start[c] += start[c - 1];  // CSR starts
    std::uint32_t* cursor = w_.cursor.data();
    std::copy(start, start + cols, cursor);
    // Running max_z per column while filling: reachMax of each element as it is written.
    std::fill(w_.runMax.begin(), w_.runMax.end(), std::int16_t(-32000));
    w_.entries.resize(start[cols]);
    w_.local.resize(particles.size());
    ColumnEntry* entries = w_.entries.data();
    const int zmax = nz_ - 1;
    const std::array<std::int16_t, 2>* span = w_.rowSpans.data();
    for (std::uint32_t li = 0; li < particles.size(); ++li) {
      const Particle& p = particles[li];
      CacheParticle& cp = w_.local[li];
      for (int a = 0; a < 3; ++a) {
        cp.rest[a] = p.rest[a];
        // Block particles lie within Rc of the interior, so their anchors are inside the
        // expanded block (margin m >= Rc / S): 0 <= a <= n.
        assert(p.anchor[a] - g0_[a] >= 0 && p.anchor[a] - g0_[a] <= su_.n[a]);
        cp.na[a] = std::int16_t(g0_[a] - p.anchor[a]);
      }
      cp.k = p.k;
      cp.s = p.strength;
      cp.s4 = 4.0f * p.strength;
      const double fz = p.z * inv - double(g0_[2]);
      // Away from the block's top and bottom (the usual case) the clamps below cannot act.
      const double reach = std::sqrt(p.rc2) * inv + 2.0;
      const bool clampFree = fz - reach >= 1.0 && fz + reach <= double(zmax);
#if defined(FLUID_SURFACE_AVX2_FILL)
      if (su_.avx2) {
        if (clampFree)
          fillDiscAvx2<false>(p, li, fz, span, entries, cursor);
        else
          fillDiscAvx2<true>(p, li, fz, span, entries, cursor);
        continue;
      }
#endif
      if (clampFree)
        fillDisc<false>(p, li, fz, span, entries, cursor);
      else
        fillDisc<true>(p, li, fz, span, entries, cursor);
    }
    assert(span == w_.rowSpans.data() + w_.rowSpans.size());
    // reachMin: suffix minimum of min_z per column (see ColumnEntry; reachMax was set by the fill).
    for (std::size_t c = 0; c < cols; ++c) {
      const std::uint32_t b = start[c], en = start[c + 1];
      if (b == en) continue;
      // The low half of a key is 0x8000 - min_z (0 when empty), so the smallest min_z is the largest
      // low half; 768 = 0x8000 - 32000 stands for "none" (reachMin 32000) and is below every real one.
      std::uint32_t run = 0x8000u - 32000u;
      for (std::uint32_t i = en; i-- > b;) {
        run = std::max(run, entries[i].zKey & 0xffffu);
        entries[i].reachMinB = std::uint16_t(run);  // 0x8000 - reachMin
      }
    }
    std::copy(start, start + cols, cursor);
    colStart_ = w_.colStart.data();
    cursor_ = w_.cursor.data();
    entries_ = w_.entries.data();
    off0_ = w_.offsets.data() + offsetRange_;
    parts_ = w_.local.data();
  }

  // Element for column x of a row: z range [lo, hi] (empty: stored as key 0 with max_z -32000),
  // reachMax from the column's running max, reachMin set after the fill.
  // `key` is columnKey(lo, hi), or 0 when empty.
  static void storeEntry(ColumnEntry* entries, std::uint32_t* rowCursor, std::int16_t* rowRun, int x,
                         std::uint32_t key, int hi, std::uint32_t li) {
    const std::int16_t rm = std::max(rowRun[x], std::int16_t(hi));
    rowRun[x] = rm;
    ColumnEntry& en = entries[rowCursor[x]++];
    en.zKey = key;
    en.reachMax = rm;
    en.particle8 = 8 * li;
  }

  // One column, scalar: the closed form, bounds near a lattice slice settled by the exact
  // predicate (influences()), so the cache returns precisely the particles within Rc_i.
  // fz = the particle's z in local cubes; dy2 = its row's dy * dy (see fillDisc).
  template <bool kClamp>
  void fillColumn(const Particle& p, std::uint32_t li, double fz, ColumnEntry* entries, std::uint32_t* rowCursor,
                  std::int16_t* rowRun, int x, double dy2) const {
    const double inv = 1.0 / su_.s;
    const double* cz = w_.cz.data();
    const int zmax = nz_ - 1;
    const double pz = p.z, rc2 = p.rc2;
    auto inside = [&](double dxy, int z) {
      const double dz = cz[z] - pz;
      return dxy + dz * dz < rc2;
    };
    const double dx = w_.cx[x] - p.x;
    const double dxy = dx * dx + dy2;
    int lo = -32000, hi = -32000;  // an empty range, which no corner (z >= 0) falls in
    if (dxy < rc2) {
      const double h = std::sqrt(rc2 - dxy) * inv;
      const double zlo = fz - h, zhi = fz + h;
      // ceil / floor without clamping first: c - 1 < zlo <= c and f <= zhi < f + 1.
      const int c = static_cast<int>(zlo) + (zlo > double(static_cast<int>(zlo)));
      const int f = static_cast<int>(zhi) - (zhi < double(static_cast<int>(zhi)));
      int l = c, u = f;
      if constexpr (kClamp) {
        // Intersect with [1, zmax] (not clamp each bound: a range wholly below 1 or above zmax,
        // possible for a particle in the outermost margin cube, must stay empty).
        l = std::max(c, 1);
        u = std::min(f, zmax);
      }  // else fz -/+ (Rc / S + 2) lies in [1, zmax], so c >= 1 and f <= zmax
      // The closed form differs from the predicate only by rounding (~1e-12 cubes); when a
      // bound is within about 1e-6 of a lattice slice (c - zlo in [0, 1) near 0 or 1, resp.
      // zhi - f), settle it with the predicate itself. Elsewhere the closed form is exact,
      // so where exactly the 1e-6 cut falls does not matter.
      // One test for both bounds; settling a bound the closed form already got right
      // leaves it unchanged, so both are settled when either is close.
      if (std::max(std::abs(double(c) - zlo - 0.5), std::abs(zhi - double(f) - 0.5)) > 0.5 - 1e-6) [[unlikely]] {
        if (l > 1 && inside(dxy, l - 1)) {
          do --l;
          while (l > 1 && inside(dxy, l - 1));
        } else {
          while (l <= u && !inside(dxy, l)) ++l;
        }
        if (u < zmax && inside(dxy, u + 1)) {
          do ++u;
          while (u < zmax && inside(dxy, u + 1));
        } else {
          while (u >= l && !inside(dxy, u)) --u;
        }
      }
      if (l <= u) {
        lo = l;
        hi = u;
      }
    }
    storeEntry(entries, rowCursor, rowRun, x, lo > -32000 ? columnKey(lo, hi) : 0u, hi, li);
  }

  // One particle's elements, row by row of its disc (rows and spans as in the count pass).
  // Without clamping (the particle is away from the block's top and bottom: fz -/+ (Rc / S + 2)
  // lies in [1, zmax]) two columns go through the closed form at once (SSE2, the same double
  // operations lane by lane); a pair with a rim column (outside the disc) or a bound that needs
  // the exact predicate takes the scalar path, column by column.
  template <bool kClamp>
  void fillDisc(const Particle& p, std::uint32_t li, double fz, const std::array<std::int16_t, 2>*& span,
                ColumnEntry* entries, std::uint32_t* cursor) {
    const double inv = 1.0 / su_.s;
    const double* cx = w_.cx.data();
    const int zmax = nz_ - 1;
    const double px = p.x, rc2 = p.rc2;
    (void)cx, (void)zmax, (void)px, (void)rc2;  // used by the SSE2 path only
    std::int16_t* runMax = w_.runMax.data();
    int y0, y1;
    discRows(p, inv, y0, y1);
    for (int y = y0; y <= y1; ++y, ++span) {
      const double dyr = w_.cy[y] - p.y;  // as discRow()
      const double dy2 = dyr * dyr;
      const std::size_t rowBase = std::size_t(y) * std::size_t(stride_);
      std::uint32_t* rowCursor = cursor + rowBase;
      std::int16_t* rowRun = runMax + rowBase;
      const int x0 = (*span)[0], x1 = (*span)[1];
      int x = x0;
#if defined(__SSE2__)
      {
        // Without clamping zlo >= 1, so truncation is floor: c = trunc(zlo) + 1 is ceil(zlo)
        // except when zlo is a whole number, where c - zlo = 1 sends the column to the scalar path
        // (settled). With clamping zlo may be below 1: then ceil(zlo) <= 1 and c <= 1 (trunc
        // rounds towards zero), both 1 after the clamp; zhi = fz + h >= 0 always.
        const __m128d vpx = _mm_set1_pd(px), vdy2 = _mm_set1_pd(dy2), vrc2 = _mm_set1_pd(rc2);
        const __m128d vinv = _mm_set1_pd(inv), vfz = _mm_set1_pd(fz), half = _mm_set1_pd(0.5);
        const __m128d cut = _mm_set1_pd(0.5 - 1e-6), absMask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffll));
        const __m128i one = _mm_set1_epi32(1);
        for (; x <= x1; x += 2) {
          // The row's last column, when alone, rides in both lanes; only lane 0 is stored.
          const bool pair = x < x1;
          const __m128d dx = _mm_sub_pd(pair ? _mm_loadu_pd(cx + x) : _mm_set1_pd(cx[x]), vpx);
          const __m128d dxy = _mm_add_pd(_mm_mul_pd(dx, dx), vdy2);
          const __m128d in = _mm_cmplt_pd(dxy, vrc2);
          const __m128d h = _mm_mul_pd(_mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(vrc2, dxy), _mm_setzero_pd())), vinv);
          const __m128d zlo = _mm_sub_pd(vfz, h), zhi = _mm_add_pd(vfz, h);
          const __m128i c = _mm_add_epi32(_mm_cvttpd_epi32(zlo), one), f = _mm_cvttpd_epi32(zhi);
          const __m128d a = _mm_and_pd(_mm_sub_pd(_mm_sub_pd(_mm_cvtepi32_pd(c), zlo), half), absMask);
          const __m128d b = _mm_and_pd(_mm_sub_pd(_mm_sub_pd(zhi, _mm_cvtepi32_pd(f)), half), absMask);
          const __m128d settle = _mm_cmpgt_pd(_mm_max_pd(a, b), cut);
          if (_mm_movemask_pd(_mm_andnot_pd(settle, in)) != 3) [[unlikely]] {
            fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x, dy2);
            if (pair) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x + 1, dy2);
            continue;
          }
          // Both columns are inside the disc with clear bounds; c <= f holds unless the range
          // holds no slice, where the element is stored empty like the scalar path does. Keys
          // (columnKey, 0 when empty) and max_z (-32000 when empty) for both lanes at once.
          __m128i cc = c, ff = f;
          if constexpr (kClamp) {  // intersect with [1, zmax], as the scalar path
            const __m128i vz = _mm_set1_epi32(zmax);
            const __m128i below1 = _mm_cmplt_epi32(cc, one), above = _mm_cmpgt_epi32(ff, vz);
            cc = _mm_or_si128(_mm_andnot_si128(below1, cc), _mm_and_si128(below1, one));
            ff = _mm_or_si128(_mm_andnot_si128(above, ff), _mm_and_si128(above, vz));
          }
          const __m128i empty = _mm_cmpgt_epi32(cc, ff);
          const __m128i key = _mm_andnot_si128(
              empty, _mm_or_si128(_mm_slli_epi32(ff, 16), _mm_sub_epi32(_mm_set1_epi32(0x8000), cc)));
          const __m128i hi = _mm_or_si128(_mm_andnot_si128(empty, ff), _mm_and_si128(empty, _mm_set1_epi32(-32000)));
          if (!pair) [[unlikely]] {
            const __m128i kh = _mm_unpacklo_epi32(key, hi);  // key0 hi0 key1 hi1
            storeEntry(entries, rowCursor, rowRun, x, std::uint32_t(_mm_cvtsi128_si32(kh)),
                       _mm_cvtsi128_si32(_mm_shuffle_epi32(kh, 1)), li);
            break;
          }
          // Columns x and x + 1 are neighbours, so their running max_z (int16) and cursors
          // (uint32) are adjacent: update both at once, then write each element's first 8 bytes
          // (key, reachMax; reachMinB is set by the suffix pass) in one store.
          std::int32_t run2;
          std::memcpy(&run2, rowRun + x, 4);
          const __m128i rm = _mm_max_epi16(_mm_cvtsi32_si128(run2), _mm_packs_epi32(hi, hi));  // reachMax x, x+1
          run2 = _mm_cvtsi128_si32(rm);
          std::memcpy(rowRun + x, &run2, 4);
          const __m128i cur = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(rowCursor + x));
          _mm_storel_epi64(reinterpret_cast<__m128i*>(rowCursor + x), _mm_sub_epi32(cur, _mm_set1_epi32(-1)));
          const __m128i kr = _mm_unpacklo_epi32(key, _mm_unpacklo_epi16(rm, _mm_setzero_si128()));  // k0 r0 k1 r1
          ColumnEntry* e0 = entries + std::uint32_t(_mm_cvtsi128_si32(cur));
          ColumnEntry* e1 = entries + std::uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(cur, 1)));
          static_assert(offsetof(ColumnEntry, reachMax) == 4 && offsetof(ColumnEntry, particle8) == 8);
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e0), kr);
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e1), _mm_unpackhi_epi64(kr, kr));
          e0->particle8 = 8 * li;
          e1->particle8 = 8 * li;
        }
        continue;
      }
#endif
      for (; x <= x1; ++x) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x, dy2);
    }
  }

#if defined(FLUID_SURFACE_AVX2_FILL)
  // fillDisc's twin for CPUs with AVX2 (Setup::avx2): four columns of a row at once, the same
  // double operations lane by lane as the SSE2 path and fillColumn (no FMA contraction: the
  // target is avx2 alone), so every element gets the same bits; a group with a column that needs
  // the scalar path sends each of its columns there, as the SSE2 path does for a pair.
  // Reads cx[x .. x + 3] (Worker::cx is padded by 3); lanes past the row's last column are
  // computed but neither stored nor counted (their running max and cursor are rewritten unchanged:
  // they lie inside the column arrays since x1 + 3 <= nx + 2 and y <= ny - 1).
  template <bool kClamp>
  [[gnu::target("avx2")]] void fillDiscAvx2(const Particle& p, std::uint32_t li, double fz,
                                           const std::array<std::int16_t, 2>*& span, ColumnEntry* entries,
                                           std::uint32_t* cursor) {
    const double inv = 1.0 / su_.s;
    const double* cx = w_.cx.data();
    const int zmax = nz_ - 1;
    std::int16_t* runMax = w_.runMax.data();
    const __m256d vpx = _mm256_set1_pd(p.x), vrc2 = _mm256_set1_pd(p.rc2), vinv = _mm256_set1_pd(inv);
    const __m256d vfz = _mm256_set1_pd(fz), half = _mm256_set1_pd(0.5), cut = _mm256_set1_pd(0.5 - 1e-6);
    const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffll));
    const __m128i one = _mm_set1_epi32(1), lanes = _mm_setr_epi32(0, 1, 2, 3);
    const __m128i none = _mm_set1_epi32(-32000);
    const std::uint32_t p8 = 8 * li;
    int y0, y1;
    discRows(p, inv, y0, y1);
    for (int y = y0; y <= y1; ++y, ++span) {
      const double dyr = w_.cy[y] - p.y;  // as discRow()
      const double dy2 = dyr * dyr;
      const std::size_t rowBase = std::size_t(y) * std::size_t(stride_);
      std::uint32_t* rowCursor = cursor + rowBase;
      std::int16_t* rowRun = runMax + rowBase;
      const int x1 = (*span)[1];
      const __m256d vdy2 = _mm256_set1_pd(dy2);
      for (int x = (*span)[0]; x <= x1; x += 4) {
        const int cnt = std::min(4, x1 - x + 1);
        const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(cx + x), vpx);
        const __m256d dxy = _mm256_add_pd(_mm256_mul_pd(dx, dx), vdy2);
        const __m256d in = _mm256_cmp_pd(dxy, vrc2, _CMP_LT_OS);
        const __m256d h =
            _mm256_mul_pd(_mm256_sqrt_pd(_mm256_max_pd(_mm256_sub_pd(vrc2, dxy), _mm256_setzero_pd())), vinv);
        const __m256d zlo = _mm256_sub_pd(vfz, h), zhi = _mm256_add_pd(vfz, h);
        const __m128i c = _mm_add_epi32(_mm256_cvttpd_epi32(zlo), one), f = _mm256_cvttpd_epi32(zhi);
        const __m256d a = _mm256_and_pd(_mm256_sub_pd(_mm256_sub_pd(_mm256_cvtepi32_pd(c), zlo), half), absMask);
        const __m256d b = _mm256_and_pd(_mm256_sub_pd(_mm256_sub_pd(zhi, _mm256_cvtepi32_pd(f)), half), absMask);
        const __m256d settle = _mm256_cmp_pd(_mm256_max_pd(a, b), cut, _CMP_GT_OS);
        const int want = (1 << cnt) - 1;
        if ((_mm256_movemask_pd(_mm256_andnot_pd(settle, in)) & want) != want) [[unlikely]] {
          for (int l = 0; l < cnt; ++l) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x + l, dy2);
          continue;
        }
        __m128i cc = c, ff = f;
        if constexpr (kClamp) {  // intersect with [1, zmax], as the scalar path
          const __m128i vz = _mm_set1_epi32(zmax);
          cc = _mm_max_epi32(cc, one);
          ff = _mm_min_epi32(ff, vz);
        }
        const __m128i empty = _mm_cmpgt_epi32(cc, ff);
        const __m128i key =
            _mm_andnot_si128(empty, _mm_or_si128(_mm_slli_epi32(ff, 16), _mm_sub_epi32(_mm_set1_epi32(0x8000), cc)));
        // max_z, or -32000 for an empty range and for the lanes past the row's end (a no-op in
        // the running max below).
        const __m128i active = _mm_cmpgt_epi32(_mm_set1_epi32(cnt), lanes);
        const __m128i hi = _mm_blendv_epi8(none, ff, _mm_andnot_si128(empty, active));
        const __m128i rm = _mm_max_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(rowRun + x)),
                                         _mm_packs_epi32(hi, hi));  // reachMax of columns x .. x + 3
        _mm_storel_epi64(reinterpret_cast<__m128i*>(rowRun + x), rm);
        const __m128i cur = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rowCursor + x));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(rowCursor + x), _mm_sub_epi32(cur, active));
        const __m128i r32 = _mm_unpacklo_epi16(rm, _mm_setzero_si128());
        const __m128i kr01 = _mm_unpacklo_epi32(key, r32), kr23 = _mm_unpackhi_epi32(key, r32);  // k0 r0 k1 r1, k2 r2 k3 r3
        ColumnEntry* e = entries + std::uint32_t(_mm_cvtsi128_si32(cur));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(e), kr01);
        e->particle8 = p8;
        if (cnt > 1) {
          e = entries + std::uint32_t(_mm_extract_epi32(cur, 1));
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e), _mm_unpackhi_epi64(kr01, kr01));
          e->particle8 = p8;
          if (cnt > 2) {
            e = entries + std::uint32_t(_mm_extract_epi32(cur, 2));
            _mm_storel_epi64(reinterpret_cast<__m128i*>(e), kr23);
            e->particle8 = p8;
            if (cnt > 3) {
              e = entries + std::uint32_t(_mm_extract_epi32(cur, 3));
              _mm_storel_epi64(reinterpret_cast<__m128i*>(e), _mm_unpackhi_epi64(kr23, kr23));
              e->particle8 = p8;
            }
          }
        }
      }
    }
  }
#endif

  // The start-pointer update of §6 for column k (entries [begin, end)): moves the column's
  // cursor to the first element whose reach covers z and returns it. reachMax is non-decreasing,
  // so the pointer may skip 8 elements at once when the one 8 away is still on the same side
  // (long moves happen when the sweep jumps between surfaces).
  std::uint32_t seekColumn(std::size_t k, std::uint32_t begin, std::uint32_t end, int z) {
    std::uint32_t cur = cursor_[k];
    const ColumnEntry* e = entries_;
    while (cur > begin && e[cur - 1].reachMax >= z) {
      if (cur >= begin + 9 && e[cur - 9].reachMax >= z)
        cur -= 9;
      else
        --cur;
    }
    while (cur < end && e[cur].reachMax < z) {
      if (cur + 8 < end && e[cur + 8].reachMax < z)
        cur += 9;
      else
        ++cur;
    }
    cursor_[k] = cur;
    return cur;
  }

  // §6 lookup: from the column's start pointer find the bottom-most entry that can reach z
  // (reachMax >= z; the paper's mid_z >= z - window, tightened), walk up while entries can still
  // reach it (reachMin <= z; the paper's mid_z <= z + window), keep min_z <= z <= max_z, and leave
  // the start pointer at the first entry found. f(particle, dx, dy, dz) is called in (z, index)
  // order with the offsets from the particle to the corner (field.hpp's latticeOffset(), bit for
  // bit); the walk stops early when f returns true.
  // With kTable the offsets along z come from the slice's table (dzt, see fillSliceDz), else from
  // the offsets table; f(particle, dx, dy, dz, dz * dz).
  template <bool kTable, class F>
  void forEachInfluencing(int x, int y, int z, const SliceDz* dzt, F&& f) {
    const std::size_t k = col(x, y);
    const std::uint32_t begin = colStart_[k], end = colStart_[k + 1];
    if (begin == end) return;
    const std::uint32_t cur = seekColumn(k, begin, end, z);
    const ColumnEntry* e = entries_;
    const float* off = off0_;
    const float* offX = off + x;
    const float* offY = off + y;
    const float* offZ = off + z;
    const CacheParticle* parts = parts_;
    const std::uint32_t ck = cornerKey(z);
    const unsigned zb = 0x8000u - unsigned(z);
    for (std::uint32_t i = cur; i < end; ++i) {
      const ColumnEntry& en = e[i];
      if (en.reachMinB < zb) break;  // reachMin > z
      if (!coversCorner(en.zKey, ck)) continue;  // min_z <= z <= max_z
      const CacheParticle& p = atParticle8(parts, en.particle8);
      float dz, dz2;
      if constexpr (kTable) {
        const SliceDz& d = atParticle8(dzt, en.particle8);
        dz = d.dz;
        dz2 = d.dz2;
      } else {
        dz = offZ[p.na[2]] - p.rest[2];
        dz2 = dz * dz;
      }
      if (f(p, offX[p.na[0]] - p.rest[0], offY[p.na[1]] - p.rest[1], dz, dz2)) break;
    }
  }

  template <bool kGradient>
  void evaluate(int x, int y, int z, const SliceDz* dzt, Corner<Policy>& c) {
    float v = 0, gx = 0, gy = 0, gz = 0;
    std::uint64_t looked = 0;
    c.user = {};
    if constexpr (!kGradient && !Policy::kHasUser) {
      // Margin corner: only the sign of f - T is ever read (§3), so stop as soon as the sum
      // passes T (see insideAt).
      v = sumUntilAbove<true>(x, y, z, dzt, looked);
    } else {
      forEachInfluencing<true>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float dz, float dz2) {
        ++looked;
        const float before = v;
        accumulateDz2S4(dx, dy, dx * dx + dy * dy, dz, dz2, p.k, p.s, p.s4, v, gx, gy, gz);
        if constexpr (Policy::kHasUser) pol_.add(c.user, indexOf(p), v - before);
        return false;
      });
    }
    out_.stats.particlesLookedUp += looked;
    c.value = v;
    c.g[0] = gx;
    c.g[1] = gy;
    c.g[2] = gz;
  }

  // The field summed in (z, index) order, stopped as soon as the partial sum exceeds T. Every
  // term is >= 0 and rounded float addition is monotone, so a partial sum above T proves the full
  // sum above T, and a sum that never passes T is the full sum: (result > T) == (f > T) exactly.
  template <bool kTable>
  float sumUntilAbove(int x, int y, int z, const SliceDz* dzt, std::uint64_t& looked) {
    const float t = su_.threshold;
    float v = 0;
    forEachInfluencing<kTable>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float, float dz2) {
      ++looked;
      v += contributionDz2(dx * dx + dy * dy, dz2, p.k, p.s);
      return v > t;
    });
    return v;
  }

  // Seeding only asks whether a corner is inside (§4).
  bool insideAt(int x, int y, int z) {
    std::uint64_t looked = 0;
    ++out_.stats.seedEvaluations;
    return sumUntilAbove<false>(x, y, z, nullptr, looked) > su_.threshold;
  }

  bool interiorCorner(int x, int y, int z) const {
    // m <= v <= m + b per axis, as one unsigned compare each.
    const int m = su_.m;
    return (unsigned(x - m) <= unsigned(su_.b[0])) & (unsigned(y - m) <= unsigned(su_.b[1])) &
           (unsigned(z - m) <= unsigned(su_.b[2]));
  }

  // Seeding (§4): snap each particle to its nearest corner and step down -z until the field is
  // at or below T; push the cube whose vertical edge holds the crossing into that slab's todo.
  // Stop after Rc_i. A per-column memo of the inside corners already walked lets a later
  // particle stop as soon as its descent reaches one (same connected inside run: same seed).
  void seed(std::span<const Particle> particles) {
    for (std::uint32_t c : w_.chainTouched) {
      w_.chainLo[c] = 0;
      w_.chainHi[c] = -1;
    }
    w_.chainTouched.clear();
    const double inv = 1.0 / su_.s;
    const float t = su_.threshold;
    for (const Particle& p : particles) {
      const int x = iround(p.x * inv - double(g0_[0]));
      const int y = iround(p.y * inv - double(g0_[1]));
      const int z0 = iround(p.z * inv - double(g0_[2]));
      if (x < 1 || x > nx_ - 1 || y < 1 || y > ny_ - 1 || z0 < 1 || z0 > nz_ - 1) continue;
      const std::size_t k = col(x, y);
      if (z0 >= w_.chainLo[k] && z0 <= w_.chainHi[k]) continue;
      // The field is a sum of non-negative terms, so the particle's own term above T already
      // proves its nearest corner inside (no lookup needed); otherwise evaluate.
      const float ox = latticeOffset(g0_[0] + x, p.anchor[0], p.rest[0], su_.s);
      const float oy = latticeOffset(g0_[1] + y, p.anchor[1], p.rest[1], su_.s);
      const float oz = latticeOffset(g0_[2] + z0, p.anchor[2], p.rest[2], su_.s);
      const bool ownInside =
          influences(p, w_.cx[x], w_.cy[y], w_.cz[z0]) && contribution(ox * ox + oy * oy, oz, p.k, p.strength) > t;
      if (!ownInside && !insideAt(x, y, z0)) continue;  // nearest corner outside: no seed here
      const int steps = iceil(std::sqrt(p.rc2) * inv) + 1;
      int z = z0;
      bool joined = false;
      for (int i = 0; i < steps && z > 0; ++i) {
        const int below = z - 1;
        if (below >= w_.chainLo[k] && below <= w_.chainHi[k]) {
          joined = true;
          break;
        }
        // As at the start: the particle's own term above T proves the corner inside.
        const float ozb = latticeOffset(g0_[2] + below, p.anchor[2], p.rest[2], su_.s);
        const bool ownBelow = below >= 1 && influences(p, w_.cx[x], w_.cy[y], w_.cz[below]) &&
                              contribution(ox * ox + oy * oy, ozb, p.k, p.strength) > t;
        if (!ownBelow && !insideAt(x, y, below)) {
          pushTodo(below, x, y);
          joined = true;
          break;
        }
        z = below;
      }
      if (!joined) continue;  // went Rc down without leaving: a particle below seeds it (§4)
      // Keep one walked run [z, z0] per column: merge when it touches the old one, else replace
      // (a gap between two runs is not known to be inside).
      if (w_.chainHi[k] < w_.chainLo[k]) w_.chainTouched.push_back(std::uint32_t(k));
      if (w_.chainHi[k] >= w_.chainLo[k] && z <= w_.chainHi[k] + 1 && z0 >= w_.chainLo[k] - 1) {
        w_.chainLo[k] = std::int16_t(std::min<int>(w_.chainLo[k], z));
        w_.chainHi[k] = std::int16_t(std::max<int>(w_.chainHi[k], z0));
      } else {
        w_.chainLo[k] = std::int16_t(z);
        w_.chainHi[k] = std::int16_t(z0);
      }
    }
  }

  void pushTodo(int slab, int x, int y) {
    w_.todo[slab].push_back(std::uint32_t(x) | (std::uint32_t(y) << 16));
    lowestTodo_ = std::min(lowestTodo_, slab);
  }

  // A lookup at slice z walks only particles whose anchor lies within m + 1 slices of z (every
  // element it passes has mid_z within ceil(Rc/S) = m of z, see forEachInfluencing, and the
  // anchor is floor(mid_z) up to rounding), a contiguous run of the z-sorted block particles; the
  // run for m + 2 (the offsets table's reach) is tabulated, one slice of slack.
  void fillSliceDz(Slice<Policy>& slice, int z) {
    const std::size_t n = w_.local.size();
    slice.dz.resize(n);
    const CacheParticle* parts = w_.local.data();
    // -na[2] = anchor - corner 0 along z, non-decreasing in the local index.
    const int lo = z - offsetRange_, hi = z + offsetRange_;  // offsetRange_ = m + 2
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < lo; });
    const float* offZ = w_.offsets.data() + offsetRange_ + z;
    SliceDz* out = slice.dz.data();
    for (const CacheParticle* p = first; p != parts + n && -int(p->na[2]) <= hi; ++p) {
      const float dz = offZ[p->na[2]] - p->rest[2];
      out[p - parts] = {dz, dz * dz};
    }
  }

  Slice<Policy>* ensureSlice(int z) {
    if (!w_.active[z]) {
      w_.active[z] = w_.acquireSlice();
      fillSliceDz(*w_.active[z], z);
      ++activeSlices_;
      out_.stats.maxActiveSlices = std::max<std::uint32_t>(out_.stats.maxActiveSlices, activeSlices_);
    }
    return w_.active[z];
  }
  void freeSlice(int z) {
    if (!w_.active[z]) return;
    // Every evaluated corner sits in exactly one slice's corner cache until the slice is
    // returned (all are by the end of march()): count them here rather than per evaluation.
    out_.stats.cornersEvaluated += w_.active[z]->corners.size();
    w_.releaseSlice(w_.active[z]);
    w_.active[z] = nullptr;
    --activeSlices_;
  }
  void notePeak(int z) {
    // Active slices are z, z+1 and any abandoned below after a reversal; count all of them.
    std::uint64_t bytes = 0;
    for (int i = 0; i <= nz_; ++i)
      if (w_.active[i])
        bytes += w_.active[i]->cells.size() * sizeof(SliceCell) +
                 w_.active[i]->corners.size() * sizeof(Corner<Policy>) + w_.active[i]->dz.size() * sizeof(SliceDz);
    (void)z;
    peakCornerBytes_ = std::max(peakCornerBytes_, bytes);
  }

  // Alg. 1 lookupOrEval: the corner's index in the slice's corner cache, evaluated on first use.
  // `interior`: the caller knows the corner is interior (a corner of an emitted cube).
  std::uint32_t lookupOrEval(Slice<Policy>& slice, SliceCell& cell, int x, int y, int z, bool interior) {
    const std::uint32_t id = cell.corner;
    if (id) [[likely]]
      return id - 1;
    return evaluateInto(slice, cell, x, y, z, interior) - 1;
  }

  // lookupOrEval for a corner of the lower slice (z) whose twin one slice up (z + 1, same column)
  // the cube needs as well: when neither is cached yet, both come from one walk of the column.
  std::uint32_t lookupOrEvalLow(Slice<Policy>& lo, SliceCell& cellLo, Slice<Policy>& hi, SliceCell& cellHi, int x,
                                int y, int z, bool interior) {
    const std::uint32_t id = cellLo.corner;
    if (id) [[likely]]
      return id - 1;
    if constexpr (!Policy::kHasUser) {
      if (!cellHi.corner && (interior || (interiorCorner(x, y, z) && interiorCorner(x, y, z + 1))))
        return evaluatePairInto(lo, cellLo, hi, cellHi, x, y, z) - 1;
    }
    return evaluateInto(lo, cellLo, x, y, z, interior) - 1;
  }

  // Two interior corners of one column, (x, y, z) and (x, y, z + 1), from one §6 walk: the walk
  // for z + 1 starts at or after the one for z (reachMax is non-decreasing) and stops at or after
  // it (reachMin is too), so walking from z's start to z + 1's stop passes every element of both
  // in the same (z, index) order. Each corner adds exactly the terms, in exactly the order and
  // with exactly the float expressions, of evaluate<true>: the same bits as two separate calls,
  // while the walk, the particle record and the x, y offsets are shared (about a third of the
  // evaluated corners come in such pairs: horizontal stretches of surface). Returns the lower
  // corner's index + 1 (the upper one is cached in its slice).
  // Scalar sums: GCC's SLP vectoriser would pack each corner's four sums into one register and
  // repack them on every term (about 10 more instructions per term for the second corner).
  [[gnu::noinline, gnu::optimize("no-tree-slp-vectorize")]] std::uint32_t evaluatePairInto(Slice<Policy>& lo, SliceCell& cellLo, Slice<Policy>& hi,
                                                   SliceCell& cellHi, int x, int y, int z) {
    float v0 = 0, gx0 = 0, gy0 = 0, gz0 = 0, v1 = 0, gx1 = 0, gy1 = 0, gz1 = 0;
    std::uint64_t looked = 0;
    const std::size_t k = col(x, y);
    const std::uint32_t begin = colStart_[k], end = colStart_[k + 1];
    if (begin != end) {
      const std::uint32_t cur = seekColumn(k, begin, end, z);  // start of z's walk
      const ColumnEntry* e = entries_;
      const float* off = off0_;
      const float* offX = off + x;
      const float* offY = off + y;
      const CacheParticle* parts = parts_;
      const SliceDz* dzLo = lo.dz.data();
      const SliceDz* dzHi = hi.dz.data();
      const int z1 = z + 1;
      const std::uint32_t ck0 = cornerKey(z), ck1 = cornerKey(z1);
      const unsigned zb1 = 0x8000u - unsigned(z1);
      for (std::uint32_t i = cur; i < end; ++i) {
        const ColumnEntry& en = e[i];
        if (en.reachMinB < zb1) break;  // reachMin > z + 1
        const bool in0 = coversCorner(en.zKey, ck0), in1 = coversCorner(en.zKey, ck1);
        if (!(in0 | in1)) continue;
        const std::uint32_t pi = en.particle8;
        const CacheParticle& p = atParticle8(parts, pi);
        const float dx = offX[p.na[0]] - p.rest[0], dy = offY[p.na[1]] - p.rest[1];
        const float dxy2 = dx * dx + dy * dy;
        if (in0) {
          ++looked;
          const SliceDz& d = atParticle8(dzLo, pi);
          accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v0, gx0, gy0, gz0);
        }
        if (in1) {
          ++looked;
          const SliceDz& d = atParticle8(dzHi, pi);
          accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v1, gx1, gy1, gz1);
        }
      }
    }
    out_.stats.particlesLookedUp += looked;
    Corner<Policy> c;
    c.user = {};
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.x = std::int16_t(x);
    c.y = std::int16_t(y);
    auto store = [&c](Slice<Policy>& slice, SliceCell& cell, float v, float gx, float gy, float gz) {
      c.value = v;
      c.g[0] = gx;
      c.g[1] = gy;
      c.g[2] = gz;
      slice.corners.push_back(c);
      cell.corner = std::uint32_t(slice.corners.size());
    };
    store(hi, cellHi, v1, gx1, gy1, gz1);
    store(lo, cellLo, v0, gx0, gy0, gz0);
    return cellLo.corner;
  }

  // Evaluates corner (x, y, z) into the slice's corner cache; returns its index + 1. Not inlined:
  // one out-of-line copy keeps the march loop small (most corners are already cached).
  [[gnu::noinline]] std::uint32_t evaluateInto(Slice<Policy>& slice, SliceCell& cell, int x, int y, int z,
                                               bool interior) {
    Corner<Policy> c;
    if (interior || interiorCorner(x, y, z))
      evaluate<true>(x, y, z, slice.dz.data(), c);
    else
      evaluate<false>(x, y, z, slice.dz.data(), c);  // margin: only the sign is needed (§3)
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.x = std::int16_t(x);
    c.y = std::int16_t(y);
    slice.corners.push_back(c);
    cell.corner = std::uint32_t(slice.corners.size());
    return cell.corner;
  }

  // Alg. 1 main loop.
  void march() {
    const float t = su_.threshold;
    const auto& table = mc::tables().cases[su_.octant];
    const int ia = su_.m, ibx = su_.m + su_.b[0], iby = su_.m + su_.b[1], ibz = su_.m + su_.b[2];
    int z = lowestTodo_;
    while (true) {
      while (z < nz_ && w_.todo[z].empty()) ++z;  // lowest slab with work
      if (z >= nz_) break;
      Slice<Policy>* below = ensureSlice(z);
      Slice<Policy>* above = ensureSlice(z + 1);
      auto& list = w_.todo[z];
      const bool interiorSlab = z >= ia && z < ibz;
      // The index arrays never move while the slices are active; the corner arrays may grow
      // (evaluateInto), so corner pointers are taken after the cube's evaluations.
      SliceCell* const cellsB = below->cells.data();
      SliceCell* const cellsA = above->cells.data();
      const std::size_t sy = std::size_t(stride_);
      const std::size_t slabFirst = nIndices_;
      while (!list.empty()) {
        const std::uint32_t item = list.back();
        list.pop_back();
        const int x = int(item & 0xffff), y = int(item >> 16);
        const std::size_t c0 = col(x, y);
        SliceCell& cb = cellsB[c0];
        SliceCell& ca = cellsA[c0];
        if (cb.doneAbove || ca.doneBelow) continue;
        cb.doneAbove = 1;
        ca.doneBelow = 1;
        ++out_.stats.cubesVisited;
        // A cube of the block's interior (the ones polygonize() emits): all eight corners interior.
        const bool emit = interiorSlab && x >= ia && x < ibx && y >= ia && y < iby;
        std::uint32_t ci[8];
        ci[0] = lookupOrEvalLow(*below, cellsB[c0], *above, cellsA[c0], x, y, z, emit);
        ci[1] = lookupOrEvalLow(*below, cellsB[c0 + 1], *above, cellsA[c0 + 1], x + 1, y, z, emit);
        ci[2] = lookupOrEvalLow(*below, cellsB[c0 + sy], *above, cellsA[c0 + sy], x, y + 1, z, emit);
        ci[3] = lookupOrEvalLow(*below, cellsB[c0 + sy + 1], *above, cellsA[c0 + sy + 1], x + 1, y + 1, z, emit);
        ci[4] = lookupOrEval(*above, cellsA[c0], x, y, z + 1, emit);
        ci[5] = lookupOrEval(*above, cellsA[c0 + 1], x + 1, y, z + 1, emit);
        ci[6] = lookupOrEval(*above, cellsA[c0 + sy], x, y + 1, z + 1, emit);
        ci[7] = lookupOrEval(*above, cellsA[c0 + sy + 1], x + 1, y + 1, z + 1, emit);
        Corner<Policy>* const cornersB = below->corners.data();
        Corner<Policy>* const cornersA = above->corners.data();
        Corner<Policy>* cp[8];
        for (int i = 0; i < 4; ++i) cp[i] = cornersB + ci[i];
        for (int i = 4; i < 8; ++i) cp[i] = cornersA + ci[i];
#if defined(__SSE2__)
        // The case index: bit i set when corner i is inside, as two 4-wide compares.
        const __m128 lo = _mm_setr_ps(cp[0]->value, cp[1]->value, cp[2]->value, cp[3]->value);
        const __m128 hi = _mm_setr_ps(cp[4]->value, cp[5]->value, cp[6]->value, cp[7]->value);
        const __m128 tv = _mm_set1_ps(t);
        const unsigned cube =
            unsigned(_mm_movemask_ps(_mm_cmpgt_ps(lo, tv))) | (unsigned(_mm_movemask_ps(_mm_cmpgt_ps(hi, tv))) << 4);
#else
        unsigned cube = 0;
        for (int i = 0; i < 8; ++i) cube |= unsigned(cp[i]->value > t) << i;
#endif
        if (cube == 0 || cube == 255) continue;
        const mc::CaseTable& cs = table[cube];
        if (emit) polygonize(cs, cp, x, y, z);
        // Push neighbours across crossed faces unless done (Alg. 1).
        const unsigned f = cs.faceMask;
        auto pushIn = [&](SliceCell& n, std::uint32_t next) {
          if (!(n.doneAbove | n.queuedAbove)) {
            n.queuedAbove = 1;
            list.push_back(next);
          }
        };
        if (f & 1) pushIn(cellsB[c0 - 1], item - 1);
        if (f & 2) pushIn(cellsB[c0 + 1], item + 1);
        if (f & 4) pushIn(cellsB[c0 - sy], item - (1u << 16));
        if (f & 8) pushIn(cellsB[c0 + sy], item + (1u << 16));
        if ((f & 16) && !(cb.doneBelow | cb.queuedBelow)) {
          assert(z > 0);
          cb.queuedBelow = 1;
          w_.todo[z - 1].push_back(item);
        }
        if ((f & 32) && !(ca.doneAbove | ca.queuedAbove)) {
          assert(z + 1 < nz_);
          ca.queuedAbove = 1;
          w_.todo[z + 1].push_back(item);
        }
      }
      closeSlabVisit(z, slabFirst);
      notePeak(z);
      // Return slices no neighbouring slab still needs (Alg. 1, end of the slab).
      const bool belowEmpty = z == 0 || w_.todo[z - 1].empty();
      const bool aboveEmpty = z + 1 >= nz_ || w_.todo[z + 1].empty();
      if (belowEmpty) freeSlice(z);
      if (aboveEmpty) freeSlice(z + 1);
      if (!belowEmpty) {  // the sweep reverses: slab z-1 got work from this one (Fig. 4)
        --z;
        ++out_.stats.slabReversals;
      }
    }
    for (int i = 0; i <= nz_; ++i) freeSlice(i);
    out_.indices.resize(nIndices_);  // drop the unused tail of the last step (polygonize)
    lowestTodo_ = std::numeric_limits<int>::max();
  }

  std::uint32_t vertexOn(Corner<Policy>* cp[8], int edge, int x, int y, int z) {
    const int base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
    Corner<Policy>& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const Corner<Policy>& cb = *cp[base | (1 << axis)];
    const int lx = x + (base & 1), ly = y + ((base >> 1) & 1), lz = z + (base >> 2);
    double local[3] = {w_.cx[lx], w_.cy[ly], w_.cz[lz]};  // double(g0 + l) * S, see begin()
    const VertexOut v = makeVertexAt(su_, local, axis, ca.value, ca.g, cb.value, cb.g);
    out_.positions.push_back(v.position);
    out_.normals.push_back(v.normal);
    if constexpr (Policy::kHasUser) {
      const float tf = (su_.threshold - ca.value) / (cb.value - ca.value);
      out_.attributes.push_back(pol_.vertex(ca.user, cb.user, tf));
    }
    out_.keys.push_back(w_.kx[lx] | w_.ky[ly] | w_.kz[lz] | std::uint64_t(axis));  // edgeKey(g0 + l, axis)
    const std::uint32_t id = vertexCount_++;  // == out_.positions.size() - 1
    ca.vert[axis] = id + 1;
    return id;
  }

  // Each crossed edge's vertex is looked up (or made) once per cube, in first-use order along the
  // case's triangles (the order walking the triangles would make them in), then the triangles
  // are written from those.
  void polygonize(const mc::CaseTable& cs, Corner<Policy>* cp[8], int x, int y, int z) {
    std::uint32_t vid[12];
    const int ne = cs.edgeCount;
    for (int u = 0; u < ne; ++u) vid[u] = vertexOn(cp, cs.firstUse[u], x, y, z);
    const int nt = cs.triangleCount;
    // out_.indices is grown ahead in steps of 256 (one bulk zero-fill instead of a resize per
    // cube); nIndices_ is its used length, and march() trims it to that at the end.
    const std::size_t first = nIndices_;
    if (out_.indices.size() < first + 36) [[unlikely]]
      out_.indices.resize(first + 256 + 36);  // 36 = 3 x the most triangles of one case (12)
    nIndices_ = first + 3 * std::size_t(nt);
    std::uint32_t* dst = out_.indices.data() + first;
    const int b = su_.flip ? 2 : 1, c = su_.flip ? 1 : 2;  // flipped winding: swap the last two
    const std::uint8_t* slot = cs.slot.data();
    for (int tri = 0; tri < nt; ++tri, slot += 3, dst += 3) {
      dst[0] = vid[slot[0]];
      dst[1] = vid[slot[b]];
      dst[2] = vid[slot[c]];
    }
  }

  // After one visit of slab z (the triangles from index `first` on are all of that slab): their
  // slab tags for the exact order, or one run per stretch of consecutive triangles of one slab
  // (what buildRuns makes), extended when the previous visit ended with the same slab.
  void closeSlabVisit(int z, std::size_t first) {
    const std::size_t count = nIndices_ - first;
    if (count == 0) return;
    const std::int32_t slab = std::int32_t(g0_[2] + z);
    if (su_.exact) {
      out_.triSlab.insert(out_.triSlab.end(), count / 3, slab);
    } else {
      if (out_.runs.size() == runBase_ || out_.runs.back().slab != slab)
        out_.runs.push_back(SurfaceSlabRun{slab, IndexRange{std::uint32_t(first), 0}});
      out_.runs.back().indices.count += std::uint32_t(count);
    }
  }

  // Exact order (§5): one index range per slab, slabs in sweep order (stable counting sort), and
  // within a slab the triangles sorted by the depth of their centroid along the view direction,
  // farthest first (the paper's "cubes within each slice ... sorted by distance to viewer").
  void sortBySlab() {
    const std::size_t nt = out_.triSlab.size();
    if (nt == 0) return;
    const std::int32_t base = std::int32_t(g0_[2]);
    auto& count = w_.slabCount;
    std::fill(count.begin(), count.end(), 0u);
    for (std::int32_t s : out_.triSlab) ++count[std::size_t(s - base) + 1];
    for (int i = 0; i < nz_; ++i) count[i + 1] += count[i];
    auto& keyed = out_.depthScratch;
    keyed.resize(nt);
    for (std::size_t i = 0; i < nt; ++i) {
      const std::uint32_t* t = &out_.indices[3 * i];
      double depth = 0;
      for (int a = 0; a < 3; ++a) {
        const double c = (double(out_.positions[t[0]][a]) + out_.positions[t[1]][a] + out_.positions[t[2]][a]) / 3.0;
        depth += (c - su_.eyeRel[a]) * su_.view[a];
      }
      const std::uint32_t dst = count[std::size_t(out_.triSlab[i] - base)]++;
      keyed[dst] = {float(-depth), std::uint32_t(i)};  // ascending key = farthest first
    }
    // count[s] is now the end of slab s; sort each slab's range by depth (ties: emission order).
    std::uint32_t begin = 0;
    for (int sl = 0; sl < nz_; ++sl) {
      const std::uint32_t end = count[std::size_t(sl)];
      std::sort(keyed.begin() + begin, keyed.begin() + end);
      begin = end;
    }
    auto& tmp = out_.sortScratch;
    tmp.resize(nt * 3);
    for (std::size_t i = 0; i < nt; ++i)
      std::memcpy(&tmp[3 * i], &out_.indices[3 * keyed[i].second], 3 * sizeof(std::uint32_t));
    out_.indices.swap(tmp);
    std::sort(out_.triSlab.begin(), out_.triSlab.end());
  }
};

struct FollowWorker;  // approach 2 (baselines.hpp), defined in marching_slices.cpp

// ---------------------------------------------------------------------------------------------
struct ExtractorState {
  std::vector<Particle> particles;
  std::vector<ParticleSortKey> sortKeys;
  struct Pair {
    std::uint64_t key;
    std::uint32_t rank;
  };
  std::vector<Pair> pairs, pairsByBlock;
  std::vector<std::uint32_t> blockCount;  // counting sort of pairs by block
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
};

inline SweepFrame chooseFrame(const SurfaceParams& p) {
  SweepFrame f;
  if (p.order == SurfaceOrder::none) return f;
  const float d[3] = {p.viewDir.x, p.viewDir.y, p.viewDir.z};
  int a = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(d[i]) > std::fabs(d[a])) a = i;
  // §5: "rotate the rendering volume" so the sweep runs along the axis nearest the view.
  // Back-to-front sweeps towards the eye (against the view direction), front-to-back away.
  const int sweepSign = (d[a] > 0 ? -1 : 1) * (p.order == SurfaceOrder::backToFront ? 1 : -1);
  const int others[3][2] = {{1, 2}, {2, 0}, {0, 1}};  // cyclic: with signs (1, s, s) a rotation
  f.axis[0] = others[a][0];
  f.axis[1] = others[a][1];
  f.axis[2] = a;
  f.sign[0] = 1;
  f.sign[1] = sweepSign;
  f.sign[2] = sweepSign;
  return f;
}

// Runs fn(slot, i) for i in [0, n) on the arena's workers; slot < max_concurrency identifies the
// worker (its scratch). ThreadSanitizer cannot see the synchronisation inside the uninstrumented
// system oneTBB, so TSan builds run the same per-item work on plain std::threads instead.
template <class Fn>
void parallelItems(tbb::task_arena& arena, std::size_t n, Fn&& fn) {
#if defined(__SANITIZE_THREAD__)
  const int slots = arena.max_concurrency();
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < slots; ++t)
    pool.emplace_back([&, t] {
      for (std::size_t i = next++; i < n; i = next++) fn(t, i);
    });
  for (std::thread& th : pool) th.join();
#else
  // One task per slot, each taking the next item from a shared counter as it becomes free: with
  // few, uneven items (2-4 blocks) this balances better than splitting the index range in halves.
  const int slots = arena.max_concurrency();
  std::atomic<std::size_t> next{0};
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(0, slots, 1),
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
// again, whatever the schedule (issue 3: no allocation per frame after warm-up, for N threads).
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
  grow(&Worker<Policy>::chainTouched);
  grow(&Worker<Policy>::slicePool);
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
    w->peakBytes = 0;
  }
  if (appendBlocks(st, su)) {
    // One thread: the blocks in emission order, each appending to the mesh's own arrays. The
    // same vertices and indices as concatenating per-block outputs (ids continue from the
    // blocks before), without the copy.
    BlockOut& sh = st.shared;
    sh.reset();
    sh.positions.swap(out.positions);
    sh.normals.swap(out.normals);
    sh.attributes.swap(out.attributes);
    sh.keys.swap(out.edgeKeys);
    sh.indices.swap(out.indices);
    sh.runs.swap(out.slabRuns);
    for (std::size_t i = 0; i < st.blocks.size(); ++i) {
      const BlockDesc& b = st.blocks[i];
      BlockMesher<Policy> mesher(*workers[0], su, policy, sh, true);
      mesher.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
      BlockOut& o = st.outs[i];
      o.reset();
      o.stats = sh.stats;
      o.cornerBytes = sh.cornerBytes;
      o.particleBytes = sh.particleBytes;
      o.vertexCount = sh.vertexCount;
      o.indexCount = sh.indexCount;
      o.runCount = sh.runCount;
    }
    sh.positions.swap(out.positions);
    sh.normals.swap(out.normals);
    sh.attributes.swap(out.attributes);
    sh.keys.swap(out.edgeKeys);
    sh.indices.swap(out.indices);
    sh.runs.swap(out.slabRuns);
    return;
  }
  runParallelLargestFirst(st, workers, [&](Worker<Policy>& w, std::size_t i) {
    const BlockDesc& b = st.blocks[i];
    BlockMesher<Policy> mesher(w, su, policy, st.outs[i]);
    mesher.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
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
  // Auto: blocks of up to max(autoCubes, 12 m) cubes keep the margins (m = ceil(Rc/S) cubes each
  // side, traversed but not emitted, §3) a modest share of the work; a set that fits one such
  // block is cut in two along its longest axis when both halves stay at least 5 m wide, so
  // mid-size sets still have two blocks to run in parallel. Depends on the data, S and Rc only.
  const bool autoSize = params.blockCubes <= 0;
  const int maxBlock = autoSize ? std::max(autoCubes, 12 * su.m) : params.blockCubes;
  std::int64_t extent[3];
  for (int a = 0; a < 3; ++a) {
    const std::int64_t c0 = floorDiv(lo[a] - su.rcMax, su.s) - 1;
    const std::int64_t c1 = floorDiv(hi[a] + su.rcMax, su.s) + 2;
    extent[a] = std::max<std::int64_t>(1, c1 - c0);
    su.nb[a] = int((extent[a] + maxBlock - 1) / maxBlock);
    su.lattice0[a] = c0;
  }
  if (autoSize && su.nb[0] * su.nb[1] * su.nb[2] == 1) {
    const int a = extent[0] >= extent[1] && extent[0] >= extent[2] ? 0 : (extent[1] >= extent[2] ? 1 : 2);
    if ((extent[a] + 1) / 2 >= 5 * su.m) su.nb[a] = 2;
  }
  for (int a = 0; a < 3; ++a) {
    su.b[a] = int((extent[a] + su.nb[a] - 1) / su.nb[a]);
    su.n[a] = su.b[a] + 2 * su.m;
  }
}

// Approach 2's block pass and its memory figure (marching_slices.cpp).
void runFollow(ExtractorState& st, const Setup& su);
std::uint64_t followPeakBytes(const ExtractorState& st);

template <class Policy>
SurfaceStatus extractImpl(ExtractorState& st, const SurfaceInput& input, const SurfaceParams& params,
                          const Policy& policy, SurfaceMesh& out) {
  out.clear();
  SurfaceStatus status = validateSurface(input, params);
  if (!status.ok()) return status;

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
  prepareParticles(input, params, su.frame, st.particles, su.rcMax, &st.sortKeys);
  if (st.particles.empty()) return {};
  su.m = std::max(1, int(std::ceil(su.rcMax / su.s)));  // margin of ceil(Rc/S) cubes (§3)
  // Marching slices keeps only a few slices per block, so its auto blocks can be as large as the
  // paper's (~100^3, §3): 128 cubes, where the margins cost about 15% of the cubes (64: ~30%).
  // Approach 2 holds a full 3D corner array per block, so it keeps 64 (its memory grows with the
  // cube of the block edge; 128 would make it a strawman).
  planBlocks(st.particles, params, st.method == 2 ? 64 : 128, su);
  if (su.n[0] + 1 > 32000 || su.n[1] + 1 > 32000 || su.n[2] + 1 > 32000)
    return {"surface params: blockCubes + 2 ceil(rc / cube) is too large"};
  {
    // View octant in the sweep frame, for the in-cube order tables (§5).
    const float d[3] = {params.viewDir.x, params.viewDir.y, params.viewDir.z};
    double ld[3];
    for (int a = 0; a < 3; ++a) ld[a] = su.frame.sign[a] * double(d[su.frame.axis[a]]);
    if (params.order == SurfaceOrder::frontToBack)
      for (double& v : ld) v = -v;
    su.octant = params.order == SurfaceOrder::none ? 0 : (ld[0] < 0) | ((ld[1] < 0) << 1) | ((ld[2] < 0) << 2);
  }

  // Block lists (§3): each particle goes to every block whose interior, grown by Rc_i, holds it.
  // Sorting (block, rank) pairs keeps each block's particles in (z, index) order. The pairs are
  // made in rank order, so a stable counting sort by block gives that order in one pass when the
  // block grid is not much larger than the pair list (otherwise a comparison sort).
  st.pairs.clear();
  const double inv = 1.0 / su.s;
  for (std::uint32_t r = 0; r < st.particles.size(); ++r) {
    const Particle& p = st.particles[r];
    const double rc = std::sqrt(p.rc2);
    const double pc[3] = {p.x, p.y, p.z};
    int b0[3], b1[3];
    for (int a = 0; a < 3; ++a) {
      b0[a] = std::clamp(ifloor(((pc[a] - rc) * inv - double(su.lattice0[a])) / su.b[a]), 0, su.nb[a] - 1);
      b1[a] = std::clamp(ifloor(((pc[a] + rc) * inv - double(su.lattice0[a])) / su.b[a]), 0, su.nb[a] - 1);
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
  if (st.outs.size() < st.blocks.size()) st.outs.resize(st.blocks.size());

  const int threads = params.threads > 0 ? params.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  if (!st.arena || st.arenaThreads != threads) {
    st.arena = std::make_unique<tbb::task_arena>(threads);
    st.arenaThreads = threads;
  }
  if (st.method == 2)
    runFollow(st, su);
  else
    runBlocks(st, su, policy, st.workersFor<Policy>(), out);

  // Concatenate block outputs in emission order (prefix sums, then a parallel copy; one block's
  // buffers are swapped in whole, and one worker appends the blocks in turn, which spares the
  // zero-fill of resize()). When the blocks appended to the mesh's arrays themselves
  // (appendBlocks), only the block ranges are left to fill in.
  const std::size_t nb = st.blocks.size();
  const bool appended = st.method != 2 && appendBlocks(st, su);
  auto counts = [&](const BlockOut& o, std::uint64_t c[3]) {
    c[0] = appended ? o.vertexCount : o.positions.size();
    c[1] = appended ? o.indexCount : o.indices.size();
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
    counts(o, c);
    if (std::uint64_t(st.vertexBase[i]) + c[0] > 0xffffffffull || std::uint64_t(st.indexBase[i]) + c[1] > 0xffffffffull) {
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
    stats.cornerCacheBytesPeakBlock = std::max(stats.cornerCacheBytesPeakBlock, o.cornerBytes);
    stats.particleCacheBytesPeakBlock = std::max(stats.particleCacheBytesPeakBlock, o.particleBytes);
  }
  const bool user = Policy::kHasUser && st.method == 1;
  // 0: parallel copy into resized arrays; 1: one block, swapped; 2: appended block by block;
  // 3: the blocks wrote into the mesh's arrays (appendBlocks).
  const int gather = appended ? 3 : nb == 1 ? 1 : (st.arena->max_concurrency() == 1 ? 2 : 0);
  if (gather == 1) {
    BlockOut& o = st.outs[0];
    out.positions.swap(o.positions);
    out.normals.swap(o.normals);
    out.edgeKeys.swap(o.keys);
    if (user) out.attributes.swap(o.attributes);
    out.indices.swap(o.indices);  // vertex base 0: no rebasing
  } else if (gather == 2) {
    for (std::size_t i = 0; i < nb; ++i) {
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
  stats.triangles = out.indices.size() / 3;
  stats.vertices = out.positions.size();
  stats.blocks = std::uint32_t(nb);
  std::uint64_t workBytes = st.method == 2 ? followPeakBytes(st) : 0;
  if (st.method != 2)
    for (auto& w : st.workersFor<Policy>())
      if (w) workBytes += w->peakBytes;
  stats.workingBytesAllWorkers = workBytes;
  return {};
}

}  // namespace fluid::detail
