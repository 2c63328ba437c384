// Depth-map collider queries: eq. (1) per ortho map, the §4.3 depth-cube distance, and rule (2)
// of Kolb et al. 2004 §4.1 combining the votes. Encodings: see collide.hpp.
#include "fluid/collide/collide.hpp"
#include "fluid/collide/map_sampling.hpp"
#include "fluid/core/parallel.hpp"

#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cassert>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace fluid {

namespace {

constexpr float kFarOutside = FLT_MAX;

// Winner bookkeeping: which map/texel decided f, so only one normal is decoded per point.
struct Winner {
  float f = -FLT_MAX;  // rule (2): start "far inside"
  const DepthMap* map = nullptr;
  std::uint32_t texel = 0;  // texel number within the map (cube: face·N·N + ...)
  std::uint8_t layer = 0;   // front_back16: 0 = front, 1 = back
  bool any_vote = false;
};

// Rule (2), order-independent form: f = min of the votes >= 0 if there is one, otherwise the
// max of the negative votes. (The printed iterative rule treats f_i = 0 as neither case; we
// count it as outside/on the surface.)
inline void vote(Winner& w, float fi, const DepthMap* map, std::uint32_t texel, std::uint8_t layer) {
  w.any_vote = true;
  const bool take = fi >= 0.0f ? (w.f < 0.0f || fi < w.f) : (w.f < 0.0f && fi > w.f);
  if (take) {
    w.f = fi;
    w.map = map;
    w.texel = texel;
    w.layer = layer;
  }
}

inline void invalidVote(Winner& w, const DepthMap& map) {
  if (map.encloses_collider) vote(w, kFarOutside, nullptr, 0, 0);
}

using collide_detail::depthHalf;
using collide_detail::transformPoint;

inline std::uint16_t loadU16(const std::uint8_t* p) {
  std::uint16_t v;
  std::memcpy(&v, p, 2);
  return v;
}

// The answer of a collider with no opinion: "far outside" (invalid), the normal a default sample has.
constexpr ColliderSample kNoOpinion{FLT_MAX, {0.0f, 0.0f, 1.0f}, false};

// The bits of a texel that its votes read, as one 32-bit word: front_back16 front | back << 16,
// fixed8 and cube8 the 16-bit code, float32 the depth's bits. The collider keeps these words
// beside the texels (DepthMapCollider::vote_words_): half (front_back16) or a quarter (float32) of
// the texel bytes, so a lookup's scattered reads touch fewer cache lines. The normal indices are
// read from the texels, once per point, for the winning vote only.
std::uint32_t voteWord(const DepthMap& map, std::size_t texel) {
  const std::uint8_t* t = map.texels.data() + texel * texelBytes(map.format);
  switch (map.format) {
    case DepthMapFormat::float32: {
      std::uint32_t bits;
      std::memcpy(&bits, t + 12, 4);
      return bits;
    }
    case DepthMapFormat::front_back16:
      return static_cast<std::uint32_t>(loadU16(t + 4)) | (static_cast<std::uint32_t>(loadU16(t + 6)) << 16);
    case DepthMapFormat::fixed8:
    case DepthMapFormat::cube8:
      break;
  }
  return static_cast<std::uint32_t>((t[2] << 8) | t[3]);
}

// Where a point falls in an ortho map: P' = T·P and, inside the footprint, its texel (outside it
// texel 0, never voted with: the batch query computes every point's texel without a branch and
// fetches the texels of a block before it votes, so the cache misses of a block overlap).
struct OrthoSpot {
  glm::vec3 q;
  std::uint32_t texel;
  bool inside;
};

inline OrthoSpot orthoSpot(const DepthMap& map, glm::vec3 p) {
  OrthoSpot s;
  s.q = transformPoint(map.collider_to_map, p);
  // Outside the map's footprint the vote is invalid (§4.1).
  s.inside = s.q.x >= 0.0f && s.q.x < 1.0f && s.q.y >= 0.0f && s.q.y < 1.0f;
  const int n = static_cast<int>(map.resolution);
  const float nf = static_cast<float>(n);
  const int i = std::min(static_cast<int>((s.inside ? s.q.x : 0.0f) * nf), n - 1);
  const int j = std::min(static_cast<int>((s.inside ? s.q.y : 0.0f) * nf), n - 1);
  s.texel = static_cast<std::uint32_t>(j) * map.resolution + static_cast<std::uint32_t>(i);
  return s;
}

// The votes of an ortho map at a located point (eq. (1)). `ring` receives the votes of
// margin-ring texels (MapSpec::margin) of front_back16 maps baked with one: equal front and back
// depth bits mark them. They are only a fallback (see finish). The format is a template argument
// so the batch query picks it once per map; sample() and the batch run this same code.
template <DepthMapFormat kFormat>
inline void orthoVotes(Winner& w, Winner& ring, const DepthMap& map, const OrthoSpot& spot,
                       const std::uint32_t* words) {
  constexpr bool two = kFormat == DepthMapFormat::front_back16;
  if (!spot.inside) {
    if (two) invalidVote(w, map);
    return invalidVote(w, map);
  }
  const glm::vec3 q = spot.q;
  const std::uint32_t texel = spot.texel;
  // Along the view direction a LESS map is valid up to its far plane and a GREATER map from
  // its near plane on: a point in front of the near plane is still in front of the first
  // surface, so eq. (1) holds there; behind the far plane it would wrongly read "inside".
  const bool less_ok = q.z <= 1.0f, greater_ok = q.z >= 0.0f;
  const std::uint32_t word = words[texel];  // voteWord of the texel
  if constexpr (kFormat == DepthMapFormat::front_back16) {
    const std::uint16_t front_bits = static_cast<std::uint16_t>(word & 0xFFFFu);
    const std::uint16_t back_bits = static_cast<std::uint16_t>(word >> 16);
    const float front = depthHalf(front_bits);
    const float back = depthHalf(back_bits);
    Winner& to = map.margin_ring && front_bits == back_bits && front >= 0.0f ? ring : w;
    if (front < 0.0f || !less_ok) {
      invalidVote(w, map);
    } else {
      vote(to, map.z_scale * (front - q.z), &map, texel, 0);  // eq. (1), LESS
    }
    if (back < 0.0f || !greater_ok) {
      invalidVote(w, map);
    } else {
      vote(to, map.z_scale * (q.z - back), &map, texel, 1);  // GREATER: negated eq. (1)
    }
  } else {
    const bool less = map.compare == DepthCompare::less;
    const float sign_less = less ? 1.0f : -1.0f;
    if constexpr (kFormat == DepthMapFormat::float32) {
      float depth;
      std::memcpy(&depth, &word, 4);
      if (depth < 0.0f || !(less ? less_ok : greater_ok)) return invalidVote(w, map);
      vote(w, sign_less * map.z_scale * (depth - q.z), &map, texel, 0);
    } else {
      static_assert(kFormat == DepthMapFormat::fixed8, "cube8 is handled by cubeVote");
      const std::uint16_t code = static_cast<std::uint16_t>(word);
      if (code == kFixedBackground || !(less ? less_ok : greater_ok)) return invalidVote(w, map);
      vote(w, sign_less * map.z_scale * (decodeFixedDepth(code) - q.z), &map, texel, 0);
    }
  }
}

// Cube face and face-local (sc, tc) by the OpenGL cube-map table (collide.hpp).
inline int cubeFace(glm::vec3 d, float& sc, float& tc, float& ma) {
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  if (ax >= ay && ax >= az) {
    ma = ax;
    tc = -d.y;
    if (d.x >= 0.0f) {
      sc = -d.z;
      return 0;
    }
    sc = d.z;
    return 1;
  }
  if (ay >= az) {
    ma = ay;
    sc = d.x;
    if (d.y >= 0.0f) {
      tc = d.z;
      return 2;
    }
    tc = -d.z;
    return 3;
  }
  ma = az;
  tc = -d.y;
  if (d.z >= 0.0f) {
    sc = d.x;
    return 4;
  }
  sc = -d.x;
  return 5;
}

// Where a point falls in a depth cube: inside the view volume, its distance L from the centre,
// the direction and the texel (outside: those of the centre, never voted with; see OrthoSpot).
struct CubeSpot {
  glm::vec3 dir;
  float length;
  std::uint32_t texel;
  bool inside;
};

inline CubeSpot cubeSpot(const DepthMap& map, glm::vec3 p) {
  CubeSpot spot;
  const glm::vec3 mapped = transformPoint(map.collider_to_map, p);
  spot.inside = std::fabs(mapped.x) <= 1.0f && std::fabs(mapped.y) <= 1.0f && std::fabs(mapped.z) <= 1.0f;
  const glm::vec3 q = spot.inside ? mapped : glm::vec3(0.0f);
  const float length = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  const glm::vec3 dir = length > 0.0f ? q / length : glm::vec3(0.0f, 0.0f, 1.0f);
  float sc, tc, ma;
  const int face = cubeFace(length > 0.0f ? q : dir, sc, tc, ma);
  const int n = static_cast<int>(map.resolution);
  const float nf = static_cast<float>(n);
  const float s = (sc / ma + 1.0f) * 0.5f;
  const float t = (tc / ma + 1.0f) * 0.5f;
  const int i = std::clamp(static_cast<int>(s * nf), 0, n - 1);
  const int j = std::clamp(static_cast<int>(t * nf), 0, n - 1);
  spot.texel = static_cast<std::uint32_t>(face) * map.resolution * map.resolution +
               static_cast<std::uint32_t>(j) * map.resolution + static_cast<std::uint32_t>(i);
  spot.length = length;
  spot.dir = dir;
  return spot;
}

inline void cubeVote(Winner& w, const DepthMap& map, const CubeSpot& spot, const std::uint32_t* words) {
  if (!spot.inside) return invalidVote(w, map);
  const std::uint16_t code = static_cast<std::uint16_t>(words[spot.texel]);
  if (code == kFixedBackground) return invalidVote(w, map);
  const float r = static_cast<float>(code) * kCubeRadiusStep;
  // §4.3: (1 − r/L)·|S·P'| = (L − r)·|S·dir|, signed so a LESS cube calls the centre side outside.
  const float along = glm::length(map.cube_scale * spot.dir);
  const float f = (map.compare == DepthCompare::less ? (r - spot.length) : (spot.length - r)) * along;
  vote(w, f, &map, spot.texel, 0);
}

}  // namespace

