// Near-surface coverage of a depth-map collider and the automatic concave-region cubes
// (coverage.hpp; Kolb et al. 2004 §4.1 and §4.3).
#include "fluid/collide/coverage.hpp"

#include "fluid/core/parallel.hpp"

#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <random>
#include <thread>

namespace fluid {

namespace {

int threadCount(int requested) {
  return requested > 0 ? requested : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

std::string shortest(float value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

float maxAbs(glm::vec3 v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

// What a LESS depth cube centred at `c` answers for the sample point (§4.3: the distance along the
// ray from the centre through the point to the first surface it meets, positive before it), as far
// as the ray cast through the point itself predicts it (the baked texel's ray passes within half a
// texel). `hit` receives the surface point; false when the ray meets nothing.
bool predictCubeVote(const MeshDistance& exact, glm::vec3 c, glm::vec3 p, float& vote, glm::vec3& hit) {
  const glm::vec3 dir = p - c;
  const float length = glm::length(dir);
  if (!(length > 0.0f)) return false;
  const float t = exact.firstHit(c, dir);
  if (!std::isfinite(t)) return false;
  hit = c + t * dir;
  vote = (t - 1.0f) * length;
  return true;
}

// From an unmeasured point, away from its nearest surface point, to the lattice step of largest
// clearance (exact distance): the middle of the cavity the point lies in, where a cube sees its
// walls at the steepest angles. Inside points start at their nearest surface point, outside them.
struct Candidate {
  glm::vec3 center{0.0f};
  float clearance = 0.0f;
};

Candidate marchToClearance(const MeshDistance& exact, const ColliderSample& e, glm::vec3 p, const Bounds& box,
                           float step) {
  Candidate best;
  const glm::vec3 n = e.normal;
  const glm::vec3 start = e.distance < 0.0f ? p + n * (-e.distance) : p;
  const float diagonal = glm::length(box.hi - box.lo);
  for (float s = step; s <= diagonal; s += step) {
    const glm::vec3 q = start + n * s;
    if (glm::any(glm::lessThan(q, box.lo)) || glm::any(glm::greaterThan(q, box.hi))) break;
    const float d = exact.unsignedDistance(q, diagonal);
    if (d > best.clearance) best = {q, d};
    if (d < 0.5f * best.clearance) break;  // past the middle of the cavity
  }
  return best;
}

// The view volume of a cube at `c`: every covered point and its wall inside, plus a tolerance,
// capped below the half size at which the box would enclose the collider (then its background,
// ray-sampled and not conservative, would read "far outside", §4.1).
float cubeHalfExtent(glm::vec3 c, const std::vector<glm::vec3>& reached, const Bounds& bounds, float tolerance) {
  float half = 0.0f;
  for (const glm::vec3& q : reached) half = std::max(half, maxAbs(q - c));
  half += 2.0f * tolerance;
  // The box [c ± half] encloses the bounds once half reaches the largest per-axis distance to a face.
  glm::vec3 need(0.0f);
  for (int a = 0; a < 3; ++a) need[a] = std::max(std::fabs(bounds.lo[a] - c[a]), std::fabs(bounds.hi[a] - c[a]));
  const float enclosing = std::max({need.x, need.y, need.z});
  return std::min(half, 0.999f * enclosing);
}

// The smallest power of two (16 .. max_res) whose texels at `distance` from the cube centre are no
// larger than `texel`: a face spans 2·H at distance H, so 2·distance / N at `distance` (§4.3).
int cubeResolution(float distance, float texel, int max_res) {
  const float wanted = texel > 0.0f ? 2.0f * distance / texel : static_cast<float>(max_res);
  const auto n = static_cast<unsigned>(std::clamp(std::ceil(wanted), 16.0f, static_cast<float>(max_res)));
  return std::min(static_cast<int>(std::bit_ceil(n)), max_res);
}

struct Choice {
  Candidate at;
  std::vector<glm::vec3> reached;  // covered points and their walls
  float far = 0.0f;                // largest distance from the centre to a wall it measures
  std::size_t count = 0;
};

// Scores every candidate centre over `targets` (unmeasured point indices) and returns the best.
Choice bestCenter(const MeshDistance& exact, const NearSurfaceSamples& samples,
                  const std::vector<Candidate>& candidates, const std::vector<std::uint32_t>& targets,
                  float tolerance) {
  std::vector<Choice> choices(candidates.size());
  par::parallelFor(par::Range<std::size_t>(0, candidates.size(), 1), [&](const par::Range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      Choice& ch = choices[k];
      ch.at = candidates[k];
      for (std::uint32_t i : targets) {
        const glm::vec3 p = samples.points[i];
        float vote = 0.0f;
        glm::vec3 hit;
        if (!predictCubeVote(exact, ch.at.center, p, vote, hit)) continue;
        // Held to the ring's standard (within a factor of two): a cube is worth its bytes only
        // where it measures the distance, not merely brings it within reach.
        ColliderSample predicted{vote, glm::vec3(0.0f, 0.0f, 1.0f), true};
        if (!measuredSample(predicted, samples.exact[i], tolerance, samples.reach, true)) continue;
        ++ch.count;
        ch.reached.push_back(p);
        ch.reached.push_back(hit);
        ch.far = std::max(ch.far, glm::length(hit - ch.at.center));
      }
    }
  });
  Choice best;
  for (Choice& ch : choices) {
    if (ch.count > best.count || (ch.count == best.count && ch.count > 0 && ch.at.clearance > best.at.clearance))
      best = std::move(ch);
  }
  return best;
}

// Up to `limit` of `from`, evenly spread (deterministic).
std::vector<std::uint32_t> spread(const std::vector<std::uint32_t>& from, std::size_t limit) {
  if (from.size() <= limit) return from;
  std::vector<std::uint32_t> out;
  for (std::size_t k = 0; k < limit; ++k) out.push_back(from[k * from.size() / limit]);
  return out;
}

}  // namespace

NearSurfaceSamples nearSurfaceSamples(const MeshDistance& exact, const Bounds& bounds, const CoverageDesc& desc) {
  NearSurfaceSamples out;
  out.reach = desc.reach;
  const glm::vec3 lo = bounds.lo - glm::vec3(desc.reach), hi = bounds.hi + glm::vec3(desc.reach);
  const glm::vec3 size = hi - lo;
  const double volume = static_cast<double>(size.x) * size.y * size.z;
  const double per_point = volume / static_cast<double>(std::max<std::size_t>(desc.max_points, 1));
  out.spacing = std::max(desc.reach / 4.0f, static_cast<float>(std::cbrt(per_point)));
  if (!(out.spacing > 0.0f) || !std::isfinite(out.spacing)) return out;
  const glm::ivec3 cells = glm::max(glm::ivec3(glm::ceil(size / out.spacing)), glm::ivec3(1));
  // Jittered within each lattice cell: the points do not line up with texel centres or facets.
  std::mt19937 rng(desc.seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> lattice;
  lattice.reserve(static_cast<std::size_t>(cells.x) * cells.y * cells.z);
  for (int k = 0; k < cells.z; ++k)
    for (int j = 0; j < cells.y; ++j)
      for (int i = 0; i < cells.x; ++i) {
        const glm::vec3 cell(static_cast<float>(i), static_cast<float>(j), static_cast<float>(k));
        const glm::vec3 jitter(u(rng), u(rng), u(rng));
        lattice.push_back(lo + (cell + jitter) * out.spacing);
      }
  out.lattice = lattice.size();
  // The cheap unsigned search (pruned at reach) first; the inside test only for the near points.
  std::vector<char> near(lattice.size(), 0);
  tbb::task_arena arena(threadCount(desc.threads));
  arena.execute([&] {
    par::parallelFor(par::Range<std::size_t>(0, lattice.size(), 1024), [&](const par::Range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        near[k] = exact.unsignedDistance(lattice[k], desc.reach) < desc.reach;
    });
  });
  for (std::size_t k = 0; k < lattice.size(); ++k)
    if (near[k]) out.points.push_back(lattice[k]);
  out.exact.resize(out.points.size());
  arena.execute([&] { queryParallel(exact, out.points, out.exact, {0, 256}); });
  return out;
}

bool coveredSample(const ColliderSample& got, const ColliderSample& exact, float tolerance) {
  if (!got.valid || !std::isfinite(got.distance) || !exact.valid) return false;
  return std::fabs(exact.distance) < tolerance || (got.distance < 0.0f) == (exact.distance < 0.0f);
}

bool measuredSample(const ColliderSample& got, const ColliderSample& exact, float tolerance, float reach, bool ring) {
  if (!coveredSample(got, exact, tolerance)) return false;
  const float want = std::fabs(exact.distance), have = std::fabs(got.distance);
  const bool within_twice = have <= 2.0f * want + tolerance;
  if (ring) return within_twice && have >= 0.5f * want - tolerance;
  return within_twice || have < reach;
}

CoverageReport measureCoverage(const SignedDistanceShape& shape, const NearSurfaceSamples& samples, float tolerance,
                               int threads, const DepthMapCollider* maps) {
  CoverageReport report;
  report.near = samples.points.size();
  std::vector<ColliderSample> got(samples.points.size());
  std::vector<char> ring(samples.points.size(), 0);
  if (maps == nullptr) maps = dynamic_cast<const DepthMapCollider*>(&shape);
  tbb::task_arena arena(threadCount(threads));
  arena.execute([&] {
    queryParallel(shape, samples.points, got, {0, 1024});
    if (maps == nullptr) return;
    par::parallelFor(par::Range<std::size_t>(0, got.size(), 1024), [&](const par::Range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        ring[k] = maps->decider(samples.points[k]) == DepthMapCollider::Decider::ring;
    });
  });
  double sum = 0.0;
  std::size_t finite = 0;
  for (std::size_t k = 0; k < got.size(); ++k) {
    const ColliderSample& g = got[k];
    const ColliderSample& e = samples.exact[k];
    const bool has = g.valid && std::isfinite(g.distance);
    if (has) {
      const double error = std::fabs(static_cast<double>(g.distance) - e.distance);
      sum += error;
      report.max_abs_error = std::max(report.max_abs_error, error);
      ++finite;
    }
    if (measuredSample(g, e, tolerance, samples.reach, ring[k] != 0)) continue;
    report.unmeasured.push_back(static_cast<std::uint32_t>(k));
    if (!coveredSample(g, e, tolerance)) {
      if (report.uncovered() == 0) report.first_uncovered = static_cast<std::uint32_t>(k);
      ++(has ? report.wrong_sign : report.beyond_reach);
    } else {
      ++(ring[k] ? report.ring_guess : report.off_distance);
    }
  }
  report.mean_abs_error = finite > 0 ? sum / static_cast<double>(finite) : 0.0;
  return report;
}

float coverageTolerance(std::span<const MapSpec> specs) {
  float texel = 0.0f;
  for (const MapSpec& s : specs) {
    if (s.kind != MapKind::ortho) continue;
    texel = std::max(texel, 2.0f * std::max(s.ortho.half_extent.x, s.ortho.half_extent.y) / s.resolution);
  }
  if (texel == 0.0f && !specs.empty()) texel = 2.0f * maxAbs(specs.front().cube.half_extent) / specs.front().resolution;
  return texel;
}

std::string cubeItemText(glm::vec3 center, float half_extent, int resolution) {
  return "cube@" + shortest(center.x) + ":" + shortest(center.y) + ":" + shortest(center.z) + ":" +
         shortest(half_extent) + ":" + std::to_string(resolution);
}

ConcaveCubesResult chooseConcaveCubes(const MeshView& mesh, const MeshDistance& exact,
                                      const NearSurfaceSamples& samples, std::span<const MapSpec> base_specs,
                                      std::span<const DepthMap> base, const ConcaveCubesDesc& desc) {
  ConcaveCubesResult result;
  const float tolerance = desc.tolerance > 0.0f ? desc.tolerance : coverageTolerance(base_specs);
  const Bounds bounds = meshBounds(mesh);
  const Bounds box{bounds.lo - glm::vec3(samples.reach), bounds.hi + glm::vec3(samples.reach)};
  std::vector<DepthMap> maps(base.begin(), base.end());
  result.before = measureCoverage(DepthMapCollider(maps, desc.normal_resolution), samples, tolerance, desc.threads);
  result.after = result.before;
  tbb::task_arena arena(threadCount(desc.threads));
  while (static_cast<int>(result.cubes.size()) < desc.max_cubes && !result.after.unmeasured.empty()) {
    // Only points a cube can help: those whose answer misses the surface on the outside, or
    // overestimates an inside depth. (A positive vote on an inside point wins rule (2) whatever a
    // cube adds.)
    const std::vector<std::uint32_t> targets = spread(result.after.unmeasured, 512);
    std::vector<Candidate> candidates;
    arena.execute([&] {
      const std::vector<std::uint32_t> starts = spread(targets, 64);
      candidates.resize(starts.size());
      par::parallelFor(par::Range<std::size_t>(0, starts.size(), 1), [&](const par::Range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k)
          candidates[k] =
              marchToClearance(exact, samples.exact[starts[k]], samples.points[starts[k]], box, 0.5f * samples.spacing);
      });
    });
    std::erase_if(candidates, [&](const Candidate& c) { return !(c.clearance > 2.0f * tolerance); });
    if (candidates.empty()) break;
    Choice best;
    arena.execute([&] { best = bestCenter(exact, samples, candidates, targets, tolerance); });
    if (best.count == 0) break;
    const float half = cubeHalfExtent(best.at.center, best.reached, bounds, tolerance);
    const int res = cubeResolution(std::min(best.far, std::sqrt(3.0f) * half), tolerance, desc.resolution);
    // Through the item text, so that the recipe the file records bakes exactly this cube.
    const std::string item = cubeItemText(best.at.center, half, res);
    std::vector<MapSpec> spec;
    std::string error;
    if (!parseMapSpec(item, bounds, res, DepthMapFormat::front_back16, spec, error) || spec.size() != 1) {
      result.status.error = "internal: cube item '" + item + "' does not parse: " + error;
      break;
    }
    DepthMapCollider one;
    result.status = bakeDepthMaps(mesh, spec, {desc.normal_resolution, desc.threads}, one);
    if (!result.status.ok()) break;
    std::vector<DepthMap> with = maps;
    with.push_back(one.maps().front());
    CoverageReport after =
        measureCoverage(DepthMapCollider(with, desc.normal_resolution), samples, tolerance, desc.threads);
    // Worth its bytes only when it measures at least 0.2 % of the
    // near points more (a cube at a convex edge, where the margin ring's guesses stay, helps a
    // few): otherwise stop here.
    const std::size_t left = result.after.unmeasured.size();
    if (after.unmeasured.size() + std::max<std::size_t>(1, samples.points.size() / 500) > left) break;
    if (after.uncovered() > result.after.uncovered()) break;
    maps = std::move(with);
    result.after = std::move(after);
    result.cubes.push_back(spec.front());
    result.maps.push_back(one.maps().front());
    result.items += (result.items.empty() ? "" : ",") + item;
  }
  return result;
}

}  // namespace fluid
