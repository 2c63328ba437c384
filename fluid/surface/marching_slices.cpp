// Marching slices (Rosenberg & Birdwell 2008), one oneTBB task per block (Janisz §3.2.6).
// Section numbers below refer to the marching-slices paper; "Alg. 1" to DESIGN.md's restatement.
#include "fluid/surface/marching_slices.hpp"

#include "fluid/surface/detail/field.hpp"
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
  if (p.blockCubes < 4 || p.blockCubes > 1024)
    return bad("surface params: blockCubes = " + std::to_string(p.blockCubes) + " must be in [4, 1024]");
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
  void add(CornerData&, const Particle&, double) const {}
  glm::vec4 vertex(const CornerData&, const CornerData&, float) const { return {}; }
};

// Per-particle vec4 weighted by each particle's field contribution, normalised at the corner,
// then interpolated linearly along the edge like positions and normals.
struct Vec4Policy {
  struct CornerData {
    float v[4] = {0, 0, 0, 0};
    float weight = 0;
  };
  static constexpr bool kHasUser = true;
  const glm::vec4* user = nullptr;
  void add(CornerData& c, const Particle& p, double w) const {
    const glm::vec4 u = user[p.index];
    const float wf = float(w);
    c.v[0] += wf * u.x;
    c.v[1] += wf * u.y;
    c.v[2] += wf * u.z;
    c.v[3] += wf * u.w;
    c.weight += wf;
  }
  glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const {
    auto norm = [](const CornerData& c) {
      return c.weight > 0 ? glm::vec4(c.v[0], c.v[1], c.v[2], c.v[3]) / c.weight : glm::vec4(0.0f);
    };
    const glm::vec4 va = norm(a), vb = norm(b);
    // A corner with no particle (weight 0) takes the other end's value.
    if (a.weight <= 0) return vb;
    if (b.weight <= 0) return va;
    return va + t * (vb - va);
  }
};

// ---------------------------------------------------------------------------------------------
// Data structures of Figure 3 and §6.

// One element of a column list of the projection slice (§6): the particle influences corners
// min_z..max_z of this column; mid_z is the slab holding its centre. Lists are stored as
// contiguous z-sorted arrays (CSR) rather than doubly linked lists: the same walk, better locality.
struct ColumnEntry {
  std::int16_t minZ, maxZ, midZ, pad;
  std::uint32_t particle;  // into the block's particle array
};

template <class Policy>
struct Corner {
  double value;
  float g[3];               // field gradient (normals are -g, paper §2 "field values and normals")
  std::uint32_t vert[3];    // Ix, Iy, Iz: vertex index + 1 on the edge to +x, +y, +z (0 = none)
  std::int16_t x, y;        // for clearing the index array when the slice is returned (§4)
  [[no_unique_address]] typename Policy::CornerData user;
};

struct SliceCell {
  std::uint32_t corner = 0;  // corner index + 1 (0 = not evaluated)
  std::uint8_t doneAbove = 0, doneBelow = 0;
};

template <class Policy>
struct Slice {
  std::vector<SliceCell> cells;  // (N+1)^2 corner index array
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
};

// Per-worker scratch, reused across blocks and frames.
template <class Policy>
struct Worker {
  int n = -1;  // cubes per expanded block edge (N = B + 2m); corners 0..N
  std::vector<Particle> particles;
  std::vector<std::uint32_t> colStart, cursor;
  std::vector<ColumnEntry> entries;
  std::vector<std::uint32_t> entryColumn;  // temporary: column of each entry before the scatter
  std::vector<ColumnEntry> entryTemp;
  std::vector<double> cx, cy, cz;  // corner coordinates of local indices
  std::vector<std::int16_t> chainLo, chainHi;  // seeding memo per column
  std::vector<std::uint32_t> chainTouched;
  std::vector<std::unique_ptr<Slice<Policy>>> slicePool;
  std::vector<Slice<Policy>*> freeSlices;
  std::vector<Slice<Policy>*> active;  // per slice z (0..N)
  std::vector<std::vector<std::uint32_t>> todo;  // per slab z (0..N-1)
  std::uint64_t peakBytes = 0;

  void resize(int newN) {
    if (newN == n) return;
    n = newN;
    const std::size_t cols = std::size_t(n + 1) * std::size_t(n + 1);
    colStart.assign(cols + 1, 0);
    cursor.assign(cols, 0);
    cx.assign(n + 1, 0);
    cy.assign(n + 1, 0);
    cz.assign(n + 1, 0);
    chainLo.assign(cols, 0);
    chainHi.assign(cols, -1);
    slicePool.clear();
    freeSlices.clear();
    active.assign(n + 1, nullptr);
    todo.resize(n);
  }

  Slice<Policy>* acquireSlice() {
    if (freeSlices.empty()) {
      slicePool.push_back(std::make_unique<Slice<Policy>>());
      slicePool.back()->cells.assign(std::size_t(n + 1) * std::size_t(n + 1), SliceCell{});
      freeSlices.push_back(slicePool.back().get());
    }
    Slice<Policy>* s = freeSlices.back();
    freeSlices.pop_back();
    return s;
  }
  // Returns a slice to the pool, clearing only the entries it touched (§4).
  void releaseSlice(Slice<Policy>* s) {
    for (const Corner<Policy>& c : s->corners) s->cells[std::size_t(c.y) * std::size_t(n + 1) + c.x] = SliceCell{};
    s->corners.clear();
    freeSlices.push_back(s);
  }
};