DepthMapCollider::DepthMapCollider(std::vector<DepthMap> maps, int normal_resolution)
    : maps_(std::move(maps)), normal_resolution_(normal_resolution) {
  assert(normal_resolution_ >= 1 && normal_resolution_ <= 256);
  const std::vector<float> rgb = l1NormalTexture(normal_resolution_);
  normal_table_.resize(rgb.size() / 3);
  for (std::size_t k = 0; k < normal_table_.size(); ++k)
    normal_table_[k] = {rgb[3 * k], rgb[3 * k + 1], rgb[3 * k + 2]};
  vote_words_.resize(maps_.size());
  for (std::size_t m = 0; m < maps_.size(); ++m) {
    const DepthMap& map = maps_[m];
    std::vector<std::uint32_t>& words = vote_words_[m];
    words.resize(map.texels.size() / texelBytes(map.format));
    for (std::size_t t = 0; t < words.size(); ++t) words[t] = voteWord(map, t);
  }
}

int DepthMapCollider::depthMapCount() const {
  int count = 0;
  for (const DepthMap& m : maps_) {
    count += m.format == DepthMapFormat::front_back16 ? 2 : m.format == DepthMapFormat::cube8 ? 6 : 1;
  }
  return count;
}

std::size_t DepthMapCollider::bytes() const {
  std::size_t total = 0;
  for (const DepthMap& m : maps_) total += m.texels.size();
  return total;
}

