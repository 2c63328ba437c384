#pragma once
// Internal: the data of the marching-slices core (marching_slices_impl.hpp): the field/vertex
// policies, the §6 particle cache and Figure 3 slice structures, block outputs, per-call setup and
// per-worker scratch, and the small lattice helpers shared by the block phases. Not a stable API.

#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mc_tables.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
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

// SurfaceInput::stretch (anisotropic kernels, Yu & Turk 2013): the same policy with every field
// term the stretched one of field.hpp. A wrapper type rather than a run-time flag, so the
// isotropic sums keep their code and cost, and the extractor keeps separate workers for it.
template <class Base>
struct AnisotropicPolicy : Base {
  explicit AnisotropicPolicy(const Base& base) : Base(base) {}
  static constexpr bool kAnisotropic = true;
};
template <class Policy>
constexpr bool isAnisotropic() {
  if constexpr (requires { Policy::kAnisotropic; })
    return Policy::kAnisotropic;
  else
    return false;
}

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
  std::uint32_t cell;     // y (Nx + 1) + x: for clearing the index array when the slice is returned (§4)
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
  // Slice-splat route (block_slice_splat.inl): the slice's field, dense, as four planes (value,
  // df/dx, df/dy, df/dz) of Worker::planeFloats floats each; empty on the particle-cache route.
  std::vector<float> field;
  const float* planes = nullptr;  // this slice's four planes: `field`, or its part of Worker::volume
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

