// Reach culling of a depth-map collider (collide.hpp, ReachCulledCollider): per grid cell, bounds
// of every vote of Kolb et al. 2004 §4.1 eq. (1) (ortho maps) and §4.3 (depth cube) over the cell,
// then rule (2) decides whether the cell's answer is >= reach everywhere.
#include "fluid/collide/collide.hpp"
#include "fluid/collide/map_sampling.hpp"
#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace fluid {
namespace {

// Bounds of one vote over a cell: the vote may be invalid somewhere (`maybe_invalid`), may be cast
// by a margin-ring texel somewhere (`maybe_ring`), and is in [lo, hi] where it is valid and not a
// ring vote. Ring votes are not bounded: a cell is only called far where a main vote is >= 0
// everywhere, and there DepthMapCollider::sample never uses the ring votes.
struct VoteRange {
  float lo = FLT_MAX, hi = -FLT_MAX;
  bool any_valid = false, maybe_invalid = false, maybe_ring = false;
  void add(float l, float h, bool ring) {
    if (ring) {
      maybe_ring = true;
      return;
    }
    lo = std::min(lo, l);
    hi = std::max(hi, h);
    any_valid = true;
  }
};

// What rule (2) can do over a cell, from the ranges of all votes. Far: either a vote that is
// never invalid, never a ring vote and >= reach everywhere (rule (2) then picks the smallest vote
// >= 0, a main one) while every vote that can be >= 0 is >= reach, or no vote can be valid at all
// (DepthMapCollider::sample then answers invalid).
struct CellVerdict {
  bool guaranteed = false;  // a vote never invalid, never ring, >= reach everywhere
  bool near = false;        // a vote that can be >= 0 somewhere is < reach somewhere
  bool any_valid = false;   // some vote (main or ring) can be valid somewhere
  void add(const VoteRange& v, float reach, float slack) {
    any_valid = any_valid || v.any_valid || v.maybe_ring;
    if (!v.any_valid) return;
    if (v.hi >= -slack && v.lo < reach + slack) near = true;
    if (!v.maybe_invalid && !v.maybe_ring && v.lo >= reach + slack) guaranteed = true;
  }
  bool far() const { return !any_valid || (guaranteed && !near); }
};

using collide_detail::depthHalf;
using collide_detail::transformPoint;

// The map-space bounding box of the box [lo, hi] (the map transform is affine: the image's centre
// and |M| times the half extent), padded for rounding.
void mapRange(const glm::mat4& m, glm::vec3 lo, glm::vec3 hi, glm::vec3& qlo, glm::vec3& qhi) {
  const glm::vec3 c = transformPoint(m, 0.5f * (lo + hi)), h = 0.5f * (hi - lo);
  const glm::vec3 e =
      glm::abs(glm::vec3(m[0])) * h.x + glm::abs(glm::vec3(m[1])) * h.y + glm::abs(glm::vec3(m[2])) * h.z;
  const glm::vec3 pad = 1e-5f * (glm::abs(c) + e) + 1e-6f;
  qlo = c - e - pad;
  qhi = c + e + pad;
}

// Texel range [i0, i1] that floor(u · n) takes for u in [ulo, uhi] (u already padded for rounding;
// float multiplication is monotone, so the bounds' texels bound every point's).
inline void texelRange(float ulo, float uhi, int n, int& i0, int& i1) {
  const float nf = static_cast<float>(n);
  i0 = std::clamp(static_cast<int>(std::floor(std::max(ulo, 0.0f) * nf)), 0, n - 1);
  i1 = std::clamp(static_cast<int>(std::floor(std::min(uhi, 1.0f) * nf)), 0, n - 1);
}

// Min/max pyramid of an ortho map's depths: level 0 per texel, level k over aligned 2^k squares.
// "front" holds the LESS depth (the only depth of a float32/fixed8 map, whatever its compare),
// "back" the GREATER depth of a front_back16 map; margin-ring texels and background are flags.
struct DepthStats {
  float fmin = FLT_MAX, fmax = -FLT_MAX, bmin = FLT_MAX, bmax = -FLT_MAX;
  std::uint8_t flags = 0;  // kFrontBackground | kBackBackground | kRing
  void merge(const DepthStats& o) {
    fmin = std::min(fmin, o.fmin);
    fmax = std::max(fmax, o.fmax);
    bmin = std::min(bmin, o.bmin);
    bmax = std::max(bmax, o.bmax);
    flags |= o.flags;
  }
};
constexpr std::uint8_t kFrontBackground = 1, kBackBackground = 2, kRing = 4;

struct DepthPyramid {
  std::vector<std::vector<DepthStats>> levels;
  std::vector<int> sizes;
};

DepthPyramid pyramidOf(std::vector<DepthStats> base, int n);

DepthPyramid depthPyramid(const DepthMap& map) {
  const int n = static_cast<int>(map.resolution);
  const bool two = map.format == DepthMapFormat::front_back16;
  std::vector<DepthStats> base(static_cast<std::size_t>(n) * n);
  for (std::size_t texel = 0; texel < base.size(); ++texel) {
    const std::uint8_t* t = map.texels.data() + texel * texelBytes(map.format);
    DepthStats& d = base[texel];
    if (two) {
      std::uint16_t fb, bb;
      std::memcpy(&fb, t + 4, 2);
      std::memcpy(&bb, t + 6, 2);
      const float f = depthHalf(fb), b = depthHalf(bb);
      if (map.margin_ring && fb == bb && f >= 0.0f) {
        d.flags |= kRing;  // its votes go to the ring winner, unused where a cell is far
        continue;
      }
      if (f < 0.0f)
        d.flags |= kFrontBackground;
      else
        d.fmin = d.fmax = f;
      if (b < 0.0f)
        d.flags |= kBackBackground;
      else
        d.bmin = d.bmax = b;
      continue;
    }
    float depth = -1.0f;
    if (map.format == DepthMapFormat::float32) {
      std::memcpy(&depth, t + 12, 4);
    } else {
      const std::uint16_t code = static_cast<std::uint16_t>((t[2] << 8) | t[3]);
      depth = code == kFixedBackground ? -1.0f : decodeFixedDepth(code);
    }
    if (depth < 0.0f)
      d.flags |= kFrontBackground;
    else
      d.fmin = d.fmax = depth;
  }
  return pyramidOf(std::move(base), n);
}

DepthPyramid pyramidOf(std::vector<DepthStats> base, int n) {
  DepthPyramid p;
  p.levels.push_back(std::move(base));
  p.sizes.push_back(n);
  while (p.sizes.back() > 1) {
    const int m = p.sizes.back(), h = (m + 1) / 2;
    const std::vector<DepthStats>& below = p.levels.back();
    std::vector<DepthStats> up(static_cast<std::size_t>(h) * h);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        up[static_cast<std::size_t>(j / 2) * h + i / 2].merge(below[static_cast<std::size_t>(j) * m + i]);
    p.levels.push_back(std::move(up));
    p.sizes.push_back(h);
  }
  return p;
}

// Stats over texels [i0, i1] × [j0, j1] (or a few more: the aligned squares of the smallest level
// where the range spans at most three of them per axis).
DepthStats rectStats(const DepthPyramid& p, int i0, int i1, int j0, int j1) {
  std::size_t k = 0;
  while (k + 1 < p.levels.size() && ((i1 >> k) - (i0 >> k) > 2 || (j1 >> k) - (j0 >> k) > 2)) ++k;
  DepthStats out;
  const int m = p.sizes[k];
  for (int j = j0 >> k; j <= (j1 >> k); ++j)
    for (int i = i0 >> k; i <= (i1 >> k); ++i) out.merge(p.levels[k][static_cast<std::size_t>(j) * m + i]);
  return out;
}

// Ortho map (orthoVotes in depth_map.cpp): eq. (1) per texel, z' over the cell's depth range.
void orthoRanges(const DepthMap& map, const DepthPyramid& pyramid, glm::vec3 lo, glm::vec3 hi, VoteRange& front,
                 VoteRange& back) {
  glm::vec3 qlo, qhi;
  mapRange(map.collider_to_map, lo, hi, qlo, qhi);
  const bool two = map.format == DepthMapFormat::front_back16;
  const bool less = two || map.compare == DepthCompare::less;
  if (qhi.x < 0.0f || qlo.x >= 1.0f || qhi.y < 0.0f || qlo.y >= 1.0f) {  // never in the footprint
    front.maybe_invalid = back.maybe_invalid = true;
    return;
  }
  const bool partial = !(qlo.x >= 0.0f && qhi.x < 1.0f && qlo.y >= 0.0f && qhi.y < 1.0f);
  // LESS votes are valid up to the far plane, GREATER ones from the near plane (§4.1).
  const bool less_never = qlo.z > 1.0f, less_maybe_not = qhi.z > 1.0f;
  const bool greater_never = qhi.z < 0.0f, greater_maybe_not = qlo.z < 0.0f;
  const int n = static_cast<int>(map.resolution);
  int i0, i1, j0, j1;
  texelRange(qlo.x, qhi.x, n, i0, i1);
  texelRange(qlo.y, qhi.y, n, j0, j1);
  const DepthStats d = rectStats(pyramid, i0, i1, j0, j1);
  const float zs = map.z_scale;
  const bool ring = (d.flags & kRing) != 0;
  const bool has_front = d.fmin <= d.fmax, has_back = d.bmin <= d.bmax;
  if (!two && !less) {
    // A single GREATER map: z_scale (z' − depth), its depth stored in the front slot.
    back.maybe_invalid =
        back.maybe_invalid || partial || greater_maybe_not || greater_never || (d.flags & kFrontBackground);
    if (has_front && !greater_never) back.add(zs * (qlo.z - d.fmax), zs * (qhi.z - d.fmin), false);
    return;
  }
  // The LESS vote (front of a pair, or a single LESS map): z_scale (depth − z').
  front.maybe_invalid = front.maybe_invalid || partial || less_maybe_not || less_never || (d.flags & kFrontBackground);
  front.maybe_ring = front.maybe_ring || ring;
  if (has_front && !less_never) front.add(zs * (d.fmin - qhi.z), zs * (d.fmax - qlo.z), false);
  if (!two) return;
  back.maybe_invalid =
      back.maybe_invalid || partial || greater_maybe_not || greater_never || (d.flags & kBackBackground);
  back.maybe_ring = back.maybe_ring || ring;
  if (has_back && !greater_never) back.add(zs * (qlo.z - d.bmax), zs * (qhi.z - d.bmin), false);
}

// min |x| over [lo, hi].
inline float minAbs(float lo, float hi) {
  return lo <= 0.0f && hi >= 0.0f ? 0.0f : std::min(std::fabs(lo), std::fabs(hi));
}

// Per cube face: the pyramid of its stored radii (front slot; background as kFrontBackground).
std::array<DepthPyramid, 6> facePyramids(const DepthMap& map) {
  std::array<DepthPyramid, 6> out{};
  const int n = static_cast<int>(map.resolution);
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  for (int f = 0; f < 6; ++f) {
    std::vector<DepthStats> base(per_face);
    for (std::size_t t = 0; t < per_face; ++t) {
      const std::uint8_t* tx = map.texels.data() + (f * per_face + t) * 4u;
      const std::uint16_t code = static_cast<std::uint16_t>((tx[2] << 8) | tx[3]);
      if (code == kFixedBackground) {
        base[t].flags = kFrontBackground;
      } else {
        base[t].fmin = base[t].fmax = static_cast<float>(code) * kCubeRadiusStep;
      }
    }
    out[f] = pyramidOf(std::move(base), n);
  }
  return out;
}

// Depth cube (cubeVote in depth_map.cpp): the faces and texels the cell's directions from the
// centre can reach, the radii stored there and the cell's distance range from the centre.
VoteRange cubeRange(const DepthMap& map, const std::array<DepthPyramid, 6>& faces, glm::vec3 lo, glm::vec3 hi) {
  VoteRange v;
  glm::vec3 q0, q1;
  mapRange(map.collider_to_map, lo, hi, q0, q1);
  for (int a = 0; a < 3; ++a)
    if (q1[a] < -1.0f || q0[a] > 1.0f) {
      v.maybe_invalid = true;
      return v;
    }
  v.maybe_invalid = !(q0.x >= -1.0f && q1.x <= 1.0f && q0.y >= -1.0f && q1.y <= 1.0f && q0.z >= -1.0f && q1.z <= 1.0f);
  float lmin2 = 0.0f, lmax2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float m = minAbs(q0[a], q1[a]), x = std::max(std::fabs(q0[a]), std::fabs(q1[a]));
    lmin2 += m * m;
    lmax2 += x * x;
  }
  const float lmin = std::sqrt(lmin2) * (1.0f - 1e-5f), lmax = std::sqrt(lmax2) * (1.0f + 1e-5f);
  // |S·dir| for a unit dir lies between the smallest and the largest scale.
  const glm::vec3 s = glm::abs(map.cube_scale);
  const float amin = std::min({s.x, s.y, s.z}), amax = std::max({s.x, s.y, s.z});
  // Faces in cubeFace order: major axis, its sign, the axes and signs of sc and tc.
  struct Face {
    int major;
    float sign;
    int sc_axis;
    float sc_sign;
    int tc_axis;
    float tc_sign;
  };
  static constexpr Face kFaces[6] = {{0, 1, 2, -1, 1, -1}, {0, -1, 2, 1, 1, -1}, {1, 1, 0, 1, 2, 1},
                                     {1, -1, 0, 1, 2, -1}, {2, 1, 0, 1, 1, -1},  {2, -1, 0, -1, 1, -1}};
  const int n = static_cast<int>(map.resolution);
  float rmin = FLT_MAX, rmax = -FLT_MAX;
  for (int f = 0; f < 6; ++f) {
    const Face& face = kFaces[f];
    const float m0 = face.sign > 0 ? q0[face.major] : -q1[face.major];
    const float m1 = face.sign > 0 ? q1[face.major] : -q0[face.major];
    // The face is chosen where the major coordinate is >= 0 and >= the other two in size.
    const int b = (face.major + 1) % 3, c = (face.major + 2) % 3;
    if (m1 < 0.0f || m1 < minAbs(q0[b], q1[b]) || m1 < minAbs(q0[c], q1[c])) continue;
    // Face coordinate u = sign · q[axis] / m: monotone in each variable where m > 0, so its
    // extremes are at the corners of the (m, q[axis]) rectangle; where m can reach 0 only
    // |u| <= 1 is known.
    auto ratio = [&](int axis, float sgn, float& ulo, float& uhi) {
      if (m0 <= 0.0f) {
        // On the face |u| <= 1, and u has the sign of w = sign · q[axis] with |u| >= |w| / m1.
        const float w0 = sgn > 0 ? q0[axis] : -q1[axis], w1 = sgn > 0 ? q1[axis] : -q0[axis];
        ulo = w0 > 0.0f ? w0 / m1 : -1.0f;
        uhi = w1 < 0.0f ? w1 / m1 : 1.0f;
        return;
      }
      ulo = FLT_MAX;
      uhi = -FLT_MAX;
      for (const float mm : {m0, m1})
        for (const float w : {q0[axis], q1[axis]}) {
          const float u = sgn * w / mm;
          ulo = std::min(ulo, u);
          uhi = std::max(uhi, u);
        }
      ulo = std::max(ulo, -1.0f);
      uhi = std::min(uhi, 1.0f);
    };
    float s0, s1, t0, t1;
    ratio(face.sc_axis, face.sc_sign, s0, s1);
    ratio(face.tc_axis, face.tc_sign, t0, t1);
    int i0, i1, j0, j1;
    texelRange((s0 + 1.0f) * 0.5f, (s1 + 1.0f) * 0.5f, n, i0, i1);
    texelRange((t0 + 1.0f) * 0.5f, (t1 + 1.0f) * 0.5f, n, j0, j1);
    const DepthStats d = rectStats(faces[f], i0, i1, j0, j1);
    v.maybe_invalid = v.maybe_invalid || (d.flags & kFrontBackground);
    rmin = std::min(rmin, d.fmin);
    rmax = std::max(rmax, d.fmax);
  }
  if (rmin > rmax) return v;  // no stored radius reachable: only invalid votes
  // f = (r − L)·a (LESS) or (L − r)·a (GREATER), a in [amin, amax].
  const bool less = map.compare == DepthCompare::less;
  const float d0 = less ? rmin - lmax : lmin - rmax, d1 = less ? rmax - lmin : lmax - rmin;
  v.add(std::min(d0 * amin, d0 * amax), std::max(d1 * amin, d1 * amax), false);
  return v;
}

}  // namespace