namespace {

// One map's votes over a block of points, in two loops: every point's texel first (and a
// prefetch of it), then the votes. The texel reads are what a lookup waits for (the maps are
// megabytes, the particles' texels scattered over them); the first loop has no branch, so the
// block's misses overlap instead of coming one vote at a time. Each point receives the same
// votes as from allVotes, in map order.
template <DepthMapFormat kFormat>
void orthoBlock(Winner* main, Winner* ring, const DepthMap& map, const std::uint32_t* words, const glm::vec3* points,
                std::size_t count, OrthoSpot* spots) {
  for (std::size_t k = 0; k < count; ++k) {
    spots[k] = orthoSpot(map, points[k]);
    __builtin_prefetch(words + spots[k].texel);
  }
  for (std::size_t k = 0; k < count; ++k) orthoVotes<kFormat>(main[k], ring[k], map, spots[k], words);
}

void cubeBlock(Winner* main, const DepthMap& map, const std::uint32_t* words, const glm::vec3* points,
               std::size_t count, CubeSpot* spots) {
  for (std::size_t k = 0; k < count; ++k) {
    spots[k] = cubeSpot(map, points[k]);
    __builtin_prefetch(words + spots[k].texel);
  }
  for (std::size_t k = 0; k < count; ++k) cubeVote(main[k], map, spots[k], words);
}

// Every map's votes over a block of points (finite ones), map after map: each point sees the maps
// in order, so ties go to the same map whatever the block. `spots` are caller scratch of `count`.
void votesOverBlock(Winner* main, Winner* ring, const std::vector<DepthMap>& maps,
                    const std::vector<std::vector<std::uint32_t>>& vote_words, const glm::vec3* points,
                    std::size_t count, OrthoSpot* ortho_spots, CubeSpot* cube_spots) {
  for (std::size_t m = 0; m < maps.size(); ++m) {
    const DepthMap& map = maps[m];
    const std::uint32_t* words = vote_words[m].data();
    switch (map.format) {
      case DepthMapFormat::float32:
        orthoBlock<DepthMapFormat::float32>(main, ring, map, words, points, count, ortho_spots);
        break;
      case DepthMapFormat::fixed8:
        orthoBlock<DepthMapFormat::fixed8>(main, ring, map, words, points, count, ortho_spots);
        break;
      case DepthMapFormat::front_back16:
        orthoBlock<DepthMapFormat::front_back16>(main, ring, map, words, points, count, ortho_spots);
        break;
      case DepthMapFormat::cube8:
        cubeBlock(main, map, words, points, count, cube_spots);
        break;
    }
  }
}

// The winner whose vote is the answer. Margin-ring votes only measure the depth offset to the
// nearest silhouette point (never "inside", but short of the lateral offset), so they decide only
// where no map sees the point outside: with no vote, only "far outside" votes, or only inside
// votes (a point beside a silhouette that the other maps place between their surfaces).
inline const Winner& decisive(const Winner& main, const Winner& ring) {
  const bool main_outside = main.any_vote && main.map != nullptr && main.f >= 0.0f;
  return ring.any_vote && !main_outside ? ring : main;
}

// The winning texel's bytes (where its normal index is), or null when there is no answer.
inline const std::uint8_t* winningTexel(const Winner& w) {
  if (!w.any_vote || w.map == nullptr) return nullptr;
  return w.map->texels.data() + static_cast<std::size_t>(w.texel) * texelBytes(w.map->format);
}

// Rule (2)'s result from the winners (one normal decoded per point).
ColliderSample finish(const Winner& main, const Winner& ring, const std::vector<glm::vec3>& normal_table,
                      int normal_resolution) {
  const Winner& w = decisive(main, ring);
  const std::uint8_t* t = winningTexel(w);
  if (t == nullptr) return kNoOpinion;  // no opinion, or only "far outside"
  ColliderSample out;
  out.valid = true;
  out.distance = w.f;
  const DepthMap& m = *w.map;
  std::uint32_t index = 0;
  switch (m.format) {
    case DepthMapFormat::float32: {
      float n[3];
      std::memcpy(n, t, 12);
      out.normal = {n[0], n[1], n[2]};
      return out;
    }
    case DepthMapFormat::fixed8:
    case DepthMapFormat::cube8:
      index = static_cast<std::uint32_t>(t[1]) * static_cast<std::uint32_t>(normal_resolution) + t[0];
      break;
    case DepthMapFormat::front_back16: {
      const std::uint16_t packed = loadU16(t + 2 * w.layer);
      index =
          static_cast<std::uint32_t>(packed >> 8) * static_cast<std::uint32_t>(normal_resolution) + (packed & 0xFFu);
      break;
    }
  }
  out.normal = normal_table[index];
  return out;
}

}  // namespace

