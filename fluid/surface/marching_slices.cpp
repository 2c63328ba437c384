// Marching slices (Rosenberg & Birdwell 2008), one oneTBB task per block (Janisz §3.2.6).
// Section numbers below refer to the marching-slices paper; "Alg. 1" to DESIGN.md's restatement.
#include "fluid/surface/marching_slices.hpp"

#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/detail/testing.hpp"
#include "fluid/surface/mc_tables.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

namespace fluid {

void SurfaceMesh::clear() {
  positions.clear();
  normals.clear();
  attributes.clear();
  edgeKeys.clear();
  indices.clear();
  blocks.clear();
  slabRuns.clear();
  stats = {};
}

namespace {
bool finite(float v) { return std::isfinite(v); }

std::string fieldError(const char* name, std::size_t i, float v) {
  return std::string("surface input: ") + name + "[" + std::to_string(i) + "] = " + std::to_string(v) +
         " is not finite";
}
}  // namespace

SurfaceStatus validateSurface(const SurfaceInput& in, const SurfaceParams& p) {
  auto bad = [](std::string s) { return SurfaceStatus{std::move(s)}; };
  if (!(std::isfinite(p.rc) && p.rc > 0)) return bad("surface params: rc = " + std::to_string(p.rc) + " must be > 0");
  if (!(std::isfinite(p.cube) && p.cube > 0))
    return bad("surface params: cube = " + std::to_string(p.cube) + " must be > 0");
  if (!(std::isfinite(p.threshold) && p.threshold > 0))
    return bad("surface params: threshold = " + std::to_string(p.threshold) + " must be > 0");
  if (std::ceil(p.rc / p.cube) > 4000)
    return bad("surface params: rc / cube = " + std::to_string(p.rc / p.cube) + " is too fine (max 4000)");
  if (p.blockCubes != 0 && (p.blockCubes < 4 || p.blockCubes > 1024))
    return bad("surface params: blockCubes = " + std::to_string(p.blockCubes) + " must be 0 (auto) or in [4, 1024]");
  if (p.threads < 0 || p.threads > 256)
    return bad("surface params: threads = " + std::to_string(p.threads) + " must be in [0, 256]");
  if (!std::isfinite(p.originX) || !std::isfinite(p.originY) || !std::isfinite(p.originZ))
    return bad("surface params: origin is not finite");
  if (p.order != SurfaceOrder::none) {
    if (!finite(p.eye.x) || !finite(p.eye.y) || !finite(p.eye.z)) return bad("surface params: eye is not finite");
    if (!finite(p.viewDir.x) || !finite(p.viewDir.y) || !finite(p.viewDir.z) ||
        (p.viewDir.x == 0 && p.viewDir.y == 0 && p.viewDir.z == 0))
      return bad("surface params: viewDir must be finite and non-zero");
  }
  const std::size_t n = in.x.size();
  if (in.y.size() != n || in.z.size() != n)
    return bad("surface input: x, y, z have different lengths (" + std::to_string(n) + ", " +
               std::to_string(in.y.size()) + ", " + std::to_string(in.z.size()) + ")");
  if (!in.strength.empty() && in.strength.size() != n)
    return bad("surface input: strength has " + std::to_string(in.strength.size()) + " entries, expected " +
               std::to_string(n));
  if (!in.radiusScale.empty() && in.radiusScale.size() != n)
    return bad("surface input: radiusScale has " + std::to_string(in.radiusScale.size()) + " entries, expected " +
               std::to_string(n));
  if (!in.user.empty() && in.user.size() != n)
    return bad("surface input: user has " + std::to_string(in.user.size()) + " entries, expected " +
               std::to_string(n));
  if (n >= (std::size_t(1) << 31)) return bad("surface input: too many particles");
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite(in.x[i])) return bad(fieldError("x", i, in.x[i]));
    if (!finite(in.y[i])) return bad(fieldError("y", i, in.y[i]));
    if (!finite(in.z[i])) return bad(fieldError("z", i, in.z[i]));
    // Lattice indices must fit the 20-bit key window and int32 block maths comfortably.
    const float lim = 4.0e5f * p.cube;
    if (std::fabs(in.x[i]) > lim || std::fabs(in.y[i]) > lim || std::fabs(in.z[i]) > lim)
      return bad("surface input: particle " + std::to_string(i) + " is farther than 400000 cubes from the origin");
  }
  for (std::size_t i = 0; i < in.strength.size(); ++i)
    if (!(finite(in.strength[i]) && in.strength[i] > 0))
      return bad("surface input: strength[" + std::to_string(i) + "] = " + std::to_string(in.strength[i]) +
                 " must be finite and > 0");
  for (std::size_t i = 0; i < in.radiusScale.size(); ++i)
    if (!(finite(in.radiusScale[i]) && in.radiusScale[i] > 0 && in.radiusScale[i] <= 64))
      return bad("surface input: radiusScale[" + std::to_string(i) + "] = " + std::to_string(in.radiusScale[i]) +
                 " must be in (0, 64]");
  for (std::size_t i = 0; i < in.user.size(); ++i)
    if (!finite(in.user[i].x) || !finite(in.user[i].y) || !finite(in.user[i].z) || !finite(in.user[i].w))
      return bad("surface input: user[" + std::to_string(i) + "] is not finite");
  return {};
}

namespace detail {
namespace {

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
// texturing: per-particle data interpolated onto the surface).
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
// min_z..max_z of this column; mid_z is the slab holding its centre. Lists are stored as
// contiguous z-sorted arrays (CSR) instead of doubly linked lists: the same walk, better locality.
// Each element carries the particle's x/y offsets to its column; the rest is in BlockParticle.
struct ColumnEntry {
  float dx, dy;
  std::int16_t minZ, maxZ, midZ, pad;
  std::uint32_t particle;  // into the block's particle array
};
struct BlockParticle {
  float restZ, k, s;
  std::uint32_t index;  // input index (user data)
};

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
};

template <class Policy>
struct Slice {
  std::vector<SliceCell> cells;  // (Nx+1)(Ny+1) corner index array
  std::vector<Corner<Policy>> corners;
};

struct BlockDesc {
  std::int32_t bx, by, bz;
  std::uint32_t first, count;  // into ExtractorState::blockParticles
  double sortKey;
};

struct BlockOut {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec4> attributes;
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> indices;
  std::vector<std::int32_t> triSlab;  // slab of each triangle (for runs / exact order)
  std::vector<std::uint32_t> sortScratch;
  std::vector<SurfaceSlabRun> runs;
  SurfaceStats stats;
  std::uint64_t cornerBytes = 0, particleBytes = 0;
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
  }
};