struct Setup {
  double s = 1, threshold = 0.2, rcMax = 3;
  int b = 32, m = 3, n = 38;
  int octant = 0;
  bool exact = false;
  bool flip = false;
  SweepFrame frame;
  double origin[3] = {0, 0, 0};  // world origin
};

// ---------------------------------------------------------------------------------------------
// The per-block algorithm.
template <class Policy>
class BlockMesher {
 public:
  BlockMesher(Worker<Policy>& w, const Setup& setup, const Policy& policy, BlockOut& out)
      : w_(w), su_(setup), pol_(policy), out_(out), n_(setup.n), stride_(setup.n + 1) {}

  void run(const BlockDesc& block, std::span<const Particle> particles) {
    out_.positions.clear();
    out_.normals.clear();
    out_.attributes.clear();
    out_.keys.clear();
    out_.indices.clear();
    out_.triSlab.clear();
    out_.runs.clear();
    out_.stats = {};
    g0_[0] = std::int64_t(block.bx) * su_.b - su_.m;
    g0_[1] = std::int64_t(block.by) * su_.b - su_.m;
    g0_[2] = std::int64_t(block.bz) * su_.b - su_.m;
    for (int i = 0; i <= n_; ++i) {
      w_.cx[i] = double(g0_[0] + i) * su_.s;
      w_.cy[i] = double(g0_[1] + i) * su_.s;
      w_.cz[i] = double(g0_[2] + i) * su_.s;
    }
    w_.particles.assign(particles.begin(), particles.end());
    buildParticleCache();
    seed();
    march();
    if (su_.exact) sortBySlab();
    buildRuns();
    out_.stats.triangles = out_.indices.size() / 3;
    out_.stats.vertices = out_.positions.size();
    out_.particleBytes = std::uint64_t(w_.colStart.size() + w_.cursor.size()) * sizeof(std::uint32_t) +
                         std::uint64_t(w_.entries.size()) * sizeof(ColumnEntry) +
                         std::uint64_t(w_.particles.size()) * sizeof(Particle);
    out_.cornerBytes = peakCornerBytes_;
    w_.peakBytes = std::max(w_.peakBytes, out_.particleBytes + out_.cornerBytes);
  }