ColliderSample DepthMapCollider::sample(glm::vec3 p) const {
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return kNoOpinion;
  Winner main, ring;
  OrthoSpot ortho_spot;
  CubeSpot cube_spot;
  votesOverBlock(&main, &ring, maps_, vote_words_, &p, 1, &ortho_spot, &cube_spot);
  return finish(main, ring, normal_table_, normal_resolution_);
}

DepthMapCollider::Decider DepthMapCollider::decider(glm::vec3 p) const {
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return Decider::none;
  Winner main, ring;
  OrthoSpot ortho_spot;
  CubeSpot cube_spot;
  votesOverBlock(&main, &ring, maps_, vote_words_, &p, 1, &ortho_spot, &cube_spot);
  const Winner& w = decisive(main, ring);
  if (winningTexel(w) == nullptr) return Decider::none;
  return &w == &ring ? Decider::ring : Decider::map;
}

// Batch form of sample(), bit-identical to it: blocks of points, each map's votes cast over the
// whole block before the next map's (every point still sees the maps in order, so ties go to the
// same map), and the format switch and the map's constants are paid once per block, not per point.
void DepthMapCollider::query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const {
  assert(local_points.size() == out.size());
  if (local_points.size() == 1) {
    out[0] = sample(local_points[0]);
    return;
  }
  constexpr std::size_t kBlock = 64;
  glm::vec3 points[kBlock];
  bool finite[kBlock];
  Winner main[kBlock], ring[kBlock];
  OrthoSpot ortho_spots[kBlock];
  CubeSpot cube_spots[kBlock];
  for (std::size_t b = 0; b < local_points.size(); b += kBlock) {
    const std::size_t count = std::min(kBlock, local_points.size() - b);
    for (std::size_t k = 0; k < count; ++k) {
      const glm::vec3 p = local_points[b + k];
      finite[k] = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      points[k] = finite[k] ? p : glm::vec3(0.0f);  // voted on, then answered as sample() does
      main[k] = Winner{};
      ring[k] = Winner{};
    }
    votesOverBlock(main, ring, maps_, vote_words_, points, count, ortho_spots, cube_spots);
    // The winners' texels (their normal indices) are not among the vote words read above.
    for (std::size_t k = 0; k < count; ++k)
      if (const std::uint8_t* t = winningTexel(decisive(main[k], ring[k]))) __builtin_prefetch(t);
    for (std::size_t k = 0; k < count; ++k)
      out[b + k] = finite[k] ? finish(main[k], ring[k], normal_table_, normal_resolution_) : kNoOpinion;
  }
}