// Block grid and everything else fixed for one extract() call.
struct Setup {
  double s = 1;
  float threshold = 0.2f;
  double rcMax = 3;
  int m = 3;                         // margin cubes, ceil(Rc/S) (§3)
  int b[3] = {32, 32, 32};           // interior cubes per block, per axis
  int n[3] = {38, 38, 38};           // expanded cubes per block, b + 2m
  int nb[3] = {1, 1, 1};             // blocks per axis
  std::int64_t lattice0[3] = {0, 0, 0};  // lattice index where block 0's interior starts
  int octant = 0;
  bool exact = false;
  bool flip = false;
  SweepFrame frame;
  double origin[3] = {0, 0, 0};  // world origin subtracted from output positions
};

// Per-worker scratch, reused across blocks and frames.
template <class Policy>
struct Worker {
  int nx = -1, ny = -1, nz = -1;  // expanded cubes per axis; corners 0..n
  std::vector<std::uint32_t> colStart, cursor;
  std::vector<ColumnEntry> entries;
  std::vector<BlockParticle> local;
  std::vector<float> zOffset;  // float((d) * S) for d in [-window, window], the z part of the offset
  std::vector<double> cx, cy, cz;  // corner coordinates of local indices
  std::vector<std::int16_t> chainLo, chainHi;  // seeding memo per column
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
    cx.assign(nx + 1, 0);
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
    if (freeSlices.empty()) {
      slicePool.push_back(std::make_unique<Slice<Policy>>());
      slicePool.back()->cells.assign(columns(), SliceCell{});
      freeSlices.push_back(slicePool.back().get());
    }
    Slice<Policy>* s = freeSlices.back();
    freeSlices.pop_back();
    return s;
  }
  // Returns a slice to the pool, clearing only the entries it touched (§4).
  void releaseSlice(Slice<Policy>* s) {
    for (const Corner<Policy>& c : s->corners) s->cells[std::size_t(c.y) * std::size_t(nx + 1) + c.x] = SliceCell{};
    s->corners.clear();
    freeSlices.push_back(s);
  }
};

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
inline VertexOut makeVertex(const Setup& su, const std::int64_t gi[3], int axis, float va, const float ga[3],
                            float vb, const float gb[3]) {
  const double tt = (double(su.threshold) - double(va)) / (double(vb) - double(va));
  double local[3] = {double(gi[0]) * su.s, double(gi[1]) * su.s, double(gi[2]) * su.s};
  local[axis] += tt * su.s;
  const float tf = float(tt);
  float g[3];
  for (int i = 0; i < 3; ++i) g[i] = ga[i] + tf * (gb[i] - ga[i]);
  const float len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  float nl[3] = {0, 0, 0};
  if (len2 > 1e-30f && std::isfinite(len2)) {
    const float inv = -1.0f / std::sqrt(len2);
    for (int i = 0; i < 3; ++i) nl[i] = g[i] * inv;
  } else {
    // Flat gradient (symmetric cancellation): point along the edge, inside -> outside.
    nl[axis] = va > su.threshold ? 1.0f : -1.0f;
  }
  VertexOut v;
  for (int a = 0; a < 3; ++a) {
    const int wa = su.frame.axis[a];
    v.position[wa] = float(su.frame.sign[a] * local[a] - su.origin[wa]);
    v.normal[wa] = float(su.frame.sign[a]) * nl[a];
  }
  return v;
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
  BlockMesher(Worker<Policy>& w, const Setup& setup, const Policy& policy, BlockOut& out)
      : w_(w), su_(setup), pol_(policy), out_(out), nx_(setup.n[0]), ny_(setup.n[1]), nz_(setup.n[2]),
        stride_(setup.n[0] + 1) {}

  void run(const BlockDesc& block, std::span<const Particle> particles) {
    out_.reset();
    begin(block);
    buildParticleCache(particles);
    seed(particles);
    march();
    if (su_.exact) sortBySlab();
    buildRuns(out_);
    out_.stats.triangles = out_.indices.size() / 3;
    out_.stats.vertices = out_.positions.size();
    out_.particleBytes = std::uint64_t(w_.columns()) * 2 * sizeof(std::uint32_t) +
                         std::uint64_t(w_.entries.size()) * sizeof(ColumnEntry) +
                         std::uint64_t(w_.local.size()) * sizeof(BlockParticle);
    out_.cornerBytes = peakCornerBytes_;
    w_.peakBytes = std::max(w_.peakBytes, out_.particleBytes + out_.cornerBytes);
  }

  // Test hook (detail/testing.hpp): build the particle cache only, then look up corners.
  void prepareCache(const BlockDesc& block, std::span<const Particle> particles) {
    begin(block);
    buildParticleCache(particles);
  }
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
    found.clear();
    forEachInfluencing(x, y, z, [&](const ColumnEntry&, const BlockParticle& q, float) { found.push_back(q.index); });
  }

 private:
  Worker<Policy>& w_;
  const Setup& su_;
  const Policy& pol_;
  BlockOut& out_;
  const int nx_, ny_, nz_, stride_;
  std::int64_t g0_[3] = {0, 0, 0};
  int window_ = 0;  // max |mid_z - min_z|, |max_z - mid_z| over entries: the lookup window (§6)
  int activeSlices_ = 0;
  std::uint64_t peakCornerBytes_ = 0;
  int lowestTodo_ = std::numeric_limits<int>::max();

  std::size_t col(int x, int y) const { return std::size_t(y) * std::size_t(stride_) + std::size_t(x); }

  void begin(const BlockDesc& block) {
    blockOrigin(su_, block, g0_);
    for (int i = 0; i <= nx_; ++i) w_.cx[i] = double(g0_[0] + i) * su_.s;
    for (int i = 0; i <= ny_; ++i) w_.cy[i] = double(g0_[1] + i) * su_.s;
    for (int i = 0; i <= nz_; ++i) w_.cz[i] = double(g0_[2] + i) * su_.s;
  }

  // §6: particles arrive sorted by (z, index); insert one element per column of the projection
  // slice within Rc_i. Skip boundary columns and clamp min_z/max_z to [1, Nz-1] so the field is
  // zero on the outer boundary of the expanded block (§3) and every surface is closed.
  // Two passes over the same disc (count, then fill in place) build the CSR arrays directly.
  template <class F>
  void forEachColumn(const Particle& p, F&& f) const {
    const double inv = 1.0 / su_.s, rc = std::sqrt(p.rc2);
    // Column range from the disc, widened by 1e-6 cubes against rounding; callers apply the
    // exact predicate (an element whose z range comes out empty is never returned).
    const int y0 = std::max(1, iceil((p.y - rc) * inv - double(g0_[1]) - 1e-6));
    const int y1 = std::min(ny_ - 1, ifloor((p.y + rc) * inv - double(g0_[1]) + 1e-6));
    for (int y = y0; y <= y1; ++y) {
      const double dy = w_.cy[y] - p.y;
      const double hx = std::sqrt(std::max(0.0, p.rc2 - dy * dy));
      const int x0 = std::max(1, iceil((p.x - hx) * inv - double(g0_[0]) - 1e-6));
      const int x1 = std::min(nx_ - 1, ifloor((p.x + hx) * inv - double(g0_[0]) + 1e-6));
      for (int x = x0; x <= x1; ++x) f(x, y, dy);
    }
  }

  void buildParticleCache(std::span<const Particle> particles) {
    const std::size_t cols = w_.columns();
    std::fill(w_.colStart.begin(), w_.colStart.end(), 0u);
    for (const Particle& p : particles) forEachColumn(p, [&](int x, int y, double) { ++w_.colStart[col(x, y) + 1]; });
    for (std::size_t c = 0; c < cols; ++c) w_.colStart[c + 1] += w_.colStart[c];
    for (std::size_t c = 0; c < cols; ++c) w_.cursor[c] = w_.colStart[c];
    w_.entries.resize(w_.colStart[cols]);
    w_.local.resize(particles.size());
    window_ = 0;
    const double inv = 1.0 / su_.s;
    for (std::uint32_t li = 0; li < particles.size(); ++li) {
      const Particle& p = particles[li];
      w_.local[li] = BlockParticle{p.rest[2], p.k, p.strength, p.index};
      const double fz = p.z * inv - double(g0_[2]);
      const int mid = int(p.anchor[2] - g0_[2]);
      forEachColumn(p, [&](int x, int y, double dy) {
        const double dx = w_.cx[x] - p.x;
        const double dxy = dx * dx + dy * dy;
        // Candidate range from the closed form, then corrected with the exact predicate
        // (influences()) so the cache returns precisely the particles within Rc_i.
        auto inside = [&](int z) {
          const double dz = w_.cz[z] - p.z;
          return dxy + dz * dz < p.rc2;
        };
        int lo = 1, hi = 0;
        if (dxy < p.rc2) {
          const double h = std::sqrt(p.rc2 - dxy) * inv;
          lo = std::clamp(iceil(fz - h), 1, nz_ - 1);
          hi = std::clamp(ifloor(fz + h), 1, nz_ - 1);
          if (lo > 1 && inside(lo - 1)) {
            do --lo;
            while (lo > 1 && inside(lo - 1));
          } else {
            while (lo <= hi && !inside(lo)) ++lo;
          }
          if (hi < nz_ - 1 && inside(hi + 1)) {
            do ++hi;
            while (hi < nz_ - 1 && inside(hi + 1));
          } else {
            while (hi >= lo && !inside(hi)) --hi;
          }
          if (lo <= hi) {
            window_ = mid - lo > window_ ? mid - lo : window_;
            window_ = hi - mid > window_ ? hi - mid : window_;
          }
        }
        ColumnEntry& e = w_.entries[w_.cursor[col(x, y)]++];
        e.dx = latticeOffset(g0_[0] + x, p.anchor[0], p.rest[0], su_.s);
        e.dy = latticeOffset(g0_[1] + y, p.anchor[1], p.rest[1], su_.s);
        e.minZ = std::int16_t(lo);
        e.maxZ = std::int16_t(hi);
        e.midZ = std::int16_t(std::clamp(mid, -32000, 32000));
        e.pad = 0;
        e.particle = li;
      });
    }
    for (std::size_t c = 0; c < cols; ++c) w_.cursor[c] = w_.colStart[c];
    w_.zOffset.resize(std::size_t(2 * window_ + 1));
    for (int d = -window_; d <= window_; ++d) w_.zOffset[std::size_t(d + window_)] = float(double(d) * su_.s);
  }

  // §6 lookup: from the column's start pointer find the bottom-most entry with
  // mid_z >= z - window, walk up while mid_z <= z + window, keep min_z <= z <= max_z, and leave
  // the start pointer at the first entry found. f(entry, dz) is called in (z, index) order.
  template <class F>
  void forEachInfluencing(int x, int y, int z, F&& f) {
    const std::size_t k = col(x, y);
    const std::uint32_t begin = w_.colStart[k], end = w_.colStart[k + 1];
    if (begin == end) return;
    std::uint32_t cur = w_.cursor[k];
    const int lo = z - window_, hi = z + window_;
    const ColumnEntry* e = w_.entries.data();
    while (cur > begin && e[cur - 1].midZ >= lo) --cur;
    while (cur < end && e[cur].midZ < lo) ++cur;
    w_.cursor[k] = cur;
    const float* zoff = w_.zOffset.data() + window_ + z;  // zoff[-mid] = float((z - mid) S)
    const BlockParticle* bp = w_.local.data();
    for (std::uint32_t i = cur; i < end; ++i) {
      if (e[i].midZ > hi) break;
      if (e[i].minZ > z || e[i].maxZ < z) continue;
      const BlockParticle& q = bp[e[i].particle];
      f(e[i], q, zoff[-e[i].midZ] - q.restZ);
    }
  }

  template <bool kGradient>
  void evaluate(int x, int y, int z, Corner<Policy>& c) {
    float v = 0, gx = 0, gy = 0, gz = 0;
    std::uint64_t looked = 0;
    c.user = {};
    forEachInfluencing(x, y, z, [&](const ColumnEntry& e, const BlockParticle& q, float dz) {
      ++looked;
      const float dxy2 = e.dx * e.dx + e.dy * e.dy;
      if constexpr (kGradient || Policy::kHasUser) {
        const float before = v;
        accumulate(e.dx, e.dy, dxy2, dz, q.k, q.s, v, gx, gy, gz);
        if constexpr (Policy::kHasUser) pol_.add(c.user, q.index, v - before);
      } else {
        v += contribution(dxy2, dz, q.k, q.s);
      }
    });
    out_.stats.particlesLookedUp += looked;
    c.value = v;
    c.g[0] = gx;
    c.g[1] = gy;
    c.g[2] = gz;
  }

  float fieldAt(int x, int y, int z) {
    float v = 0;
    forEachInfluencing(x, y, z, [&](const ColumnEntry& e, const BlockParticle& q, float dz) {
      v += contribution(e.dx * e.dx + e.dy * e.dy, dz, q.k, q.s);
    });
    ++out_.stats.seedEvaluations;
    return v;
  }

  bool interiorCorner(int x, int y, int z) const {
    const int m = su_.m;
    return x >= m && x <= m + su_.b[0] && y >= m && y <= m + su_.b[1] && z >= m && z <= m + su_.b[2];
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
      const bool ownInside = influences(p, w_.cx[x], w_.cy[y], w_.cz[z0]) &&
                             contribution(ox * ox + oy * oy, oz, p.k, p.strength) > t;
      if (!ownInside && !(fieldAt(x, y, z0) > t)) continue;  // nearest corner outside: no seed here
      const int steps = iceil(std::sqrt(p.rc2) * inv) + 1;
      int z = z0;
      bool joined = false;
      for (int i = 0; i < steps && z > 0; ++i) {
        const int below = z - 1;
        if (below >= w_.chainLo[k] && below <= w_.chainHi[k]) {
          joined = true;
          break;
        }
        if (!(fieldAt(x, y, below) > t)) {
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

  Slice<Policy>* ensureSlice(int z) {
    if (!w_.active[z]) {
      w_.active[z] = w_.acquireSlice();
      ++activeSlices_;
      out_.stats.maxActiveSlices = std::max<std::uint32_t>(out_.stats.maxActiveSlices, activeSlices_);
    }
    return w_.active[z];
  }
  void freeSlice(int z) {
    if (!w_.active[z]) return;
    w_.releaseSlice(w_.active[z]);
    w_.active[z] = nullptr;
    --activeSlices_;
  }
  void notePeak(int z) {
    // Active slices are z, z+1 and any abandoned below after a reversal; count all of them.
    std::uint64_t bytes = 0;
    for (int i = 0; i <= nz_; ++i)
      if (w_.active[i])
        bytes += w_.active[i]->cells.size() * sizeof(SliceCell) + w_.active[i]->corners.size() * sizeof(Corner<Policy>);
    (void)z;
    peakCornerBytes_ = std::max(peakCornerBytes_, bytes);
  }

  std::uint32_t lookupOrEval(Slice<Policy>& slice, int x, int y, int z) {
    SliceCell& cell = slice.cells[col(x, y)];
    if (cell.corner) return cell.corner - 1;
    Corner<Policy> c;
    if (interiorCorner(x, y, z))
      evaluate<true>(x, y, z, c);
    else
      evaluate<false>(x, y, z, c);  // margin: only the sign is needed (§3)
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.x = std::int16_t(x);
    c.y = std::int16_t(y);
    slice.corners.push_back(c);
    ++out_.stats.cornersEvaluated;
    cell.corner = std::uint32_t(slice.corners.size());
    return cell.corner - 1;
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
      while (!list.empty()) {
        const std::uint32_t item = list.back();
        list.pop_back();
        const int x = int(item & 0xffff), y = int(item >> 16);
        SliceCell& cb = below->cells[col(x, y)];
        SliceCell& ca = above->cells[col(x, y)];
        if (cb.doneAbove || ca.doneBelow) continue;
        cb.doneAbove = 1;
        ca.doneBelow = 1;
        ++out_.stats.cubesVisited;
        std::uint32_t ci[8];
        ci[0] = lookupOrEval(*below, x, y, z);
        ci[1] = lookupOrEval(*below, x + 1, y, z);
        ci[2] = lookupOrEval(*below, x, y + 1, z);
        ci[3] = lookupOrEval(*below, x + 1, y + 1, z);
        ci[4] = lookupOrEval(*above, x, y, z + 1);
        ci[5] = lookupOrEval(*above, x + 1, y, z + 1);
        ci[6] = lookupOrEval(*above, x, y + 1, z + 1);
        ci[7] = lookupOrEval(*above, x + 1, y + 1, z + 1);
        Corner<Policy>* cp[8];
        for (int i = 0; i < 4; ++i) cp[i] = &below->corners[ci[i]];
        for (int i = 4; i < 8; ++i) cp[i] = &above->corners[ci[i]];
        unsigned cube = 0;
        for (int i = 0; i < 8; ++i) cube |= unsigned(cp[i]->value > t) << i;
        if (cube == 0 || cube == 255) continue;
        const mc::CaseTable& cs = table[cube];
        if (interiorSlab && x >= ia && x < ibx && y >= ia && y < iby) polygonize(cs, cp, x, y, z);
        // Push neighbours across crossed faces unless done (Alg. 1).
        const unsigned f = cs.faceMask;
        if ((f & 1) && !below->cells[col(x - 1, y)].doneAbove) list.push_back(item - 1);
        if ((f & 2) && !below->cells[col(x + 1, y)].doneAbove) list.push_back(item + 1);
        if ((f & 4) && !below->cells[col(x, y - 1)].doneAbove) list.push_back(item - (1u << 16));
        if ((f & 8) && !below->cells[col(x, y + 1)].doneAbove) list.push_back(item + (1u << 16));
        if ((f & 16) && !cb.doneBelow) {
          assert(z > 0);
          w_.todo[z - 1].push_back(item);
        }
        if ((f & 32) && !ca.doneAbove) {
          assert(z + 1 < nz_);
          w_.todo[z + 1].push_back(item);
        }
      }
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
    lowestTodo_ = std::numeric_limits<int>::max();
  }

  std::uint32_t vertexOn(Corner<Policy>* cp[8], int edge, int x, int y, int z) {
    const int base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
    Corner<Policy>& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const Corner<Policy>& cb = *cp[base | (1 << axis)];
    const std::int64_t gi[3] = {g0_[0] + x + (base & 1), g0_[1] + y + ((base >> 1) & 1), g0_[2] + z + (base >> 2)};
    const VertexOut v = makeVertex(su_, gi, axis, ca.value, ca.g, cb.value, cb.g);
    out_.positions.push_back(v.position);
    out_.normals.push_back(v.normal);
    if constexpr (Policy::kHasUser) {
      const float tf = (su_.threshold - ca.value) / (cb.value - ca.value);
      out_.attributes.push_back(pol_.vertex(ca.user, cb.user, tf));
    }
    out_.keys.push_back(edgeKey(gi[0], gi[1], gi[2], axis));
    ca.vert[axis] = std::uint32_t(out_.positions.size());
    return ca.vert[axis] - 1;
  }

  void polygonize(const mc::CaseTable& cs, Corner<Policy>* cp[8], int x, int y, int z) {
    const std::int32_t slab = std::int32_t(g0_[2] + z);
    for (int tri = 0; tri < cs.triangleCount; ++tri) {
      std::uint32_t v[3];
      for (int k = 0; k < 3; ++k) v[k] = vertexOn(cp, cs.edges[3 * tri + k], x, y, z);
      if (su_.flip) std::swap(v[1], v[2]);
      out_.indices.insert(out_.indices.end(), {v[0], v[1], v[2]});
      out_.triSlab.push_back(slab);
    }
  }

  // Exact order (§5): one index range per slab, slabs in sweep order (stable counting sort).
  void sortBySlab() {
    const std::size_t nt = out_.triSlab.size();
    if (nt == 0) return;
    const std::int32_t base = std::int32_t(g0_[2]);
    auto& count = w_.slabCount;
    std::fill(count.begin(), count.end(), 0u);
    for (std::int32_t s : out_.triSlab) ++count[std::size_t(s - base) + 1];
    for (int i = 0; i < nz_; ++i) count[i + 1] += count[i];
    auto& tmp = out_.sortScratch;
    tmp.resize(nt * 3);
    for (std::size_t i = 0; i < nt; ++i) {
      const std::uint32_t dst = count[std::size_t(out_.triSlab[i] - base)]++;
      std::memcpy(&tmp[3 * dst], &out_.indices[3 * i], 3 * sizeof(std::uint32_t));
    }
    out_.indices.swap(tmp);
    std::sort(out_.triSlab.begin(), out_.triSlab.end());
  }
};

// ---------------------------------------------------------------------------------------------
// Approach 2 of §7 (baseline): surface-following marching cubes in the same blocks, with a full
// 3D corner cache per block and a point-insert / 3x3x3-lookup particle grid of cell size Rc.
struct FollowCorner {
  float value;
  float g[3];
  std::uint32_t vert[3];
  std::uint8_t evaluated, done;
};

struct FollowWorker {
  int n[3] = {-1, -1, -1}, grid[3] = {0, 0, 0};
  std::vector<Particle> particles;
  std::vector<FollowCorner> corners;
  std::vector<std::uint32_t> touched;
  std::vector<std::uint32_t> cellStart, cellItems, cellOf;
  std::vector<std::uint64_t> stack;
  std::uint64_t peakBytes = 0;
  void resize(const int dims[3], const int cells[3]) {
    if (dims[0] != n[0] || dims[1] != n[1] || dims[2] != n[2]) {
      for (int a = 0; a < 3; ++a) n[a] = dims[a];
      corners.assign(std::size_t(n[0] + 1) * std::size_t(n[1] + 1) * std::size_t(n[2] + 1), FollowCorner{});
    }
    for (int a = 0; a < 3; ++a) grid[a] = cells[a];
    cellStart.assign(std::size_t(grid[0]) * grid[1] * grid[2] + 1, 0);
  }
};

class BlockFollower {
 public:
  BlockFollower(FollowWorker& w, const Setup& su, BlockOut& out) : w_(w), su_(su), out_(out) {}

  void run(const BlockDesc& block, std::span<const Particle> particles) {
    out_.reset();
    blockOrigin(su_, block, g0_);
    w_.particles.assign(particles.begin(), particles.end());
    // Point insert: counting sort of particles by grid cell (stable: cells keep (z, index) order).
    const int* g = w_.grid;
    std::fill(w_.cellStart.begin(), w_.cellStart.end(), 0u);
    w_.cellOf.resize(w_.particles.size());
    w_.cellItems.resize(w_.particles.size());
    for (std::size_t i = 0; i < w_.particles.size(); ++i) {
      const Particle& p = w_.particles[i];
      int c[3];
      const double pc[3] = {p.x, p.y, p.z};
      for (int a = 0; a < 3; ++a)
        c[a] = std::clamp(ifloor((pc[a] - double(g0_[a]) * su_.s) / su_.rcMax), 0, g[a] - 1);
      w_.cellOf[i] = std::uint32_t((c[2] * g[1] + c[1]) * g[0] + c[0]);
      ++w_.cellStart[w_.cellOf[i] + 1];
    }
    for (std::size_t c = 1; c < w_.cellStart.size(); ++c) w_.cellStart[c] += w_.cellStart[c - 1];
    for (std::size_t i = 0; i < w_.particles.size(); ++i) w_.cellItems[w_.cellStart[w_.cellOf[i]]++] = std::uint32_t(i);
    for (std::size_t c = w_.cellStart.size() - 1; c > 0; --c) w_.cellStart[c] = w_.cellStart[c - 1];
    w_.cellStart[0] = 0;

    // Seeds as §4 (through the 3D cache), then depth-first surface following.
    const float t = su_.threshold;
    const double inv = 1.0 / su_.s;
    w_.stack.clear();
    for (const Particle& p : w_.particles) {
      const int x = iround(p.x * inv - double(g0_[0]));
      const int y = iround(p.y * inv - double(g0_[1]));
      int z = iround(p.z * inv - double(g0_[2]));
      if (x < 1 || x > su_.n[0] - 1 || y < 1 || y > su_.n[1] - 1 || z < 1 || z > su_.n[2] - 1) continue;
      if (!(corner(x, y, z).value > t)) continue;
      const int steps = iceil(std::sqrt(p.rc2) * inv) + 1;
      for (int i = 0; i < steps && z > 0; ++i, --z)
        if (!(corner(x, y, z - 1).value > t)) {
          w_.stack.push_back(pack(x, y, z - 1));
          break;
        }
    }
    const auto& table = mc::tables().cases[su_.octant];
    const int a = su_.m;
    while (!w_.stack.empty()) {
      const std::uint64_t item = w_.stack.back();
      w_.stack.pop_back();
      const int x = int(item & 0xffff), y = int((item >> 16) & 0xffff), z = int(item >> 32);
      FollowCorner& base = corner(x, y, z);
      if (base.done) continue;
      base.done = 1;
      ++out_.stats.cubesVisited;
      FollowCorner* cp[8];
      for (int c = 0; c < 8; ++c) cp[c] = &corner(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2));
      unsigned cube = 0;
      for (int c = 0; c < 8; ++c) cube |= unsigned(cp[c]->value > t) << c;
      if (cube == 0 || cube == 255) continue;
      const mc::CaseTable& cs = table[cube];
      if (x >= a && x < a + su_.b[0] && y >= a && y < a + su_.b[1] && z >= a && z < a + su_.b[2]) {
        for (int tri = 0; tri < cs.triangleCount; ++tri) {
          std::uint32_t v[3];
          for (int k = 0; k < 3; ++k) v[k] = vertexOn(cp, cs.edges[3 * tri + k], x, y, z);
          if (su_.flip) std::swap(v[1], v[2]);
          out_.indices.insert(out_.indices.end(), {v[0], v[1], v[2]});
          out_.triSlab.push_back(std::int32_t(g0_[2] + z));
        }
      }
      const unsigned f = cs.faceMask;
      auto push = [&](int px, int py, int pz) {
        if (!w_.corners[index(px, py, pz)].done) w_.stack.push_back(pack(px, py, pz));
      };
      if (f & 1) push(x - 1, y, z);
      if (f & 2) push(x + 1, y, z);
      if (f & 4) push(x, y - 1, z);
      if (f & 8) push(x, y + 1, z);
      if (f & 16) push(x, y, z - 1);
      if (f & 32) push(x, y, z + 1);
    }
    buildRuns(out_);
    out_.stats.triangles = out_.indices.size() / 3;
    out_.stats.vertices = out_.positions.size();
    // The whole 3D corner array and the particle grid are this approach's working set.
    out_.cornerBytes = w_.corners.size() * sizeof(FollowCorner);
    out_.particleBytes = w_.cellStart.size() * 4 + w_.cellItems.size() * 4 + w_.particles.size() * sizeof(Particle);
    w_.peakBytes = std::max(w_.peakBytes, out_.cornerBytes + out_.particleBytes);
    for (std::uint32_t i : w_.touched) w_.corners[i] = FollowCorner{};
    w_.touched.clear();
  }

 private:
  FollowWorker& w_;
  const Setup& su_;
  BlockOut& out_;
  std::int64_t g0_[3] = {0, 0, 0};

  static std::uint64_t pack(int x, int y, int z) {
    return std::uint64_t(x) | (std::uint64_t(y) << 16) | (std::uint64_t(z) << 32);
  }
  std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * std::size_t(su_.n[1] + 1) + std::size_t(y)) * std::size_t(su_.n[0] + 1) +
           std::size_t(x);
  }
  FollowCorner& corner(int x, int y, int z) {
    const std::size_t id = index(x, y, z);
    FollowCorner& c = w_.corners[id];
    if (c.evaluated) return c;
    c.evaluated = 1;
    w_.touched.push_back(std::uint32_t(id));
    ++out_.stats.cornersEvaluated;
    c.value = 0;
    // Zero on the expanded block's outer boundary, like marching slices (§3).
    if (x == 0 || y == 0 || z == 0 || x == su_.n[0] || y == su_.n[1] || z == su_.n[2]) return c;
    const double pc[3] = {double(g0_[0] + x) * su_.s, double(g0_[1] + y) * su_.s, double(g0_[2] + z) * su_.s};
    const int* g = w_.grid;
    int cc[3];
    for (int a = 0; a < 3; ++a) cc[a] = ifloor((pc[a] - double(g0_[a]) * su_.s) / su_.rcMax);
    float gx = 0, gy = 0, gz = 0;
    for (int k = std::max(0, cc[2] - 1); k <= std::min(g[2] - 1, cc[2] + 1); ++k)
      for (int j = std::max(0, cc[1] - 1); j <= std::min(g[1] - 1, cc[1] + 1); ++j)
        for (int i = std::max(0, cc[0] - 1); i <= std::min(g[0] - 1, cc[0] + 1); ++i) {
          const std::size_t cell = std::size_t((k * g[1] + j) * g[0] + i);
          for (std::uint32_t q = w_.cellStart[cell]; q < w_.cellStart[cell + 1]; ++q) {
            const Particle& p = w_.particles[w_.cellItems[q]];
            if (!influences(p, pc[0], pc[1], pc[2])) continue;
            ++out_.stats.particlesLookedUp;
            accumulate(p, g0_[0] + x, g0_[1] + y, g0_[2] + z, su_.s, c.value, gx, gy, gz);
          }
        }
    c.g[0] = gx;
    c.g[1] = gy;
    c.g[2] = gz;
    return c;
  }
  std::uint32_t vertexOn(FollowCorner* cp[8], int edge, int x, int y, int z) {
    const int base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
    FollowCorner& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const FollowCorner& cb = *cp[base | (1 << axis)];
    const std::int64_t gi[3] = {g0_[0] + x + (base & 1), g0_[1] + y + ((base >> 1) & 1), g0_[2] + z + (base >> 2)};
    const VertexOut v = makeVertex(su_, gi, axis, ca.value, ca.g, cb.value, cb.g);
    out_.positions.push_back(v.position);
    out_.normals.push_back(v.normal);
    out_.keys.push_back(edgeKey(gi[0], gi[1], gi[2], axis));
    ca.vert[axis] = std::uint32_t(out_.positions.size());
    return ca.vert[axis] - 1;
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
struct ExtractorState {
  std::vector<Particle> particles;
  struct Pair {
    std::uint64_t key;
    std::uint32_t rank;
  };
  std::vector<Pair> pairs;
  std::vector<Particle> blockParticles;
  std::vector<BlockDesc> blocks;
  std::vector<BlockOut> outs;
  std::vector<std::unique_ptr<Worker<PlainPolicy>>> plainWorkers;
  std::vector<std::unique_ptr<Worker<Vec4Policy>>> vec4Workers;
  std::vector<std::unique_ptr<FollowWorker>> followWorkers;
  std::unique_ptr<tbb::task_arena> arena;
  int arenaThreads = 0;
  int method = 1;  // 1 = marching slices, 2 = approach 2 (baseline, see baselines.hpp)
  std::vector<std::uint32_t> vertexBase, indexBase, runBase;
};

namespace {

SweepFrame chooseFrame(const SurfaceParams& p) {
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

template <class W, class Run>
void runParallel(ExtractorState& st, std::vector<std::unique_ptr<W>>& workers, Run&& run) {
  st.arena->execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, st.blocks.size(), 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
          W& w = *workers[std::size_t(tbb::this_task_arena::current_thread_index())];
          for (std::size_t i = r.begin(); i != r.end(); ++i) run(w, i);
        },
        tbb::simple_partitioner());
  });
}