  // Test hook (detail/testing.hpp): build the particle cache only, then look up corners.
  void prepareCache(const BlockDesc& block, std::span<const Particle> particles) {
    g0_[0] = std::int64_t(block.bx) * su_.b - su_.m;
    g0_[1] = std::int64_t(block.by) * su_.b - su_.m;
    g0_[2] = std::int64_t(block.bz) * su_.b - su_.m;
    for (int i = 0; i <= n_; ++i) {
      w_.cx[i] = double(g0_[0] + i) * su_.s;
      w_.cy[i] = double(g0_[1] + i) * su_.s;
      w_.cz[i] = double(g0_[2] + i) * su_.s;
    }
    w_.particles.assign(particles.begin(), particles.end());
    buildParticleCache();
  }
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
    found.clear();
    forEachInfluencing(x, y, z, [&](const Particle& p) { found.push_back(p.index); });
  }

 private:
  Worker<Policy>& w_;
  const Setup& su_;
  const Policy& pol_;
  BlockOut& out_;
  const int n_, stride_;
  std::int64_t g0_[3] = {0, 0, 0};
  int window_ = 0;  // max |mid_z - min_z|, |max_z - mid_z| over entries: the lookup window
  int activeSlices_ = 0;
  std::uint64_t peakCornerBytes_ = 0;

  std::size_t col(int x, int y) const { return std::size_t(y) * std::size_t(stride_) + std::size_t(x); }

  // §6: sort by z (already: particles arrive in (z, index) order), insert one element per column
  // of the projection slice within Rc_i; skip boundary columns and clamp min_z/max_z to
  // [1, N-1] so the field is zero on the outer boundary of the expanded block (§3).
  void buildParticleCache() {
    const std::size_t cols = std::size_t(stride_) * std::size_t(stride_);
    std::fill(w_.colStart.begin(), w_.colStart.end(), 0u);
    w_.entryTemp.clear();
    w_.entryColumn.clear();
    window_ = 0;
    const double s = su_.s;
    for (std::uint32_t pi = 0; pi < w_.particles.size(); ++pi) {
      const Particle& p = w_.particles[pi];
      const double rc = std::sqrt(p.rc2);
      const int x0 = std::max(1, int(std::ceil((p.x - rc) / s) - g0_[0]) - 1);
      const int x1 = std::min(n_ - 1, int(std::floor((p.x + rc) / s) - g0_[0]) + 1);
      const int y0 = std::max(1, int(std::ceil((p.y - rc) / s) - g0_[1]) - 1);
      const int y1 = std::min(n_ - 1, int(std::floor((p.y + rc) / s) - g0_[1]) + 1);
      const int mid = int(std::floor(p.z / s) - double(g0_[2]));
      for (int y = y0; y <= y1; ++y) {
        const double dy = w_.cy[y] - p.y;
        for (int x = x0; x <= x1; ++x) {
          const double dx = w_.cx[x] - p.x;
          const double dxy = dx * dx + dy * dy;
          if (!(dxy < p.rc2)) continue;  // dz*dz >= 0, so no corner of the column is within Rc
          const double h = std::sqrt(p.rc2 - dxy);
          // Candidate range from the closed form, then corrected with the exact predicate so
          // the cache returns precisely the particles influences() accepts.
          auto inside = [&](int z) {
            const double dz = w_.cz[z] - p.z;
            return dxy + dz * dz < p.rc2;
          };
          const double fz = p.z / s - double(g0_[2]);
          int zc = int(std::lround(fz));
          zc = std::clamp(zc, 1, n_ - 1);
          int lo = std::clamp(int(std::ceil(fz - h / s)), 1, n_ - 1);
          int hi = std::clamp(int(std::floor(fz + h / s)), 1, n_ - 1);
          while (lo > 1 && inside(lo - 1)) --lo;
          while (lo <= hi && !inside(lo)) ++lo;
          while (hi < n_ - 1 && inside(hi + 1)) ++hi;
          while (hi >= lo && !inside(hi)) --hi;
          (void)zc;
          if (lo > hi) continue;
          window_ = std::max({window_, mid - lo, hi - mid});
          w_.entryTemp.push_back(
              ColumnEntry{std::int16_t(lo), std::int16_t(hi), std::int16_t(std::clamp(mid, -30000, 30000)), 0, pi});
          const std::uint32_t c = std::uint32_t(col(x, y));
          w_.entryColumn.push_back(c);
          ++w_.colStart[c + 1];
        }
      }
    }
    for (std::size_t c = 0; c < cols; ++c) w_.colStart[c + 1] += w_.colStart[c];
    for (std::size_t c = 0; c < cols; ++c) w_.cursor[c] = w_.colStart[c];
    w_.entries.resize(w_.entryTemp.size());
    // Stable scatter keeps each column in particle (z) order.
    for (std::size_t i = 0; i < w_.entryTemp.size(); ++i) w_.entries[w_.cursor[w_.entryColumn[i]]++] = w_.entryTemp[i];
    for (std::size_t c = 0; c < cols; ++c) w_.cursor[c] = w_.colStart[c];
  }

  // §6 lookup: find the bottom-most entry with mid_z >= z - window from the column's start pointer,
  // walk up while mid_z <= z + window, keep min_z <= z <= max_z; update the start pointer.
  // Visits the particles influencing corner (x, y, z), in column (z, index) order.
  template <class F>
  void forEachInfluencing(int x, int y, int z, F&& f) {
    const std::size_t k = col(x, y);
    const std::uint32_t begin = w_.colStart[k], end = w_.colStart[k + 1];
    if (begin == end) return;
    std::uint32_t cur = w_.cursor[k];
    const int lo = z - window_, hi = z + window_;
    while (cur > begin && w_.entries[cur - 1].midZ >= lo) --cur;
    while (cur < end && w_.entries[cur].midZ < lo) ++cur;
    w_.cursor[k] = cur;  // the start-pointer update of §6
    for (std::uint32_t i = cur; i < end; ++i) {
      const ColumnEntry& e = w_.entries[i];
      if (e.midZ > hi) break;
      if (e.minZ > z || e.maxZ < z) continue;
      f(w_.particles[e.particle]);
    }
  }

  template <bool kGradient>
  void evaluate(int x, int y, int z, Corner<Policy>& c) {
    c.g[0] = c.g[1] = c.g[2] = 0;
    c.user = {};
    const double px = w_.cx[x], py = w_.cy[y], pz = w_.cz[z];
    double v = 0, gx = 0, gy = 0, gz = 0;
    std::uint64_t looked = 0;
    forEachInfluencing(x, y, z, [&](const Particle& p) {
      ++looked;
      if constexpr (kGradient || Policy::kHasUser) {
        const double before = v;
        accumulate(p, px, py, pz, v, gx, gy, gz);
        if constexpr (Policy::kHasUser) pol_.add(c.user, p, v - before);
      } else {
        v += contribution(p, px, py, pz);
      }
    });
    out_.stats.particlesLookedUp += looked;
    c.value = v;
    if constexpr (kGradient) {
      c.g[0] = float(gx);
      c.g[1] = float(gy);
      c.g[2] = float(gz);
    }
  }

  double fieldAt(int x, int y, int z) {
    Corner<Policy> c;
    evaluate<false>(x, y, z, c);
    ++out_.stats.seedEvaluations;
    return c.value;
  }

  bool interiorCorner(int x, int y, int z) const {
    const int a = su_.m, b = su_.m + su_.b;
    return x >= a && x <= b && y >= a && y <= b && z >= a && z <= b;
  }

  // Seeding (§4): snap each particle to its nearest corner and step down -z until the field is
  // at or below T; push the cube whose vertical edge holds the crossing into that slab's todo.
  // Stop after Rc_i. A per-column memo of descents already done skips particles whose descent
  // reaches a corner another descent already walked (same connected inside region: same seed).
  void seed() {
    for (std::uint32_t c : w_.chainTouched) {
      w_.chainLo[c] = 0;
      w_.chainHi[c] = -1;
    }
    w_.chainTouched.clear();
    const double s = su_.s, t = su_.threshold;
    for (const Particle& p : w_.particles) {
      const int x = int(std::llround(p.x / s) - g0_[0]);
      const int y = int(std::llround(p.y / s) - g0_[1]);
      const int z0 = int(std::llround(p.z / s) - g0_[2]);
      if (x < 1 || x > n_ - 1 || y < 1 || y > n_ - 1 || z0 < 1 || z0 > n_ - 1) continue;
      const std::size_t k = col(x, y);
      if (z0 >= w_.chainLo[k] && z0 <= w_.chainHi[k]) continue;
      const int steps = int(std::ceil(std::sqrt(p.rc2) / s)) + 1;
      int z = z0;
      if (!(fieldAt(x, y, z) > t)) continue;  // centre corner outside: nothing to seed from here
      bool joined = false;
      int lowest = z;
      for (int i = 0; i < steps && z > 0; ++i) {
        const int below = z - 1;
        if (below >= w_.chainLo[k] && below <= w_.chainHi[k]) {
          joined = true;
          break;
        }
        if (!(fieldAt(x, y, below) > t)) {
          pushTodo(below, x, y);
          lowest = z;
          joined = true;
          break;
        }
        z = below;
        lowest = z;
      }
      if (!joined) continue;  // went Rc down without leaving: a particle below seeds it (§4)
      // Keep one walked run per column: merge when it touches the old one, else replace it
      // (a gap between two runs is not known to be inside).
      if (w_.chainHi[k] < w_.chainLo[k]) w_.chainTouched.push_back(std::uint32_t(k));
      if (w_.chainHi[k] >= w_.chainLo[k] && lowest <= w_.chainHi[k] + 1 && z0 >= w_.chainLo[k] - 1) {
        w_.chainLo[k] = std::int16_t(std::min<int>(w_.chainLo[k], lowest));
        w_.chainHi[k] = std::int16_t(std::max<int>(w_.chainHi[k], z0));
      } else {
        w_.chainLo[k] = std::int16_t(lowest);
        w_.chainHi[k] = std::int16_t(z0);
      }
    }
  }

  int lowestTodo_ = std::numeric_limits<int>::max();
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
  void notePeak() {
    std::uint64_t bytes = 0;
    for (int z = 0; z <= n_; ++z)
      if (w_.active[z])
        bytes += w_.active[z]->cells.size() * sizeof(SliceCell) + w_.active[z]->corners.size() * sizeof(Corner<Policy>);
    peakCornerBytes_ = std::max(peakCornerBytes_, bytes);
  }

  std::uint32_t lookupOrEval(Slice<Policy>& slice, int x, int y, int z) {
    SliceCell& cell = slice.cells[col(x, y)];
    if (cell.corner) return cell.corner - 1;
    Corner<Policy> c;
    if (interiorCorner(x, y, z))
      evaluate<true>(x, y, z, c);
    else
      evaluate<false>(x, y, z, c);  // margin: the sign is all that is needed (§3)
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
    const double t = su_.threshold;
    const auto& table = mc::tables().cases[su_.octant];
    int z = lowestTodo_;
    while (true) {
      // Lowest slab with work.
      while (z < n_ && w_.todo[z].empty()) ++z;
      if (z >= n_) break;
      Slice<Policy>* below = ensureSlice(z);
      Slice<Policy>* above = ensureSlice(z + 1);
      auto& list = w_.todo[z];
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
        if (cube == 0 || cube == 255) continue;  // seeds can land on empty cubes only by rounding
        const mc::CaseTable& cs = table[cube];
        const int a = su_.m, b = su_.m + su_.b;
        if (x >= a && x < b && y >= a && y < b && z >= a && z < b) polygonize(cs, cp, x, y, z);
        // Push neighbours across crossed faces unless done (Alg. 1).
        const unsigned f = cs.faceMask;
        if ((f & 1) && !below->cells[col(x - 1, y)].doneAbove) list.push_back(item - 1);
        if ((f & 2) && !below->cells[col(x + 1, y)].doneAbove) list.push_back(item + 1);
        if ((f & 4) && !below->cells[col(x, y - 1)].doneAbove) list.push_back(item - (1u << 16));
        if ((f & 8) && !below->cells[col(x, y + 1)].doneAbove) list.push_back(item + (1u << 16));
        if ((f & 16) && !below->cells[col(x, y)].doneBelow) {
          assert(z > 0);
          w_.todo[z - 1].push_back(item);
        }
        if ((f & 32) && !above->cells[col(x, y)].doneAbove) {
          assert(z + 1 < n_);
          w_.todo[z + 1].push_back(item);
        }
      }
      notePeak();
      // Return slices no neighbouring slab still needs (Alg. 1, end of the slab).
      const bool belowEmpty = z == 0 || w_.todo[z - 1].empty();
      const bool aboveEmpty = z + 1 >= n_ || w_.todo[z + 1].empty();
      if (belowEmpty) freeSlice(z);
      if (aboveEmpty) freeSlice(z + 1);
      if (!belowEmpty) {  // the sweep reverses: slab z-1 got work from this one
        --z;
        ++out_.stats.slabReversals;
      }
    }
    for (int i = 0; i <= n_; ++i) freeSlice(i);
  }

  std::uint32_t vertexOn(Corner<Policy>* cp[8], int edge, int x, int y, int z) {
    const int base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
    Corner<Policy>& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const Corner<Policy>& cb = *cp[base | (1 << axis)];
    // Linear interpolation of position and normal (paper §2, the default vertex routine).
    const double tt = (su_.threshold - ca.value) / (cb.value - ca.value);
    const int lx = x + (base & 1), ly = y + ((base >> 1) & 1), lz = z + ((base >> 2) & 1);
    const std::int64_t gi[3] = {g0_[0] + lx, g0_[1] + ly, g0_[2] + lz};
    double local[3] = {double(gi[0]) * su_.s, double(gi[1]) * su_.s, double(gi[2]) * su_.s};
    local[axis] += tt * su_.s;
    const float tf = float(tt);
    float g[3];
    for (int i = 0; i < 3; ++i) g[i] = ca.g[i] + tf * (cb.g[i] - ca.g[i]);
    float len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    float nl[3];
    if (len2 > 1e-30f && std::isfinite(len2)) {
      const float inv = -1.0f / std::sqrt(len2);
      for (int i = 0; i < 3; ++i) nl[i] = g[i] * inv;
    } else {
      // Flat gradient (e.g. symmetric cancellation): point along the edge, inside -> outside.
      nl[0] = nl[1] = nl[2] = 0;
      nl[axis] = ca.value > su_.threshold ? 1.0f : -1.0f;
    }
    glm::vec3 pw, nw;
    for (int a = 0; a < 3; ++a) {
      const int wa = su_.frame.axis[a];
      pw[wa] = float(su_.frame.sign[a] * local[a] - su_.origin[wa]);
      nw[wa] = float(su_.frame.sign[a]) * nl[a];
    }
    out_.positions.push_back(pw);
    out_.normals.push_back(nw);
    if constexpr (Policy::kHasUser) out_.attributes.push_back(pol_.vertex(ca.user, cb.user, tf));
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
    auto& count = w_.colStart;  // reuse a scratch of size >= N+1 (rebuilt next block)
    std::fill(count.begin(), count.begin() + n_ + 1, 0u);
    for (std::int32_t s : out_.triSlab) ++count[std::size_t(s - base) + 1];
    for (int i = 0; i < n_; ++i) count[i + 1] += count[i];
    auto& tmp = out_.sortScratch;
    tmp.resize(nt * 3);
    for (std::size_t i = 0; i < nt; ++i) {
      const std::uint32_t dst = count[std::size_t(out_.triSlab[i] - base)]++;
      std::memcpy(&tmp[3 * dst], &out_.indices[3 * i], 3 * sizeof(std::uint32_t));
    }
    out_.indices.swap(tmp);
    std::sort(out_.triSlab.begin(), out_.triSlab.end());
  }

  void buildRuns() {
    for (std::size_t i = 0; i < out_.triSlab.size(); ++i) {
      const std::int32_t s = out_.triSlab[i];
      if (out_.runs.empty() || out_.runs.back().slab != s)
        out_.runs.push_back(SurfaceSlabRun{s, IndexRange{std::uint32_t(3 * i), 0}});
      out_.runs.back().indices.count += 3;
    }
  }
};