// ---- batch ---------------------------------------------------------------------------

std::size_t queryParallel(const SignedDistanceShape& shape, std::span<const glm::vec3> points,
                          std::span<ColliderSample> out, const ParallelDesc& desc) {
  assert(points.size() == out.size());
  const std::size_t grain = std::max<std::size_t>(desc.grain, 1);
  auto run = [&] {
    par::parallelFor(par::Range<std::size_t>(0, points.size(), grain), [&](const par::Range<std::size_t>& r) {
      shape.query(points.subspan(r.begin(), r.size()), out.subspan(r.begin(), r.size()));
    });
  };
  if (desc.threads == 1 || points.size() <= grain) {
    shape.query(points, out);
  } else if (desc.threads <= 0) {
    run();  // the caller's arena: no arena set-up per call (per-frame use)
  } else {
    tbb::task_arena arena(desc.threads);
    arena.execute(run);
  }
  std::size_t non_finite = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const glm::vec3 p = points[k];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      ++non_finite;
      out[k] = kNoOpinion;  // whatever the shape wrote
    }
  }
  return non_finite;
}

std::size_t queryWorld(const SignedDistanceShape& shape, const ColliderPose& pose, std::span<const glm::vec3> world,
                       std::span<ColliderSample> out, std::vector<glm::vec3>& scratch, const ParallelDesc& desc) {
  assert(world.size() == out.size());
  scratch.resize(world.size());
  const glm::quat inverse = glm::inverse(pose.rotation);
  for (std::size_t k = 0; k < world.size(); ++k) scratch[k] = inverse * (world[k] - pose.translation);
  const std::size_t bad = queryParallel(shape, scratch, out, desc);
  for (ColliderSample& s : out) {
    if (s.valid) s.normal = pose.rotation * s.normal;
  }
  return bad;
}

