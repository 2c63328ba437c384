#include "fluid/surface/baselines.hpp"

#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/mc_tables.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace fluid {
namespace detail {

// Implemented in marching_slices.cpp: approach 2 shares the block subdivision and output path.
SurfaceStatus extractBlockedSurfaceFollowing(SurfaceExtractor& extractor, const SurfaceInput& input,
                                             const SurfaceParams& params, SurfaceMesh& out, std::uint64_t& cornerBytes,
                                             std::uint64_t& particleBytes);

namespace {

struct CornerValue {
  float value;
  float g[3];
};

// The default vertex routine (same expressions as marching_slices.cpp: positions in double from
// the global lattice index, normals from the interpolated gradient).
void emitVertex(const CornerValue& a, const CornerValue& b, std::int64_t i, std::int64_t j, std::int64_t k, int axis,
                const SurfaceParams& params, SurfaceMesh& out) {
  const double s = params.cube;
  const double tt = (double(params.threshold) - double(a.value)) / (double(b.value) - double(a.value));
  double p[3] = {double(i) * s, double(j) * s, double(k) * s};
  p[axis] += tt * s;
  const float tf = float(tt);
  float g[3];
  for (int c = 0; c < 3; ++c) g[c] = a.g[c] + tf * (b.g[c] - a.g[c]);
  const float len2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
  glm::vec3 n(0.0f);
  if (len2 > 1e-30f && std::isfinite(len2)) {
    const float inv = -1.0f / std::sqrt(len2);
    n = {g[0] * inv, g[1] * inv, g[2] * inv};
  } else {
    n[axis] = a.value > params.threshold ? 1.0f : -1.0f;
  }
  out.positions.push_back({float(p[0] - params.originX), float(p[1] - params.originY), float(p[2] - params.originZ)});
  out.normals.push_back(n);
  out.edgeKeys.push_back(edgeKey(i, j, k, axis));
}

std::uint64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
  const std::int64_t bias = std::int64_t(1) << 20;
  return (std::uint64_t(k + bias) << 42) | (std::uint64_t(j + bias) << 21) | std::uint64_t(i + bias);
}
std::uint64_t mix(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  return x;
}

// Open-addressing map from a packed key to a uint32 payload (index into a side array).
struct HashIndex {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> vals;
  std::size_t count = 0, mask = 0;
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  void reset(std::size_t expected) {
    std::size_t cap = 64;
    while (cap < expected * 2) cap <<= 1;
    if (keys.size() != cap) {
      keys.assign(cap, kEmpty);
      vals.assign(cap, 0);
    } else {
      std::fill(keys.begin(), keys.end(), kEmpty);
    }
    mask = cap - 1;
    count = 0;
  }
  // Returns pointer to the payload, inserting `fresh` when absent (inserted = true).
  std::uint32_t* findOrInsert(std::uint64_t key, std::uint32_t fresh, bool& inserted) {
    if ((count + 1) * 2 > keys.size()) grow();
    std::size_t h = mix(key) & mask;
    while (true) {
      if (keys[h] == key) {
        inserted = false;
        return &vals[h];
      }
      if (keys[h] == kEmpty) {
        keys[h] = key;
        vals[h] = fresh;
        ++count;
        inserted = true;
        return &vals[h];
      }
      h = (h + 1) & mask;
    }
  }
  const std::uint32_t* find(std::uint64_t key) const {
    std::size_t h = mix(key) & mask;
    while (true) {
      if (keys[h] == key) return &vals[h];
      if (keys[h] == kEmpty) return nullptr;
      h = (h + 1) & mask;
    }
  }
  void grow() {
    std::vector<std::uint64_t> ok = std::move(keys);
    std::vector<std::uint32_t> ov = std::move(vals);
    keys.assign(ok.size() * 2, kEmpty);
    vals.assign(ok.size() * 2, 0);
    mask = keys.size() - 1;
    count = 0;
    bool ins;
    for (std::size_t i = 0; i < ok.size(); ++i)
      if (ok[i] != kEmpty) *findOrInsert(ok[i], ov[i], ins) = ov[i];
  }
  std::uint64_t bytes() const { return keys.size() * (sizeof(std::uint64_t) + sizeof(std::uint32_t)); }
};

}  // namespace