template <class Policy>
void runBlocks(ExtractorState& st, const Setup& su, const Policy& policy,
               std::vector<std::unique_ptr<Worker<Policy>>>& workers) {
  const int slots = st.arena->max_concurrency();
  if (int(workers.size()) < slots) workers.resize(slots);
  for (auto& w : workers) {
    if (!w) w = std::make_unique<Worker<Policy>>();
    w->resize(su.n);
    w->peakBytes = 0;
  }
  runParallel(st, workers, [&](Worker<Policy>& w, std::size_t i) {
    const BlockDesc& b = st.blocks[i];
    BlockMesher<Policy> mesher(w, su, policy, st.outs[i]);
    mesher.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
  });
}

void runFollow(ExtractorState& st, const Setup& su) {
  auto& workers = st.followWorkers;
  const int slots = st.arena->max_concurrency();
  if (int(workers.size()) < slots) workers.resize(slots);
  int grid[3];
  for (int a = 0; a < 3; ++a) grid[a] = int(std::ceil(double(su.n[a]) * su.s / su.rcMax)) + 1;
  for (auto& w : workers) {
    if (!w) w = std::make_unique<FollowWorker>();
    w->resize(su.n, grid);
    w->peakBytes = 0;
  }
  runParallel(st, workers, [&](FollowWorker& w, std::size_t i) {
    const BlockDesc& b = st.blocks[i];
    BlockFollower f(w, su, st.outs[i]);
    f.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
  });
}