namespace {

// No coordinate is inf or NaN: x * 0 is NaN exactly then, so one compare checks all three (this
// runs for every particle and collider, most of which then need nothing else).
bool finitePoint(glm::vec3 p) { return glm::dot(p, glm::vec3(0.0f)) == 0.0f; }

// The posed collider as collideParticles samples it: the pose, its inverse and whether it is the
// identity (a level's colliders, baked in world coordinates: no transform needed, the same samples).
struct PosedShape {
  const SignedDistanceShape& shape;
  const ColliderPose& pose;
  glm::quat inverse;
  bool identity;

  glm::vec3 local(glm::vec3 world) const { return identity ? world : inverse * (world - pose.translation); }
  // A valid normal comes back in world space; `finite` false: no opinion (nothing is queried).
  ColliderSample sample(glm::vec3 local_point, bool finite) const {
    if (!finite) return kNoOpinion;
    ColliderSample s;
    shape.query({&local_point, 1}, {&s, 1});
    if (s.valid && !identity) s.normal = pose.rotation * s.normal;
    return s;
  }
};

// The segment from a to b (collider space) misses the box.
bool segmentMissesBox(glm::vec3 a, glm::vec3 b, const Bounds& box) {
  const glm::vec3 lo = glm::min(a, b), hi = glm::max(a, b);
  return glm::any(glm::lessThan(hi, box.lo)) || glm::any(glm::greaterThan(lo, box.hi));
}

CollisionOutcome collideOne(const PosedShape& posed, glm::vec3 previous, glm::vec3& predicted_position,
                            glm::vec3& velocity, const CollideDesc& desc, CollideCounts& counts) {
  glm::vec3 predicted = predicted_position;
  const glm::vec3 local_predicted = posed.local(predicted);
  if (desc.bounded && segmentMissesBox(posed.local(previous), local_predicted, desc.inside))
    return CollisionOutcome::none;
  const glm::vec3 step = predicted - previous;
  // A non-finite position has no opinion (as queryWorld). One check for the pair: the step is
  // finite unless a coordinate of either end is inf or NaN (or it overflows: then both ends are).
  bool previous_finite = true, predicted_finite = true;
  if (!finitePoint(step)) {
    previous_finite = finitePoint(previous);
    predicted_finite = finitePoint(predicted);
    counts.non_finite += !previous_finite + !predicted_finite;
  }
  ColliderSample after = posed.sample(local_predicted, predicted_finite);
  // Swept (beyond the paper): the first sample inside along the step decides, whether or not the
  // end point is inside. An end point past the middle of a thin wall is inside too, but nearer the
  // far face: reacting to it would push the particle out through the far face.
  if (desc.max_step > 0.0f) {
    const float length = glm::length(step);
    if (std::isfinite(length) && length > desc.max_step) {
      const int samples = static_cast<int>(std::min(std::ceil(length / desc.max_step), 4096.0f));
      for (int s = 1; s < samples; ++s) {
        const glm::vec3 world = previous + step * (static_cast<float>(s) / static_cast<float>(samples));
        const ColliderSample hit = posed.sample(posed.local(world), true);  // between two finite ends
        if (hit.valid && hit.distance < 0.0f) {
          after = hit;
          predicted = world;
          ++counts.swept;
          break;
        }
      }
    }
  }
  if (!after.valid || after.distance >= 0.0f) return CollisionOutcome::none;
  // §3.3.2: the collision test is done twice, at the previous and the expected position.
  const ColliderSample before = posed.sample(posed.local(previous), previous_finite);
  const CollisionResult r =
      resolveCollision(previous, before, predicted, velocity, after, colliderVelocityAt(posed.pose, predicted), desc.dt,
                       desc.skin, desc.material);
  predicted_position = r.position;
  velocity = r.velocity;
  counts.reacted += r.outcome == CollisionOutcome::reacted;
  counts.pushed_out += r.outcome == CollisionOutcome::pushed_out;
  return r.outcome;
}

}  // namespace