struct BaselineState {
  std::vector<Particle> particles;
  std::vector<ParticleSortKey> sortKeys;  // prepareParticles scratch
  std::vector<StretchTerm> stretch;          // SurfaceInput::stretch's terms (prepareParticles)
  const StretchTerm* stretchTerms = nullptr;  // stretch.data() for this call, null for spheres
  // dense
  std::vector<CornerValue> lower, upper;
  std::vector<std::uint32_t> lowIx, lowIy, lowIz, upIx, upIy;
  // hashed
  struct HCorner {
    CornerValue c;
    std::uint32_t vert[3];
    std::uint8_t done;
  };
  std::vector<HCorner> corners;
  HashIndex cornerIndex, cellIndex;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> cellPairs;
  std::vector<std::uint32_t> cellRanges;  // first, count pairs per cell entry
  std::vector<std::uint32_t> cellParticles;
  std::vector<std::array<std::int64_t, 3>> stack;
  SurfaceExtractor blockedExtractor;
  std::uint64_t cornerBytes = 0, particleBytes = 0;
};

namespace {

void dense(BaselineState& st, const SurfaceParams& params, double rcMax, SurfaceMesh& out) {
  const auto& ps = st.particles;
  if (ps.empty()) return;
  const double s = params.cube, t = params.threshold;
  double lo[3] = {ps[0].x, ps[0].y, ps[0].z}, hi[3] = {lo[0], lo[1], lo[2]};
  for (const Particle& p : ps) {
    lo[0] = std::min(lo[0], p.x), hi[0] = std::max(hi[0], p.x);
    lo[1] = std::min(lo[1], p.y), hi[1] = std::max(hi[1], p.y);
    lo[2] = std::min(lo[2], p.z), hi[2] = std::max(hi[2], p.z);
  }
  std::int64_t i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    i0[a] = floorDiv(lo[a] - rcMax, s) - 1;
    i1[a] = floorDiv(hi[a] + rcMax, s) + 2;
  }
  const std::size_t nx = std::size_t(i1[0] - i0[0] + 1), ny = std::size_t(i1[1] - i0[1] + 1);
  const std::size_t cells = nx * ny;
  st.lower.assign(cells, {});
  st.upper.assign(cells, {});
  st.lowIx.assign(cells, 0), st.lowIy.assign(cells, 0), st.lowIz.assign(cells, 0);
  st.upIx.assign(cells, 0), st.upIy.assign(cells, 0);
  st.cornerBytes = 2 * cells * sizeof(CornerValue) + 5 * cells * sizeof(std::uint32_t);
  st.particleBytes = ps.size() * sizeof(Particle);
  std::size_t window = 0;
  auto fill = [&](std::int64_t k, std::vector<CornerValue>& slice) {
    std::fill(slice.begin(), slice.end(), CornerValue{0, {0, 0, 0}});
    const double cz = double(k) * s;
    while (window < ps.size() && ps[window].z <= cz - rcMax) ++window;
    for (std::size_t pi = window; pi < ps.size() && ps[pi].z < cz + rcMax; ++pi) {
      const Particle& p = ps[pi];
      const double rc = std::sqrt(p.rc2);
      const std::int64_t xa = std::max<std::int64_t>(i0[0], floorDiv(p.x - rc, s)),
                         xb = std::min<std::int64_t>(i1[0], floorDiv(p.x + rc, s) + 1);
      const std::int64_t ya = std::max<std::int64_t>(i0[1], floorDiv(p.y - rc, s)),
                         yb = std::min<std::int64_t>(i1[1], floorDiv(p.y + rc, s) + 1);
      for (std::int64_t j = ya; j <= yb; ++j)
        for (std::int64_t i = xa; i <= xb; ++i) {
          const double cx = double(i) * s, cy = double(j) * s;
          if (!influences(p, cx, cy, cz)) continue;
          CornerValue& c = slice[std::size_t(j - i0[1]) * nx + std::size_t(i - i0[0])];
          accumulateAt(p, st.stretchTerms, i, j, k, s, c.value, c.g[0], c.g[1], c.g[2]);
        }
    }
  };
  const auto& table = mc::tables().cases[0];
  fill(i0[2], st.lower);
  for (std::int64_t k = i0[2]; k < i1[2]; ++k) {
    fill(k + 1, st.upper);
    for (std::size_t y = 0; y + 1 < ny; ++y)
      for (std::size_t x = 0; x + 1 < nx; ++x) {
        const CornerValue* cv[8];
        std::uint32_t* vi[8][3];
        for (int c = 0; c < 8; ++c) {
          const std::size_t id = (y + ((c >> 1) & 1)) * nx + x + (c & 1);
          const bool up = c >> 2;
          cv[c] = up ? &st.upper[id] : &st.lower[id];
          vi[c][0] = up ? &st.upIx[id] : &st.lowIx[id];
          vi[c][1] = up ? &st.upIy[id] : &st.lowIy[id];
          vi[c][2] = up ? nullptr : &st.lowIz[id];
        }
        unsigned cube = 0;
        for (int c = 0; c < 8; ++c) cube |= unsigned(cv[c]->value > t) << c;
        if (cube == 0 || cube == 255) continue;
        const mc::CaseTable& cs = table[cube];
        for (int tri = 0; tri < cs.triangleCount; ++tri)
          for (int e = 0; e < 3; ++e) {
            const int edge = cs.edges[3 * tri + e], base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
            std::uint32_t& slot = *vi[base][axis];
            if (!slot) {
              emitVertex(*cv[base], *cv[base | (1 << axis)], i0[0] + std::int64_t(x) + (base & 1),
                         i0[1] + std::int64_t(y) + ((base >> 1) & 1), k + (base >> 2), axis, params, out);
              slot = std::uint32_t(out.positions.size());
            }
            out.indices.push_back(slot - 1);
          }
      }
    std::swap(st.lower, st.upper);
    std::swap(st.lowIx, st.upIx);
    std::swap(st.lowIy, st.upIy);
    std::fill(st.upIx.begin(), st.upIx.end(), 0u);
    std::fill(st.upIy.begin(), st.upIy.end(), 0u);
    std::fill(st.lowIz.begin(), st.lowIz.end(), 0u);
  }
}