// Block grid (§3): blocks tile the lattice cubes that can hold surface (particles' extent
// grown by Rc) in equal parts of at most blockCubes per axis. The lattice itself is global
// (corners at integer multiples of S), so the tiling changes seams, never triangles.
void planBlocks(const std::vector<Particle>& ps, const SurfaceParams& params, Setup& su) {
  double lo[3] = {ps[0].x, ps[0].y, ps[0].z}, hi[3] = {ps[0].x, ps[0].y, ps[0].z};
  for (const Particle& p : ps) {
    lo[0] = std::min(lo[0], p.x), hi[0] = std::max(hi[0], p.x);
    lo[1] = std::min(lo[1], p.y), hi[1] = std::max(hi[1], p.y);
    lo[2] = std::min(lo[2], p.z), hi[2] = std::max(hi[2], p.z);
  }
  const int maxBlock = params.blockCubes > 0 ? params.blockCubes : std::max(32, 8 * su.m);
  for (int a = 0; a < 3; ++a) {
    const std::int64_t c0 = floorDiv(lo[a] - su.rcMax, su.s) - 1;
    const std::int64_t c1 = floorDiv(hi[a] + su.rcMax, su.s) + 2;
    const std::int64_t extent = std::max<std::int64_t>(1, c1 - c0);
    su.nb[a] = int((extent + maxBlock - 1) / maxBlock);
    su.b[a] = int((extent + su.nb[a] - 1) / su.nb[a]);
    su.n[a] = su.b[a] + 2 * su.m;
    su.lattice0[a] = c0;
  }
}

}  // namespace
}  // namespace detail