ReachCulledCollider::ReachCulledCollider(std::shared_ptr<const DepthMapCollider> inner, Bounds box,
                                         const ReachGridDesc& desc)
    : inner_(std::move(inner)), box_(box) {
  assert(inner_ && desc.reach > 0.0f);
  const glm::vec3 size = glm::max(box_.hi - box_.lo, glm::vec3(0.0f));
  cell_ = glm::vec3(desc.cell > 0.0f ? desc.cell : 0.25f * desc.reach);
  auto count = [&](glm::vec3 c) { return glm::ivec3(glm::max(glm::ceil(size / c), glm::vec3(1.0f))); };
  // Too many cells: coarsen the axis with the most cells first (a wide flat slab keeps fine
  // cells across its thickness, where its distance changes).
  while (true) {
    const glm::ivec3 d = count(cell_);
    if (static_cast<double>(d.x) * d.y * d.z <= static_cast<double>(std::max<std::size_t>(desc.max_cells, 1))) break;
    const int a = d.x >= d.y && d.x >= d.z ? 0 : d.y >= d.z ? 1 : 2;
    cell_[a] *= 1.25f;
  }
  inv_cell_ = 1.0f / cell_;
  dims_ = count(cell_);
  const std::size_t cells = static_cast<std::size_t>(dims_.x) * dims_.y * dims_.z;
  std::vector<std::uint8_t> far_bytes(cells, 0);  // bytes while the blocks resolve in parallel, then bits
  // Slack for the float rounding of the votes (collider units): far below any useful reach.
  const float slack = 1e-4f * desc.reach + 1e-6f;
  const glm::vec3 pad = 1e-4f * cell_ + 1e-5f * (glm::abs(box_.lo) + glm::abs(box_.hi));
  // Far over [lo, hi] (cell units, exclusive hi): every point of the padded box.
  std::vector<std::array<DepthPyramid, 6>> stats(inner_->maps().size());
  std::vector<DepthPyramid> pyramids(inner_->maps().size());
  for (std::size_t m = 0; m < stats.size(); ++m) {
    const DepthMap& map = inner_->maps()[m];
    if (map.format == DepthMapFormat::cube8)
      stats[m] = facePyramids(map);
    else
      pyramids[m] = depthPyramid(map);
  }
  auto far = [&](glm::ivec3 lo, glm::ivec3 hi) {
    const glm::vec3 plo = box_.lo + glm::vec3(lo) * cell_ - pad, phi = box_.lo + glm::vec3(hi) * cell_ + pad;
    CellVerdict verdict;
    for (std::size_t m = 0; m < stats.size(); ++m) {
      const DepthMap& map = inner_->maps()[m];
      if (map.format == DepthMapFormat::cube8) {
        verdict.add(cubeRange(map, stats[m], plo, phi), desc.reach, slack);
      } else {
        VoteRange front, back;
        orthoRanges(map, pyramids[m], plo, phi, front, back);
        verdict.add(front, desc.reach, slack);
        verdict.add(back, desc.reach, slack);
      }
      if (verdict.near) return false;
    }
    return verdict.far();
  };
  // Blocks of kBlock³ cells first, halved while near a surface: a far block's cells are all far
  // (the bounds over a sub-box lie within the box's), so only cells near a surface are resolved.
  constexpr int kBlock = 8;
  auto resolve = [&](auto&& self, glm::ivec3 lo, glm::ivec3 hi) -> void {
    const bool whole = far(lo, hi);
    const glm::ivec3 extent = hi - lo;
    if (!whole && (extent.x > 1 || extent.y > 1 || extent.z > 1)) {
      const glm::ivec3 mid = lo + (extent + 1) / 2;
      for (int c = 0; c < 8; ++c) {
        const glm::ivec3 a((c & 1) ? mid.x : lo.x, (c & 2) ? mid.y : lo.y, (c & 4) ? mid.z : lo.z);
        const glm::ivec3 b((c & 1) ? hi.x : mid.x, (c & 2) ? hi.y : mid.y, (c & 4) ? hi.z : mid.z);
        if (a.x < b.x && a.y < b.y && a.z < b.z) self(self, a, b);
      }
      return;
    }
    for (int z = lo.z; z < hi.z; ++z)
      for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x) far_bytes[(static_cast<std::size_t>(z) * dims_.y + y) * dims_.x + x] = whole;
  };
  const glm::ivec3 blocks = (dims_ + (kBlock - 1)) / kBlock;
  par::parallelFor(par::Range<int>(0, blocks.z, 1), [&](const par::Range<int>& r) {
    for (int bz = r.begin(); bz != r.end(); ++bz)
      for (int by = 0; by < blocks.y; ++by)
        for (int bx = 0; bx < blocks.x; ++bx) {
          const glm::ivec3 lo = glm::ivec3(bx, by, bz) * kBlock;
          resolve(resolve, lo, glm::min(lo + kBlock, dims_));
        }
  });
  // One bit per cell: the grid is read once per particle and collider, at scattered cells, and a
  // byte per cell (megabytes) made those reads cache misses.
  far_bits_.assign((cells + 63) / 64, 0);
  for (std::size_t k = 0; k < cells; ++k)
    far_bits_[k / 64] |= static_cast<std::uint64_t>(far_bytes[k] != 0) << (k % 64);
}

