// Marching slices (Rosenberg & Birdwell 2008), one oneTBB task per block (Janisz §3.2.6).
// Section numbers below refer to the marching-slices paper; "Alg. 1" to DESIGN.md's restatement.
// The templated core lives in detail/marching_slices_impl.hpp.
#include "fluid/surface/marching_slices.hpp"

#include "fluid/surface/detail/marching_slices_impl.hpp"
#include "fluid/surface/detail/testing.hpp"

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

std::string fieldError(char axis, std::size_t i, float v) {
  return "surface input: positions[" + std::to_string(i) + "]." + axis + " = " + std::to_string(v) + " is not finite";
}
}  // namespace

int surfaceThreads(const SurfaceParams& params) {
  return params.threads > 0 ? params.threads : std::max(1, tbb::this_task_arena::max_concurrency());
}

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
  const std::size_t n = in.positions.count;
  if (n > 0 && in.positions.data == nullptr) return bad("surface input: positions has no data for its count");
  if (n > 0 && (in.positions.stride < 3 * sizeof(float) || in.positions.stride % sizeof(float) != 0))
    return bad("surface input: positions stride = " + std::to_string(in.positions.stride) +
               " bytes must be a multiple of 4 and at least 12");
  if (!in.strength.empty() && in.strength.size() != n)
    return bad("surface input: strength has " + std::to_string(in.strength.size()) + " entries, expected " +
               std::to_string(n));
  if (!in.radiusScale.empty() && in.radiusScale.size() != n)
    return bad("surface input: radiusScale has " + std::to_string(in.radiusScale.size()) + " entries, expected " +
               std::to_string(n));
  if (!in.user.empty() && in.user.size() != n)
    return bad("surface input: user has " + std::to_string(in.user.size()) + " entries, expected " + std::to_string(n));
  if (!in.stretch.empty() && in.stretch.size() != n)
    return bad("surface input: stretch has " + std::to_string(in.stretch.size()) + " entries, expected " +
               std::to_string(n));
  if (n >= (std::size_t(1) << 31)) return bad("surface input: too many particles");
  // Lattice indices must fit the 20-bit key window and int32 block maths comfortably.
  const float lim = 4.0e5f * p.cube;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 q = in.positions[i];
    // One test per particle (NaN and inf fail it too); the message says which bound it broke.
    if (std::fabs(q.x) <= lim && std::fabs(q.y) <= lim && std::fabs(q.z) <= lim) [[likely]]
      continue;
    for (int a = 0; a < 3; ++a)
      if (!finite(q[a])) return bad(fieldError("xyz"[a], i, q[a]));
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
  for (std::size_t i = 0; i < in.stretch.size(); ++i) {
    const glm::mat3& g = in.stretch[i];
    float largest = 0.0f;
    bool ok = true;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) {
        ok = ok && finite(g[c][r]);
        largest = std::max(largest, std::fabs(g[c][r]));
      }
    for (int c = 0; c < 3 && ok; ++c)
      for (int r = c + 1; r < 3; ++r) ok = ok && std::fabs(g[c][r] - g[r][c]) <= 1e-4f * largest;
    if (!ok) return bad("surface input: stretch[" + std::to_string(i) + "] is not a finite symmetric matrix");
    const double smallest = detail::smallestEigenvalue(g);
    if (!(smallest >= 1.0 / 64.0))
      return bad("surface input: stretch[" + std::to_string(i) + "] has smallest eigenvalue " +
                 std::to_string(smallest) + ", must be >= 1/64 (a semi-axis of at most 64 Rc)");
  }
  for (std::size_t i = 0; i < in.user.size(); ++i)
    if (!finite(in.user[i].x) || !finite(in.user[i].y) || !finite(in.user[i].z) || !finite(in.user[i].w))
      return bad("surface input: user[" + std::to_string(i) + "] is not finite");
  return {};
}

namespace detail {

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
      for (int a = 0; a < 3; ++a) c[a] = std::clamp(ifloor((pc[a] - double(g0_[a]) * su_.s) / su_.rcMax), 0, g[a] - 1);
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
    return (std::size_t(z) * std::size_t(su_.n[1] + 1) + std::size_t(y)) * std::size_t(su_.n[0] + 1) + std::size_t(x);
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
std::uint64_t followPeakBytes(const ExtractorState& st) {
  std::uint64_t bytes = 0;
  for (const auto& w : st.followWorkers)
    if (w) bytes += w->peakBytes;
  return bytes;
}

}  // namespace detail

SurfaceExtractor::SurfaceExtractor() : state(std::make_unique<detail::ExtractorState>()) {}
SurfaceExtractor::~SurfaceExtractor() = default;
SurfaceExtractor::SurfaceExtractor(SurfaceExtractor&&) noexcept = default;
SurfaceExtractor& SurfaceExtractor::operator=(SurfaceExtractor&&) noexcept = default;

SurfaceStatus SurfaceExtractor::extract(const SurfaceInput& input, const SurfaceParams& params, SurfaceMesh& out) {
  if (input.user.empty()) return detail::extractImpl(*state, input, params, detail::PlainPolicy{}, out);
  detail::Vec4Policy policy;
  policy.user = input.user.data();
  return detail::extractImpl(*state, input, params, policy, out);
}

float surfaceFieldAtCorner(const SurfaceInput& input, const SurfaceParams& params, std::int64_t i, std::int64_t j,
                           std::int64_t k) {
  std::vector<detail::Particle> ps;
  std::vector<detail::StretchTerm> stretch;
  double rcMax = 0;
  detail::prepareParticles(input, params, detail::SweepFrame{}, ps, rcMax, nullptr, &stretch);
  const double s = params.cube;
  float value = 0, g[3] = {0, 0, 0};
  for (const detail::Particle& p : ps) {
    if (!detail::influences(p, double(i) * s, double(j) * s, double(k) * s)) continue;
    detail::accumulateAt(p, stretch.empty() ? nullptr : stretch.data(), i, j, k, s, value, g[0], g[1], g[2]);
  }
  return value;
}

namespace detail {
SurfaceStatus extractBlockedSurfaceFollowing(SurfaceExtractor& extractor, const SurfaceInput& input,
                                             const SurfaceParams& params, SurfaceMesh& out, std::uint64_t& cornerBytes,
                                             std::uint64_t& particleBytes) {
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
  su.avx2 = detectFillAvx2(params);
  prepareParticles(input, params, SweepFrame{}, particles, su.rcMax);
  su.m = marginCubes(su.rcMax, su.s);
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
  const int bc[3] = {bx, by, bz};
  for (const Particle& p : particles) {
    const int reach = particleReach(p, su.s);
    bool in = true;
    for (int a = 0; a < 3; ++a) {
      int first, last;
      blockSpan(su, a, p.anchor[a], reach, first, last);
      in = in && first <= bc[a] && bc[a] <= last;
    }
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