// SurfaceStats' phase times: a steady clock read a few times per block (tens of ns each).
using PhaseClock = std::chrono::steady_clock;
inline double phaseMs(PhaseClock::time_point from, PhaseClock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

// Block grid and everything else fixed for one extract() call.
struct Setup {
  double s = 1;
  float threshold = 0.2f;
  double rcMax = 3;
  int m = 3;                             // margin cubes, marginCubes() (§3)
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
  bool splat = false;            // SurfaceFieldRoute::sliceSplat (and a policy without corner data)
  bool dense = false;            // SurfaceFieldRoute::denseScan: slice splat a slice at a time, every cube scanned
  bool valueOnly = false;        // SurfaceFieldRoute::valueScan: the dense scan on value slices (block_value_splat.inl)
  const StretchTerm* stretch = nullptr;  // by input index: SurfaceInput::stretch's terms (null: spheres)
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
  std::vector<StretchTerm> localStretch;  // anisotropic: the block particles' terms, as `local`
  std::vector<std::array<std::int16_t, 2>> rowSpans;  // cache build: x0, x1 of each disc row
  std::vector<float> offsets;                         // float(d S), d in [-offsetRange, offsetRange]
  std::vector<double> cx, cy, cz;                     // corner coordinates of local indices
  std::vector<std::uint64_t> kx, ky, kz;              // edgeKey() parts of local indices
  std::vector<std::int16_t> chainLo, chainHi;         // seeding memo per column
  std::vector<std::uint32_t> chainTouched;
  std::vector<std::uint8_t> seamX, seamY, seamZ;  // seam face bits per local cube index (BlockMesher::begin)
  std::vector<std::unique_ptr<Slice<Policy>>> slicePool;
  std::vector<Slice<Policy>*> freeSlices;
  std::vector<Slice<Policy>*> active;            // per slice z (0..nz)
  std::vector<std::vector<std::uint32_t>> todo;  // per slab z (0..nz-1)
  // Slice-splat route (block_slice_splat.inl). A plane holds one float per corner of a slice,
  // rows of planeStride floats (nx + 1, or a particle's widest window of 8-wide vectors if more):
  // corner (x, y) at y planeStride + planePad + x (planePad is 0). 0 on the cache route.
  std::size_t planeFloats = 0;
  int planeStride = 0, planePad = 0;
  bool volumeMode = false;           // the block's field is summed whole into `volume` (setPlanes)
  std::size_t sliceFieldFloats = 0;  // Slice::field size (4 planes, or 0 in volume mode)
  std::vector<float> volume;         // volume mode: slice z's four planes at 4 z planeFloats
  // Volume mode: per slice, the rows y0..y1 and columns x0..x1 ({y0, y1, x0, x1}) its last splat
  // wrote; all else of the volume is 0, so the next block clears just these (empty: y0 > y1).
  std::vector<std::array<std::int16_t, 4>> volumeRect;
  std::vector<float> seedRing;                  // seeding: value planes of the last ringSlots slices used
  std::vector<std::int32_t> ringZ;              // slice z held by each ring slot (-1: none)
  std::vector<float> splatOffsets;              // float(d S), d in [-(m + 2), m + 18] (8-wide windows)
  std::vector<double> splatCx;                  // double(g0 + x) S, x in [-m, nx + m + 15]
  std::vector<std::int32_t> splatInBlock;       // per plane column: -1 on the inner columns 1 .. nx - 1, else 0
  std::vector<std::int16_t> splatReach;         // particleReach() of each block particle
  std::vector<std::array<float, 2>> splatBand;  // per block particle: float(Rc_i^2 -/+ tol) (splatSlice)
  std::vector<std::uint32_t> slabCount;
  // Dense scan (block_dense_scan.inl): the inside bits of two slices' rows (words per row each),
  // the cubes of the interior as a row mask, vertex ids + 1 of the edges of two slices' faces (x
  // and y edges, by slice parity) and of one slab's z edges, five per column, and the slots
  // written in each of those three kinds since they were last cleared.
  std::vector<std::uint64_t> denseBits, denseCubeMask;
  // Its two slices' planes (4 planeFloats each, slice z in [z & 1]) and what their last splats
  // wrote ({y0, y1, x0, x1}, as volumeRect): everything else of them is 0.
  std::array<std::vector<float>, 2> denseField;
  std::array<std::array<std::int16_t, 4>, 2> denseRect{};
  // valueScan (block_value_splat.inl): four value slices instead (slice z in [z & 3]: central
  // differences read z - 1 and z + 1 around a slab's two), each with what its last splat wrote,
  // and float(Rc_i^2) per block particle.
  std::array<std::vector<float>, 4> valueField;
  std::array<std::array<std::int16_t, 4>, 4> valueRect{};
  std::vector<float> splatRc2;
  std::vector<std::uint32_t> denseIds;
  std::array<std::vector<std::uint32_t>, 3> denseTouched;
  std::size_t denseWords = 0;
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
    seamX.assign(nx + 1, 0);
    seamY.assign(ny + 1, 0);
    seamZ.assign(nz + 1, 0);
    slicePool.clear();
    freeSlices.clear();
    active.assign(nz + 1, nullptr);
    todo.resize(nz);
    for (auto& t : todo) t.clear();
    slabCount.assign(nz + 1, 0);
  }

  // The slice-splat planes for margin m (0: the cache route, no planes). Sized once per block
  // shape, so after warm-up nothing is allocated. When the block's whole field (four planes per
  // slice) stays under kVolumeBytes it is summed once up front (`volume`) and serves both §4
  // seeding and the sweep; otherwise each slice the sweep takes up is summed into the slice's own
  // planes, and seeding reads value planes of all slices (`seedRing`) or, when even those exceed
  // kVolumeBytes, a ring of 2 m + 4 (seeding's descents start at the particles' nearest corners,
  // which rise with their z, but one from a margin column may run down the whole block).
  static constexpr std::size_t kVolumeBytes = std::size_t(8) << 20;
  // `scan`: the dense scan (block_dense_scan.inl) needs neither: it sums each slice's planes once,
  // in order, into one of two slices of the pool, and reads each only while it is in cache;
  // `valueOnly` (valueScan): into one of four value slices instead.
  void setPlanes(bool splat, int m, bool scan = false, bool valueOnly = false) {
    const int pad = 0;
    const int stride = splat ? std::max(nx + 1, 8 * ((2 * m + 8) / 8)) : 0;
    const std::size_t floats = splat ? std::size_t(stride) * std::size_t(ny + 1) : 0;
    const std::size_t slices = std::size_t(nz + 1);
    const bool vol = splat && !scan && 4 * slices * floats * sizeof(float) <= kVolumeBytes;
    const std::size_t denseFloats = scan && !valueOnly ? 4 * floats : 0;
    if (denseField[0].size() != denseFloats || floats != planeFloats || stride != planeStride)
      for (int i = 0; i < 2; ++i) {
        denseField[i].assign(denseFloats, 0.0f);
        denseRect[i] = {1, 0, 1, 0};
      }
    const std::size_t valueFloats = valueOnly ? floats + 8 : 0;  // + 8: denseSliceBits' loads past the last row
    if (valueField[0].size() != valueFloats || floats != planeFloats || stride != planeStride)
      for (int i = 0; i < 4; ++i) {
        valueField[i].assign(valueFloats, 0.0f);
        valueRect[i] = {1, 0, 1, 0};
      }
    const std::size_t slots = !splat || vol || scan                             ? 0
                              : slices * floats * sizeof(float) <= kVolumeBytes ? slices
                                                                                : std::size_t(2 * m + 4);
    if (floats == planeFloats && stride == planeStride && pad == planePad && vol == volumeMode &&
        (!vol || volume.size() == 4 * slices * floats) && ringZ.size() == slots)
      return;
    planeFloats = floats, planeStride = stride, planePad = pad, volumeMode = vol;
    sliceFieldFloats = vol || scan ? 0 : 4 * floats;  // (the scan uses no pool slices)
    for (auto& s : slicePool) s->field.assign(sliceFieldFloats, 0.0f);
    volume.assign(vol ? 4 * slices * floats : 0, 0.0f);
    volumeRect.assign(vol ? slices : 0, std::array<std::int16_t, 4>{1, 0, 1, 0});
    seedRing.assign(slots * floats, 0.0f);
    ringZ.assign(slots, -1);
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
    slicePool.back()->field.resize(sliceFieldFloats);
    return slicePool.back().get();
  }
  // Returns a slice to the pool, clearing only the entries it touched (§4).
  void releaseSlice(Slice<Policy>* s) {
    for (const Corner<Policy>& c : s->corners) s->cells[c.cell] = SliceCell{};
    s->corners.clear();
    freeSlices.push_back(s);
  }
};