SurfaceExtractor::SurfaceExtractor() : state(std::make_unique<detail::ExtractorState>()) {}
SurfaceExtractor::~SurfaceExtractor() = default;
SurfaceExtractor::SurfaceExtractor(SurfaceExtractor&&) noexcept = default;
SurfaceExtractor& SurfaceExtractor::operator=(SurfaceExtractor&&) noexcept = default;

SurfaceStatus SurfaceExtractor::extract(const SurfaceInput& input, const SurfaceParams& params, SurfaceMesh& out) {
  using namespace detail;
  out.clear();
  SurfaceStatus status = validateSurface(input, params);
  if (!status.ok()) return status;
  ExtractorState& st = *state;

  Setup su;
  su.s = params.cube;
  su.threshold = params.threshold;
  su.frame = chooseFrame(params);
  su.flip = su.frame.flipsWinding();
  su.exact = params.order != SurfaceOrder::none && params.exactSlabOrder;
  su.origin[0] = params.originX;
  su.origin[1] = params.originY;
  su.origin[2] = params.originZ;
  prepareParticles(input, params, su.frame, st.particles, su.rcMax);
  if (st.particles.empty()) return {};
  su.m = std::max(1, int(std::ceil(su.rcMax / su.s)));  // margin of ceil(Rc/S) cubes (§3)
  planBlocks(st.particles, params, su);
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
  // Sorting (block, rank) pairs keeps each block's particles in (z, index) order.
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
          st.pairs.push_back({(std::uint64_t(bz) * std::uint64_t(su.nb[1]) + std::uint64_t(by)) * std::uint64_t(su.nb[0]) +
                                  std::uint64_t(bx),
                              r});
  }
  std::sort(st.pairs.begin(), st.pairs.end(), [](const ExtractorState::Pair& a, const ExtractorState::Pair& b) {
    return a.key < b.key || (a.key == b.key && a.rank < b.rank);
  });
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
  if (st.method == 2) {
    runFollow(st, su);
  } else if (input.user.empty()) {
    runBlocks(st, su, PlainPolicy{}, st.plainWorkers);
  } else {
    Vec4Policy pol;
    pol.user = input.user.data();
    runBlocks(st, su, pol, st.vec4Workers);
  }

  // Concatenate block outputs in emission order (prefix sums, then a parallel copy).
  const std::size_t nb = st.blocks.size();
  st.vertexBase.resize(nb + 1);
  st.indexBase.resize(nb + 1);
  st.runBase.resize(nb + 1);
  st.vertexBase[0] = st.indexBase[0] = st.runBase[0] = 0;
  SurfaceStats& stats = out.stats;
  for (std::size_t i = 0; i < nb; ++i) {
    const BlockOut& o = st.outs[i];
    if (std::uint64_t(st.vertexBase[i]) + o.positions.size() > 0xffffffffull ||
        std::uint64_t(st.indexBase[i]) + o.indices.size() > 0xffffffffull)
      return {"surface: mesh exceeds 2^32 vertices or indices"};
    st.vertexBase[i + 1] = st.vertexBase[i] + std::uint32_t(o.positions.size());
    st.indexBase[i + 1] = st.indexBase[i] + std::uint32_t(o.indices.size());
    st.runBase[i + 1] = st.runBase[i] + std::uint32_t(o.runs.size());
    stats.cubesVisited += o.stats.cubesVisited;
    stats.cornersEvaluated += o.stats.cornersEvaluated;
    stats.seedEvaluations += o.stats.seedEvaluations;
    stats.particlesLookedUp += o.stats.particlesLookedUp;
    stats.maxActiveSlices = std::max(stats.maxActiveSlices, o.stats.maxActiveSlices);
    stats.slabReversals += o.stats.slabReversals;
    stats.cornerCacheBytesPeakBlock = std::max(stats.cornerCacheBytesPeakBlock, o.cornerBytes);
    stats.particleCacheBytesPeakBlock = std::max(stats.particleCacheBytesPeakBlock, o.particleBytes);
  }
  const bool user = !input.user.empty() && st.method == 1;
  out.positions.resize(st.vertexBase[nb]);
  out.normals.resize(st.vertexBase[nb]);
  out.edgeKeys.resize(st.vertexBase[nb]);
  if (user) out.attributes.resize(st.vertexBase[nb]);
  out.indices.resize(st.indexBase[nb]);
  out.slabRuns.resize(st.runBase[nb]);
  out.blocks.resize(nb);
  st.arena->execute([&] {
    tbb::parallel_for(std::size_t(0), nb, [&](std::size_t i) {
      const BlockOut& o = st.outs[i];
      const std::uint32_t vb = st.vertexBase[i], ib = st.indexBase[i], rb = st.runBase[i];
      std::copy(o.positions.begin(), o.positions.end(), out.positions.begin() + vb);
      std::copy(o.normals.begin(), o.normals.end(), out.normals.begin() + vb);
      std::copy(o.keys.begin(), o.keys.end(), out.edgeKeys.begin() + vb);
      if (user) std::copy(o.attributes.begin(), o.attributes.end(), out.attributes.begin() + vb);
      for (std::size_t k = 0; k < o.indices.size(); ++k) out.indices[ib + k] = o.indices[k] + vb;
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
      br.indices = {ib, std::uint32_t(o.indices.size())};
      br.firstVertex = vb;
      br.vertexCount = std::uint32_t(o.positions.size());
      br.firstSlabRun = rb;
      br.slabRunCount = std::uint32_t(o.runs.size());
    });
  });
  stats.triangles = out.indices.size() / 3;
  stats.vertices = out.positions.size();
  stats.blocks = std::uint32_t(nb);
  std::uint64_t workBytes = 0;
  if (st.method == 2) {
    for (auto& w : st.followWorkers)
      if (w) workBytes += w->peakBytes;
  } else if (user) {
    for (auto& w : st.vec4Workers)
      if (w) workBytes += w->peakBytes;
  } else {
    for (auto& w : st.plainWorkers)
      if (w) workBytes += w->peakBytes;
  }
  stats.workingBytesAllWorkers = workBytes;
  return {};
}