// ---------------------------------------------------------------------------------------------
// Approach 2 of §7 (baseline): surface-following marching cubes in the same blocks, with a full
// 3D corner cache per block and a point-insert / 3x3x3-lookup particle grid of cell size Rc.
struct FollowCorner {
  double value;
  float g[3];
  std::uint32_t vert[3];
  std::uint8_t evaluated, done;
};

struct FollowWorker {
  int n = -1, grid = 0;
  std::vector<Particle> particles;
  std::vector<FollowCorner> corners;
  std::vector<std::uint32_t> touched;
  std::vector<std::uint32_t> cellStart, cellItems, cellOf;
  std::vector<std::uint64_t> stack;
  std::uint64_t peakBytes = 0;
  void resize(int newN, int newGrid) {
    if (newN != n) {
      n = newN;
      corners.assign(std::size_t(n + 1) * std::size_t(n + 1) * std::size_t(n + 1), FollowCorner{});
    }
    grid = newGrid;
    cellStart.assign(std::size_t(grid) * grid * grid + 1, 0);
  }
};

class BlockFollower {
 public:
  BlockFollower(FollowWorker& w, const Setup& su, BlockOut& out) : w_(w), su_(su), out_(out), n_(su.n) {}

  void run(const BlockDesc& block, std::span<const Particle> particles) {
    out_.positions.clear();
    out_.normals.clear();
    out_.attributes.clear();
    out_.keys.clear();
    out_.indices.clear();
    out_.triSlab.clear();
    out_.runs.clear();
    out_.stats = {};
    g0_[0] = std::int64_t(block.bx) * su_.b - su_.m;
    g0_[1] = std::int64_t(block.by) * su_.b - su_.m;
    g0_[2] = std::int64_t(block.bz) * su_.b - su_.m;
    w_.particles.assign(particles.begin(), particles.end());
    // Point insert: counting sort of particles by grid cell (stable, so cells keep (z, index) order).
    const int g = w_.grid;
    std::fill(w_.cellStart.begin(), w_.cellStart.end(), 0u);
    w_.cellOf.resize(w_.particles.size());
    w_.cellItems.resize(w_.particles.size());
    for (std::size_t i = 0; i < w_.particles.size(); ++i) {
      const Particle& p = w_.particles[i];
      int c[3];
      const double pc[3] = {p.x, p.y, p.z};
      for (int a = 0; a < 3; ++a)
        c[a] = std::clamp(int(std::floor((pc[a] - double(g0_[a]) * su_.s) / su_.rcMax)), 0, g - 1);
      w_.cellOf[i] = std::uint32_t((c[2] * g + c[1]) * g + c[0]);
      ++w_.cellStart[w_.cellOf[i] + 1];
    }
    for (std::size_t c = 1; c < w_.cellStart.size(); ++c) w_.cellStart[c] += w_.cellStart[c - 1];
    for (std::size_t i = 0; i < w_.particles.size(); ++i) w_.cellItems[w_.cellStart[w_.cellOf[i]]++] = std::uint32_t(i);
    for (std::size_t c = w_.cellStart.size() - 1; c > 0; --c) w_.cellStart[c] = w_.cellStart[c - 1];
    w_.cellStart[0] = 0;

    // Seeds as §4 (through the 3D cache), then depth-first surface following.
    const double t = su_.threshold;
    w_.stack.clear();
    for (const Particle& p : w_.particles) {
      const int x = int(std::llround(p.x / su_.s) - g0_[0]);
      const int y = int(std::llround(p.y / su_.s) - g0_[1]);
      int z = int(std::llround(p.z / su_.s) - g0_[2]);
      if (x < 1 || x > n_ - 1 || y < 1 || y > n_ - 1 || z < 1 || z > n_ - 1) continue;
      if (!(corner(x, y, z).value > t)) continue;
      const int steps = int(std::ceil(std::sqrt(p.rc2) / su_.s)) + 1;
      for (int i = 0; i < steps && z > 0; ++i, --z)
        if (!(corner(x, y, z - 1).value > t)) {
          w_.stack.push_back(pack(x, y, z - 1));
          break;
        }
    }
    const auto& table = mc::tables().cases[su_.octant];
    const int a = su_.m, b = su_.m + su_.b;
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
      if (x >= a && x < b && y >= a && y < b && z >= a && z < b) {
        for (int tri = 0; tri < cs.triangleCount; ++tri) {
          std::uint32_t v[3];
          for (int k = 0; k < 3; ++k) v[k] = vertexOn(cp, cs.edges[3 * tri + k], x, y, z);
          out_.indices.insert(out_.indices.end(), {v[0], v[1], v[2]});
          out_.triSlab.push_back(std::int32_t(g0_[2] + z));
        }
      }
      const unsigned f = cs.faceMask;
      auto push = [&](int px, int py, int pz) {
        const FollowCorner& c = w_.corners[index(px, py, pz)];
        if (!(c.evaluated && c.done)) w_.stack.push_back(pack(px, py, pz));
      };
      if (f & 1) push(x - 1, y, z);
      if (f & 2) push(x + 1, y, z);
      if (f & 4) push(x, y - 1, z);
      if (f & 8) push(x, y + 1, z);
      if (f & 16) push(x, y, z - 1);
      if (f & 32) push(x, y, z + 1);
    }
    for (std::size_t i = 0; i < out_.triSlab.size(); ++i) {
      const std::int32_t s = out_.triSlab[i];
      if (out_.runs.empty() || out_.runs.back().slab != s)
        out_.runs.push_back(SurfaceSlabRun{s, IndexRange{std::uint32_t(3 * i), 0}});
      out_.runs.back().indices.count += 3;
    }
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
  const int n_;
  std::int64_t g0_[3] = {0, 0, 0};