// Whether the particle-cache fill takes its AVX2 path (Setup::avx2).
inline bool detectFillAvx2(const SurfaceParams& params) {
#if defined(FLUID_SURFACE_AVX2_FILL)
  // The AVX2 mesher copy is also compiled with BMI1/BMI2/POPCNT (non-destructive shifts and bit
  // operations; integer only, so the same results), which every AVX2 CPU so far also has.
  return !params.portableKernels && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi") &&
         __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("popcnt");
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

// Margin cubes on each side of a block's interior (§3): ceil(Rc/S + 1/2), not the paper's
// ceil(Rc/S). Seeding (§4) starts from each particle's nearest corner, and the expanded block's
// outermost corners are held at field 0 (so every surface closes), so that corner must lie strictly
// inside the expanded block for every particle that reaches the interior: such a particle is less
// than Rc/S cubes from an interior corner, its nearest corner less than Rc/S + 1/2. With
// ceil(Rc/S), a particle just over m - 1/2 cubes outside the interior (Rc/S a whole number, or just
// under one) would snap to a boundary corner, which never seeds, and the part of its surface inside
// the block would be left open at the seam.
inline int marginCubes(double rcMax, double s) { return std::max(1, int(std::ceil(rcMax / s + 0.5))); }

// Block membership (§3), per axis, in lattice integers. A particle influences corner c only if
// |c S - p| < Rc_i, so c lies in [anchor - reach, anchor + reach] with reach = ceil(Rc_i / S)
// (anchor = floor(p / S)). The blocks along axis `a` whose interior corners [b0, b0 + b] meet that
// range are [first, last] (callers clip it to their grid: outside it there is no corner).
// Deciding this on the same integers the particle cache uses (rather than on (p -+ Rc_i) / S,
// rounded separately) makes its invariant hold by construction: with reach <= m, every block
// particle's anchor lies in the block's expanded region, 0 <= anchor - g0 <= n (reach <= m).
// The range is exact for float input: p / S and Rc_i / S are either whole numbers or at least
// ~2^-25 (resp. 2^-48 (Rc_i / S)) away from one, far more than double rounding, so the floor,
// the ceil and the exact predicate (influences()) agree with real arithmetic at its ends.
inline std::int64_t floorDivInt(std::int64_t v, std::int64_t d) { return v / d - (v % d != 0 && (v < 0) != (d < 0)); }
inline int particleReach(const Particle& p, double s) { return int(std::ceil(std::sqrt(p.rc2) / s)); }
// The blocks along axis a whose interior corners a particle with this anchor and reach touches:
// (first + 1) b >= t - reach and last b <= t + reach, t = anchor - lattice0. `blockOf(t)` =
// floorDivInt(t, b): a division (blockSpan) or a table (BlockSpanTables, for every particle).
template <class BlockOf>
void blockSpanBy(std::int64_t t, int reach, BlockOf&& blockOf, int& first, int& last) {
  first = int(blockOf(t - reach - 1));
  last = int(blockOf(t + reach));
}
inline void blockSpan(const Setup& su, int a, std::int64_t anchor, int reach, int& first, int& last) {
  const std::int64_t b = su.b[a];
  blockSpanBy(anchor - su.lattice0[a], reach, [b](std::int64_t t) { return floorDivInt(t, b); }, first, last);
}
// blockSpan from a table of floorDivInt(t, b) per axis (two 64-bit divisions per particle and axis
// cost more than the rest of building the block lists); offsets outside the table divide.
struct BlockSpanTables {
  std::array<std::vector<std::int32_t>, 3> blockOf;
  std::int64_t pad = 0;  // the tables start at t = -pad
  static constexpr std::int64_t kMaxLength = std::int64_t(1) << 16;
  void build(const Setup& su) {
    pad = std::int64_t(su.m) + 2;  // t - reach - 1 >= -(m + 1) for anchors in the lattice
    for (int a = 0; a < 3; ++a) {
      auto& table = blockOf[std::size_t(a)];
      const std::int64_t length = std::int64_t(su.nb[a]) * su.b[a] + 2 * pad + 1;
      table.resize(length <= kMaxLength ? std::size_t(length) : 0);  // a lattice miles wide divides
      for (std::size_t i = 0; i < table.size(); ++i) table[i] = std::int32_t(floorDivInt(std::int64_t(i) - pad, su.b[a]));
    }
  }
  void span(const Setup& su, int a, std::int64_t anchor, int reach, int& first, int& last) const {
    const auto& table = blockOf[std::size_t(a)];
    const std::int64_t b = su.b[a], padded = pad;
    blockSpanBy(
        anchor - su.lattice0[a], reach,
        [&table, b, padded](std::int64_t t) {
          const std::uint64_t i = std::uint64_t(t + padded);
          return i < table.size() ? std::int64_t(table[i]) : floorDivInt(t, b);
        },
        first, last);
  }
};

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

// A unit square of a seam plane (the plane between two blocks' interiors, §3): g = its lowest
// lattice corner, `axis` = the plane's normal. For seam propagation (BlockMesher::seedFromNeighbours).
struct SeamSquare {
  std::int64_t g[3];
  std::int32_t axis;
  friend bool operator==(const SeamSquare& a, const SeamSquare& b) {
    return a.axis == b.axis && a.g[0] == b.g[0] && a.g[1] == b.g[1] && a.g[2] == b.g[2];
  }
  friend bool operator<(const SeamSquare& a, const SeamSquare& b) {
    if (a.axis != b.axis) return a.axis < b.axis;
    for (int i = 0; i < 3; ++i)
      if (a.g[i] != b.g[i]) return a.g[i] < b.g[i];
    return false;
  }
};

// One block's seam propagation state for one extract() call.
struct BlockSeams {
  std::vector<SeamSquare> seeds;   // squares its neighbours' marches crossed and its own did not (sorted)
  std::vector<SeamSquare> visits;  // seam squares its last run's march crossed (BlockMesher::noteSeamFaces)
};

}  // namespace fluid::detail