double ReachCulledCollider::farFraction() const {
  const double cells = static_cast<double>(dims_.x) * dims_.y * dims_.z;
  std::size_t far = 0;
  for (const std::uint64_t word : far_bits_) far += static_cast<std::size_t>(std::popcount(word));
  return far_bits_.empty() ? 0.0 : static_cast<double>(far) / cells;
}

std::size_t ReachCulledCollider::cellOf(glm::vec3 p) const {
  if (!(p.x >= box_.lo.x && p.x <= box_.hi.x && p.y >= box_.lo.y && p.y <= box_.hi.y && p.z >= box_.lo.z &&
        p.z <= box_.hi.z))
    return kOutside;  // also NaN points
  const glm::vec3 c = (p - box_.lo) * inv_cell_;
  const int x = std::min(static_cast<int>(c.x), dims_.x - 1);
  const int y = std::min(static_cast<int>(c.y), dims_.y - 1);
  const int z = std::min(static_cast<int>(c.z), dims_.z - 1);
  return (static_cast<std::size_t>(z) * dims_.y + y) * dims_.x + x;
}

bool ReachCulledCollider::farCell(std::size_t cell) const {
  return cell == kOutside || ((far_bits_[cell / 64] >> (cell % 64)) & 1u) != 0;
}

bool ReachCulledCollider::culled(glm::vec3 p) const { return farCell(cellOf(p)); }