void hashed(BaselineState& st, const SurfaceParams& params, double rcMax, SurfaceMesh& out) {
  const auto& ps = st.particles;
  const double s = params.cube, t = params.threshold;
  // Hashed particle grid, cell size Rc: point insert (each particle in the cell holding its
  // centre), 3x3x3 lookup with a distance test.
  st.cellPairs.clear();
  for (std::uint32_t r = 0; r < ps.size(); ++r)
    st.cellPairs.push_back({pack(floorDiv(ps[r].x, rcMax), floorDiv(ps[r].y, rcMax), floorDiv(ps[r].z, rcMax)), r});
  std::sort(st.cellPairs.begin(), st.cellPairs.end());
  st.cellIndex.reset(ps.size());
  st.cellRanges.clear();
  st.cellParticles.resize(ps.size());
  for (std::size_t i = 0; i < st.cellPairs.size(); ++i) {
    st.cellParticles[i] = st.cellPairs[i].second;
    if (i == 0 || st.cellPairs[i].first != st.cellPairs[i - 1].first) {
      bool ins;
      *st.cellIndex.findOrInsert(st.cellPairs[i].first, std::uint32_t(st.cellRanges.size() / 2), ins) =
          std::uint32_t(st.cellRanges.size() / 2);
      st.cellRanges.push_back(std::uint32_t(i));
      st.cellRanges.push_back(0);
    }
    ++st.cellRanges.back();
  }
  st.particleBytes =
      st.cellIndex.bytes() + st.cellRanges.size() * 4 + st.cellParticles.size() * 4 + ps.size() * sizeof(Particle);
  st.corners.clear();
  st.cornerIndex.reset(std::max<std::size_t>(1024, st.corners.capacity()));
  auto corner = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::uint32_t {
    bool ins;
    std::uint32_t* slot = st.cornerIndex.findOrInsert(pack(i, j, k), std::uint32_t(st.corners.size()), ins);
    if (!ins) return *slot;
    const std::uint32_t id = *slot;
    BaselineState::HCorner c{};
    const double cx = double(i) * s, cy = double(j) * s, cz = double(k) * s;
    const std::int64_t ci = floorDiv(cx, rcMax), cj = floorDiv(cy, rcMax), ck = floorDiv(cz, rcMax);
    float g[3] = {0, 0, 0};
    for (std::int64_t dk = -1; dk <= 1; ++dk)
      for (std::int64_t dj = -1; dj <= 1; ++dj)
        for (std::int64_t di = -1; di <= 1; ++di) {
          const std::uint32_t* cell = st.cellIndex.find(pack(ci + di, cj + dj, ck + dk));
          if (!cell) continue;
          const std::uint32_t first = st.cellRanges[2 * *cell], count = st.cellRanges[2 * *cell + 1];
          for (std::uint32_t q = first; q < first + count; ++q) {
            const Particle& p = ps[st.cellParticles[q]];
            if (influences(p, cx, cy, cz)) accumulateAt(p, st.stretchTerms, i, j, k, s, c.c.value, g[0], g[1], g[2]);
          }
        }
    for (int a = 0; a < 3; ++a) c.c.g[a] = g[a];
    st.corners.push_back(c);
    ++out.stats.cornersEvaluated;
    return id;
  };
  // Seeds (as §4): step down from each particle's nearest corner.
  st.stack.clear();
  for (const Particle& p : ps) {
    const std::int64_t i = iround(p.x / s), j = iround(p.y / s);
    std::int64_t k = iround(p.z / s);
    if (!(st.corners[corner(i, j, k)].c.value > t)) continue;
    const int steps = iceil(std::sqrt(p.rc2) / s) + 1;
    for (int n = 0; n < steps; ++n, --k)
      if (!(st.corners[corner(i, j, k - 1)].c.value > t)) {
        st.stack.push_back({i, j, k - 1});
        break;
      }
  }
  const auto& table = mc::tables().cases[0];
  while (!st.stack.empty()) {
    const auto [i, j, k] = st.stack.back();
    st.stack.pop_back();
    std::uint32_t ids[8];
    for (int c = 0; c < 8; ++c) ids[c] = corner(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
    if (st.corners[ids[0]].done) continue;
    st.corners[ids[0]].done = 1;
    ++out.stats.cubesVisited;
    unsigned cube = 0;
    for (int c = 0; c < 8; ++c) cube |= unsigned(st.corners[ids[c]].c.value > t) << c;
    if (cube == 0 || cube == 255) continue;
    const mc::CaseTable& cs = table[cube];
    for (int tri = 0; tri < cs.triangleCount; ++tri)
      for (int e = 0; e < 3; ++e) {
        const int edge = cs.edges[3 * tri + e], base = mc::kEdgeBase[edge], axis = mc::kEdgeAxis[edge];
        BaselineState::HCorner& cb = st.corners[ids[base]];
        if (!cb.vert[axis]) {
          emitVertex(cb.c, st.corners[ids[base | (1 << axis)]].c, i + (base & 1), j + ((base >> 1) & 1),
                     k + (base >> 2), axis, params, out);
          cb.vert[axis] = std::uint32_t(out.positions.size());
        }
        out.indices.push_back(cb.vert[axis] - 1);
      }
    auto visit = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
      const std::uint32_t* id = st.cornerIndex.find(pack(a, b, c));
      if (id && st.corners[*id].done) return;
      st.stack.push_back({a, b, c});
    };
    const unsigned f = cs.faceMask;
    if (f & 1) visit(i - 1, j, k);
    if (f & 2) visit(i + 1, j, k);
    if (f & 4) visit(i, j - 1, k);
    if (f & 8) visit(i, j + 1, k);
    if (f & 16) visit(i, j, k - 1);
    if (f & 32) visit(i, j, k + 1);
  }
  st.cornerBytes = st.cornerIndex.bytes() + st.corners.size() * sizeof(BaselineState::HCorner);
}

}  // namespace
}  // namespace detail