CollideCounts collideParticles(const SignedDistanceShape& shape, const ColliderPose& pose,
                               std::span<const glm::vec3> previous_positions, std::span<glm::vec3> predicted_positions,
                               std::span<glm::vec3> predicted_velocities, const CollideDesc& desc,
                               CollideScratch& scratch) {
  const std::size_t n = previous_positions.size();
  assert(predicted_positions.size() == n && predicted_velocities.size() == n);
  scratch.outcome.resize(n);
  const PosedShape posed{shape, pose, glm::inverse(pose.rotation),
                         pose.rotation == glm::quat(1.0f, 0.0f, 0.0f, 0.0f) && pose.translation == glm::vec3(0.0f)};
  auto chunk = [&](const par::Range<std::size_t>& r, CollideCounts counts) {
    // Local copies: the shape's (virtual) query could write anything the caller can reach, so
    // values read through the captured references would be reloaded after every query.
    const PosedShape p = posed;
    const CollideDesc d = desc;
    const glm::vec3* previous = previous_positions.data();
    glm::vec3* predicted = predicted_positions.data();
    glm::vec3* velocity = predicted_velocities.data();
    CollisionOutcome* outcome = scratch.outcome.data();
    for (std::size_t k = r.begin(); k != r.end(); ++k)
      outcome[k] = collideOne(p, previous[k], predicted[k], velocity[k], d, counts);
    return counts;
  };
  const std::size_t grain = std::max<std::size_t>(desc.parallel.grain, 1);
  if (desc.parallel.threads == 1 || n <= grain) return chunk(par::Range<std::size_t>(0, n), CollideCounts{});
  auto join = [](CollideCounts a, const CollideCounts& b) {
    a.reacted += b.reacted;
    a.pushed_out += b.pushed_out;
    a.non_finite += b.non_finite;
    a.swept += b.swept;
    return a;
  };
  // Integer sums: the same for any split, so the non-deterministic (faster) reduce is fine.
  auto run = [&] { return par::parallelReduce(par::Range<std::size_t>(0, n, grain), CollideCounts{}, chunk, join); };
  if (desc.parallel.threads <= 0) return run();  // the caller's arena: no arena set-up per call
  tbb::task_arena arena(desc.parallel.threads);
  return arena.execute(run);
}

}  // namespace fluid