  static std::uint64_t pack(int x, int y, int z) {
    return std::uint64_t(x) | (std::uint64_t(y) << 16) | (std::uint64_t(z) << 32);
  }
  std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * std::size_t(n_ + 1) + std::size_t(y)) * std::size_t(n_ + 1) + std::size_t(x);
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
    if (x == 0 || y == 0 || z == 0 || x == n_ || y == n_ || z == n_) return c;
    const double cx = double(g0_[0] + x) * su_.s, cy = double(g0_[1] + y) * su_.s, cz = double(g0_[2] + z) * su_.s;
    const int g = w_.grid;
    int cc[3];
    const double pc[3] = {cx, cy, cz};
    for (int a = 0; a < 3; ++a) cc[a] = int(std::floor((pc[a] - double(g0_[a]) * su_.s) / su_.rcMax));
    double gx = 0, gy = 0, gz = 0;
    for (int k = std::max(0, cc[2] - 1); k <= std::min(g - 1, cc[2] + 1); ++k)
      for (int j = std::max(0, cc[1] - 1); j <= std::min(g - 1, cc[1] + 1); ++j)
        for (int i = std::max(0, cc[0] - 1); i <= std::min(g - 1, cc[0] + 1); ++i) {
          const std::size_t cell = std::size_t((k * g + j) * g + i);
          for (std::uint32_t q = w_.cellStart[cell]; q < w_.cellStart[cell + 1]; ++q) {
            const Particle& p = w_.particles[w_.cellItems[q]];
            if (!influences(p, cx, cy, cz)) continue;
            ++out_.stats.particlesLookedUp;
            accumulate(p, cx, cy, cz, c.value, gx, gy, gz);
          }
        }
    c.g[0] = float(gx);
    c.g[1] = float(gy);
    c.g[2] = float(gz);
    return c;
  }
  std::uint32_t vertexOn(FollowCorner* cp[8], int edge, int x, int y, int z) {
    const int base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
    FollowCorner& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const FollowCorner& cb = *cp[base | (1 << axis)];
    const double tt = (su_.threshold - ca.value) / (cb.value - ca.value);
    const std::int64_t gi[3] = {g0_[0] + x + (base & 1), g0_[1] + y + ((base >> 1) & 1), g0_[2] + z + (base >> 2)};
    double local[3] = {double(gi[0]) * su_.s, double(gi[1]) * su_.s, double(gi[2]) * su_.s};
    local[axis] += tt * su_.s;
    const float tf = float(tt);
    float g[3];
    for (int i = 0; i < 3; ++i) g[i] = ca.g[i] + tf * (cb.g[i] - ca.g[i]);
    const float len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    float nl[3] = {0, 0, 0};
    if (len2 > 1e-30f && std::isfinite(len2)) {
      const float inv = -1.0f / std::sqrt(len2);
      for (int i = 0; i < 3; ++i) nl[i] = g[i] * inv;
    } else {
      nl[axis] = ca.value > su_.threshold ? 1.0f : -1.0f;
    }
    glm::vec3 pw, nw;
    for (int a = 0; a < 3; ++a) {
      const int wa = su_.frame.axis[a];
      pw[wa] = float(su_.frame.sign[a] * local[a] - su_.origin[wa]);
      nw[wa] = float(su_.frame.sign[a]) * nl[a];
    }
    out_.positions.push_back(pw);
    out_.normals.push_back(nw);
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
  std::vector<std::uint32_t> order;
  std::vector<BlockOut> outs;
  std::vector<std::unique_ptr<Worker<PlainPolicy>>> plainWorkers;
  std::vector<std::unique_ptr<Worker<Vec4Policy>>> vec4Workers;
  std::vector<std::unique_ptr<FollowWorker>> followWorkers;
  int method = 1;  // 1 = marching slices, 2 = approach 2 (baseline)
  std::unique_ptr<tbb::task_arena> arena;
  int arenaThreads = 0;
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
  // Sweep axis a becomes local z. Back-to-front sweeps towards the eye (against the view).
  const int sweepSign = (d[a] > 0 ? -1 : 1) * (p.order == SurfaceOrder::backToFront ? 1 : -1);
  const int others[3][2] = {{1, 2}, {2, 0}, {0, 1}};  // cyclic, so the frame is a rotation when signs agree
  f.axis[0] = others[a][0];
  f.axis[1] = others[a][1];
  f.axis[2] = a;
  f.sign[0] = 1;
  f.sign[1] = sweepSign;
  f.sign[2] = sweepSign;
  return f;
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
  st.arena->execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, st.blocks.size(), 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
          const int slot = tbb::this_task_arena::current_thread_index();
          Worker<Policy>& w = *workers[std::size_t(slot)];
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const BlockDesc& b = st.blocks[i];
            BlockMesher<Policy> mesher(w, su, policy, st.outs[i]);
            mesher.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
          }
        },
        tbb::simple_partitioner());
  });
}