// What a culled point answers: beyond reach (invalid), as the maps would.
constexpr ColliderSample kCulled{FLT_MAX, glm::vec3(0.0f, 1.0f, 0.0f), false};

ColliderSample ReachCulledCollider::sample(glm::vec3 p) const {
  if (culled(p)) return kCulled;
  return inner_->sample(p);
}

// The points that survive the cull go to the collider as one batch per block (its batch query
// answers like its sample), so the maps' per-block set-up is shared by every point near a surface.
void ReachCulledCollider::query(std::span<const glm::vec3> points, std::span<ColliderSample> out) const {
  assert(points.size() == out.size());
  if (points.size() == 1) {
    out[0] = sample(points[0]);
    return;
  }
  constexpr std::size_t kBlock = 256;
  glm::vec3 kept[kBlock];
  std::uint32_t where[kBlock];
  std::size_t cell[kBlock];
  ColliderSample answers[kBlock];
  for (std::size_t b = 0; b < points.size(); b += kBlock) {
    const std::size_t count = std::min(kBlock, points.size() - b);
    // The block's cells first (with a prefetch of their bits), then the tests: the bit reads of a
    // block overlap instead of waiting one by one.
    for (std::size_t k = 0; k < count; ++k) {
      cell[k] = cellOf(points[b + k]);
      if (cell[k] != kOutside) __builtin_prefetch(far_bits_.data() + cell[k] / 64);
    }
    std::size_t q = 0;
    for (std::size_t k = b; k < b + count; ++k) {
      if (farCell(cell[k - b])) {
        out[k] = kCulled;
      } else {
        kept[q] = points[k];
        where[q++] = static_cast<std::uint32_t>(k);
      }
    }
    if (q == 0) continue;
    inner_->query(std::span<const glm::vec3>(kept, q), std::span<ColliderSample>(answers, q));
    for (std::size_t k = 0; k < q; ++k) out[where[k]] = answers[k];
  }
}

}  // namespace fluid