BaselineExtractor::BaselineExtractor() : state(std::make_unique<detail::BaselineState>()) {}
BaselineExtractor::~BaselineExtractor() = default;
BaselineExtractor::BaselineExtractor(BaselineExtractor&&) noexcept = default;
BaselineExtractor& BaselineExtractor::operator=(BaselineExtractor&&) noexcept = default;
std::uint64_t BaselineExtractor::cornerBytes() const { return state->cornerBytes; }
std::uint64_t BaselineExtractor::particleBytes() const { return state->particleBytes; }

SurfaceStatus BaselineExtractor::extract(BaselineMethod method, const SurfaceInput& input, const SurfaceParams& params,
                                         SurfaceMesh& out) {
  out.clear();
  SurfaceStatus status = validateSurface(input, params);
  if (status.ok() && !input.stretch.empty() && method == BaselineMethod::blocked)
    status.error = "surface input: stretch (anisotropic kernels) is not supported by the blocked baseline";
  if (!status.ok()) return status;
  if (!input.user.empty()) return {"baseline extractors do not interpolate user data"};
  if (method == BaselineMethod::blocked)
    return detail::extractBlockedSurfaceFollowing(state->blockedExtractor, input, params, out, state->cornerBytes,
                                                  state->particleBytes);
  double rcMax = 0;
  detail::prepareParticles(input, params, detail::SweepFrame{}, state->particles, rcMax, &state->sortKeys,
                           &state->stretch);
  state->stretchTerms = input.stretch.empty() ? nullptr : state->stretch.data();
  if (method == BaselineMethod::dense)
    detail::dense(*state, params, rcMax, out);
  else
    detail::hashed(*state, params, rcMax, out);
  out.stats.triangles = out.indices.size() / 3;
  out.stats.vertices = out.positions.size();
  return {};
}

}  // namespace fluid