void runFollow(ExtractorState& st, const Setup& su, std::vector<std::unique_ptr<FollowWorker>>& workers) {
  const int slots = st.arena->max_concurrency();
  if (int(workers.size()) < slots) workers.resize(slots);
  const int grid = int(std::ceil(double(su.n) * su.s / su.rcMax)) + 1;
  for (auto& w : workers) {
    if (!w) w = std::make_unique<FollowWorker>();
    w->resize(su.n, grid);
    w->peakBytes = 0;
  }
  st.arena->execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, st.blocks.size(), 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
          FollowWorker& w = *workers[std::size_t(tbb::this_task_arena::current_thread_index())];
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const BlockDesc& b = st.blocks[i];
            BlockFollower f(w, su, st.outs[i]);
            f.run(b, std::span<const Particle>(st.blockParticles.data() + b.first, b.count));
          }
        },
        tbb::simple_partitioner());
  });
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
  su.b = params.blockCubes;
  su.frame = chooseFrame(params);
  su.flip = su.frame.flipsWinding();
  su.exact = params.order != SurfaceOrder::none && params.exactSlabOrder;
  su.origin[0] = params.originX;
  su.origin[1] = params.originY;
  su.origin[2] = params.originZ;
  prepareParticles(input, params, su.frame, st.particles, su.rcMax);
  su.m = std::max(1, int(std::ceil(su.rcMax / su.s)));  // margin of ceil(Rc/S) cubes (§3)
  su.n = su.b + 2 * su.m;
  if (su.n + 1 > 32000) return {"surface params: blockCubes + 2 ceil(rc/cube) is too large"};
  {
    // View octant in the sweep frame, for the in-cube order tables.
    const float d[3] = {params.viewDir.x, params.viewDir.y, params.viewDir.z};
    double ld[3];
    for (int a = 0; a < 3; ++a) ld[a] = su.frame.sign[a] * double(d[su.frame.axis[a]]);
    if (params.order == SurfaceOrder::frontToBack)
      for (double& v : ld) v = -v;
    su.octant = params.order == SurfaceOrder::none ? 0 : (ld[0] < 0) | ((ld[1] < 0) << 1) | ((ld[2] < 0) << 2);
  }

  // Block subdivision (§3): each particle goes to every block whose interior box, grown by Rc_i,
  // contains it. Pairs sorted by (block, rank) keep each block's particles in (z, index) order.
  const double blockSize = double(su.b) * su.s;
  st.pairs.clear();
  const std::int64_t bias = std::int64_t(1) << 20;
  for (std::uint32_t r = 0; r < st.particles.size(); ++r) {
    const Particle& p = st.particles[r];
    const double rc = std::sqrt(p.rc2);
    const std::int64_t b0[3] = {floorDiv(p.x - rc, blockSize), floorDiv(p.y - rc, blockSize),
                                floorDiv(p.z - rc, blockSize)};
    const std::int64_t b1[3] = {floorDiv(p.x + rc, blockSize), floorDiv(p.y + rc, blockSize),
                                floorDiv(p.z + rc, blockSize)};
    for (std::int64_t bz = b0[2]; bz <= b1[2]; ++bz)
      for (std::int64_t by = b0[1]; by <= b1[1]; ++by)
        for (std::int64_t bx = b0[0]; bx <= b1[0]; ++bx)
          st.pairs.push_back({(std::uint64_t(bz + bias) << 42) | (std::uint64_t(by + bias) << 21) |
                                  std::uint64_t(bx + bias),
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
      const std::uint64_t k = st.pairs[i].key, m21 = (1u << 21) - 1;
      BlockDesc b;
      b.bx = std::int32_t(std::int64_t(k & m21) - bias);
      b.by = std::int32_t(std::int64_t((k >> 21) & m21) - bias);
      b.bz = std::int32_t(std::int64_t((k >> 42) & m21) - bias);
      b.first = std::uint32_t(i);
      b.count = 0;
      b.sortKey = 0;
      st.blocks.push_back(b);
    }
    ++st.blocks.back().count;
  }
  // Emission order (§5): blocks by distance of their centre to the eye (farthest first for
  // back-to-front); ties and the plain order by lattice position. Processing order follows it.
  if (params.order != SurfaceOrder::none) {
    const float e[3] = {params.eye.x, params.eye.y, params.eye.z};
    double le[3];
    for (int a = 0; a < 3; ++a) le[a] = su.frame.sign[a] * double(e[su.frame.axis[a]]);
    for (BlockDesc& b : st.blocks) {
      const double c[3] = {(b.bx + 0.5) * blockSize, (b.by + 0.5) * blockSize, (b.bz + 0.5) * blockSize};
      const double d2 = (c[0] - le[0]) * (c[0] - le[0]) + (c[1] - le[1]) * (c[1] - le[1]) +
                        (c[2] - le[2]) * (c[2] - le[2]);
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
    runFollow(st, su, st.followWorkers);
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
  const bool user = !input.user.empty();
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

double surfaceFieldAt(const SurfaceInput& input, const SurfaceParams& params, double x, double y, double z) {
  double value = 0;
  for (std::size_t i = 0; i < input.x.size(); ++i) {
    detail::Particle p;
    p.x = input.x[i];
    p.y = input.y[i];
    p.z = input.z[i];
    const double rc = double(params.rc) * (input.radiusScale.empty() ? 1.0 : double(input.radiusScale[i]));
    p.rc2 = rc * rc;
    p.k = 1.0 / (2.0 * p.rc2);
    p.strength = input.strength.empty() ? 1.0 : double(input.strength[i]);
    if (detail::influences(p, x, y, z)) value += detail::contribution(p, x, y, z);
  }
  return value;
}

}  // namespace fluid

namespace fluid::detail {
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
}  // namespace fluid::detail

#include "fluid/surface/detail/testing.hpp"

namespace fluid::detail {
BlockCacheProbe::BlockCacheProbe(const SurfaceInput& input, const SurfaceParams& params, int bx, int by, int bz) {
  auto* su = new Setup;
  setup_ = su;
  su->s = params.cube;
  su->threshold = params.threshold;
  su->b = params.blockCubes;
  prepareParticles(input, params, SweepFrame{}, particles_, su->rcMax);
  su->m = std::max(1, int(std::ceil(su->rcMax / su->s)));
  su->n = su->b + 2 * su->m;
  n = su->n;
  margin = su->m;
  const double bs = double(su->b) * su->s;
  const int bc[3] = {bx, by, bz};
  for (const Particle& p : particles_) {
    const double rc = std::sqrt(p.rc2);
    const double pc[3] = {p.x, p.y, p.z};
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && floorDiv(pc[a] - rc, bs) <= bc[a] && bc[a] <= floorDiv(pc[a] + rc, bs);
    if (in) blockParticles_.push_back(p);
  }
  auto* w = new Worker<PlainPolicy>;
  w->resize(su->n);
  worker_ = w;
  out_ = new BlockOut;
  block_ = new BlockDesc{bx, by, bz, 0, std::uint32_t(blockParticles_.size()), 0};
  static const PlainPolicy kPolicy{};
  auto* m = new BlockMesher<PlainPolicy>(*w, *su, kPolicy, *static_cast<BlockOut*>(out_));
  mesher_ = m;
  m->prepareCache(*static_cast<BlockDesc*>(block_), blockParticles_);
}
BlockCacheProbe::~BlockCacheProbe() {
  delete static_cast<BlockMesher<PlainPolicy>*>(mesher_);
  delete static_cast<BlockDesc*>(block_);
  delete static_cast<BlockOut*>(out_);
  delete static_cast<Worker<PlainPolicy>*>(worker_);
  delete static_cast<Setup*>(setup_);
}
void BlockCacheProbe::lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
  static_cast<BlockMesher<PlainPolicy>*>(mesher_)->lookup(x, y, z, found);
}
}  // namespace fluid::detail