float surfaceFieldAtCorner(const SurfaceInput& input, const SurfaceParams& params, std::int64_t i, std::int64_t j,
                           std::int64_t k) {
  std::vector<detail::Particle> ps;
  double rcMax = 0;
  detail::prepareParticles(input, params, detail::SweepFrame{}, ps, rcMax);
  const double s = params.cube;
  float value = 0, g[3] = {0, 0, 0};
  for (const detail::Particle& p : ps)
    if (detail::influences(p, double(i) * s, double(j) * s, double(k) * s))
      detail::accumulate(p, i, j, k, s, value, g[0], g[1], g[2]);
  return value;
}

namespace detail {
SurfaceStatus extractBlockedSurfaceFollowing(SurfaceExtractor& extractor, const SurfaceInput& input,
                                             const SurfaceParams& params, SurfaceMesh& out,
                                             std::uint64_t& cornerBytes, std::uint64_t& particleBytes) {
  extractor.state->method = 2;
  SurfaceStatus st = extractor.extract(input, params, out);
  extractor.state->method = 1;
  cornerBytes = out.stats.cornerCacheBytesPeakBlock;
  particleBytes = out.stats.particleCacheBytesPeakBlock;
  return st;
}

// Test hook (detail/testing.hpp).
struct BlockCacheProbe::Impl {
  Setup su;
  std::vector<Particle> blockParticles;
  Worker<PlainPolicy> worker;
  BlockOut out;
  PlainPolicy policy;
  BlockDesc block{};
  std::unique_ptr<BlockMesher<PlainPolicy>> mesher;
};

BlockCacheProbe::BlockCacheProbe(const SurfaceInput& input, const SurfaceParams& params, int bx, int by, int bz)
    : impl_(std::make_unique<Impl>()) {
  Setup& su = impl_->su;
  su.s = params.cube;
  su.threshold = params.threshold;
  prepareParticles(input, params, SweepFrame{}, particles, su.rcMax);
  su.m = std::max(1, int(std::ceil(su.rcMax / su.s)));
  // A fixed grid of blockCubes-sized blocks from lattice index 0, so the test can aim at seams.
  assert(params.blockCubes > 0);
  for (int a = 0; a < 3; ++a) {
    su.b[a] = params.blockCubes;
    su.n[a] = su.b[a] + 2 * su.m;
    su.nb[a] = 1 << 20;
    su.lattice0[a] = 0;
  }
  n = su.n[0];
  margin = su.m;
  const double bs = double(params.blockCubes) * su.s;
  const int bc[3] = {bx, by, bz};
  for (const Particle& p : particles) {
    const double rc = std::sqrt(p.rc2);
    const double pc[3] = {p.x, p.y, p.z};
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && floorDiv(pc[a] - rc, bs) <= bc[a] && bc[a] <= floorDiv(pc[a] + rc, bs);
    if (in) impl_->blockParticles.push_back(p);
  }
  impl_->worker.resize(su.n);
  impl_->block = BlockDesc{bx, by, bz, 0, std::uint32_t(impl_->blockParticles.size()), 0};
  impl_->mesher = std::make_unique<BlockMesher<PlainPolicy>>(impl_->worker, su, impl_->policy, impl_->out);
  impl_->mesher->prepareCache(impl_->block, impl_->blockParticles);
}
BlockCacheProbe::~BlockCacheProbe() = default;
void BlockCacheProbe::lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
  impl_->mesher->lookup(x, y, z, found);
}
}  // namespace detail

}  // namespace fluid
