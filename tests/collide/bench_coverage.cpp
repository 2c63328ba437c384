// bench_collide_coverage: the near-surface coverage table of docs/collide.md (issue 32). Per test
// model (tests/collide/collide_meshes.hpp: torus, bowl, mug, pipe, dish, and the basin), three
// colliders over the points within reach of the surface:
//   axes   the six axis maps with the margin ring (bake-collider --maps axes),
//   auto   those plus the concave-region cubes chooseConcaveCubes adds (the bake-collider default),
//   exact  the axis maps, and the exact mesh distance (BVH) in every reach-sized cell where the axis
//          maps left a point unmeasured (the alternative: an exact fallback for those regions only).
// The cubes and the fallback cells are chosen on the seed-1 lattice, measured on an independent
// seed-2 lattice. Prints markdown. Run: ./build/dev/tests/collide/bench_collide_coverage
#include "collide_meshes.hpp"
#include "fluid/collide/collider_cache.hpp"
#include "fluid/collide/coverage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <unordered_set>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// The alternative to cubes: depth maps, except in flagged cells, where the exact BVH distance answers.
class ExactFallback final : public fluid::SignedDistanceShape {
 public:
  ExactFallback(const fluid::DepthMapCollider& maps, const fluid::MeshDistance& exact, glm::vec3 origin, float cell)
      : maps_(maps), exact_(exact), origin_(origin), cell_(cell) {}
  void flag(glm::vec3 p) {
    const glm::ivec3 c = cellOf(p);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) cells_.insert(key(c + glm::ivec3(dx, dy, dz)));
  }
  void query(std::span<const glm::vec3> points, std::span<fluid::ColliderSample> out) const override {
    for (std::size_t k = 0; k < points.size(); ++k)
      out[k] = cells_.count(key(cellOf(points[k]))) ? exact_.sample(points[k]) : maps_.sample(points[k]);
  }
  std::size_t cells() const { return cells_.size(); }
  // A bit per cell of the model's padded bounds would do; counted as such.
  std::size_t maskBytes(glm::vec3 size) const {
    const glm::vec3 n = glm::ceil(size / cell_) + 2.0f;
    return static_cast<std::size_t>(n.x * n.y * n.z / 8.0f) + 1;
  }
  bool flagged(glm::vec3 p) const { return cells_.count(key(cellOf(p))) != 0; }

 private:
  glm::ivec3 cellOf(glm::vec3 p) const { return glm::ivec3(glm::floor((p - origin_) / cell_)); }
  static std::uint64_t key(glm::ivec3 c) {
    return (static_cast<std::uint64_t>(c.x + 0x100000) << 42) | (static_cast<std::uint64_t>(c.y + 0x100000) << 21) |
           static_cast<std::uint64_t>(c.z + 0x100000);
  }
  const fluid::DepthMapCollider& maps_;
  const fluid::MeshDistance& exact_;
  glm::vec3 origin_;
  float cell_;
  std::unordered_set<std::uint64_t> cells_;
};

struct Model {
  const char* name;
  collide_test::Mesh mesh;
};

// Serial ns per query over the points (median of three).
double nsPerQuery(const fluid::SignedDistanceShape& shape, const std::vector<glm::vec3>& points) {
  std::vector<fluid::ColliderSample> out(points.size());
  double best[3];
  for (double& b : best) {
    const auto t = Clock::now();
    shape.query(points, out);
    b = msSince(t) * 1e6 / static_cast<double>(std::max<std::size_t>(points.size(), 1));
  }
  std::sort(best, best + 3);
  return best[1];
}

void row(const char* model, const char* kind, const std::string& maps, const fluid::CoverageReport& r,
         std::size_t bytes, double ns, double ms) {
  const double near = static_cast<double>(std::max<std::size_t>(r.near, 1));
  std::printf("| %s | %s | %s | %zu | %.3f | %.3f | %zu | %.3f | %zu | %zu | %.4f | %.3f | %zu | %.0f | %.0f |\n",
              model, kind, maps.c_str(), r.near, 100.0 * r.coveredShare(), 100.0 * r.measuredShare(), r.beyond_reach,
              100.0 * r.wrong_sign / near, r.off_distance, r.ring_guess, r.mean_abs_error, r.max_abs_error, bytes, ns,
              ms);
}

}  // namespace

int main(int argc, char** argv) {
  int res = 256, threads = 0;
  float reach = 0.16f;
  std::size_t points = 120000;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--res"))
      res = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--reach"))
      reach = static_cast<float>(std::atof(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--points"))
      points = static_cast<std::size_t>(std::atoll(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--threads"))
      threads = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: bench_collide_coverage [--res N] [--reach R] [--points N] [--threads N]\n");
      return 2;
    }
  }
  if (res < 16 || res > 4096 || !(reach > 0.0f) || points < 1000) {
    std::fprintf(stderr, "bench_collide_coverage: --res 16..4096, --reach > 0, --points >= 1000\n");
    return 2;
  }
  std::vector<Model> models;
  models.push_back({"torus", collide_test::makeTorus(0.6f, 0.2f, 96, 32)});
  models.push_back({"bowl", collide_test::makeBowl(96)});
  models.push_back({"mug", collide_test::makeMug(96)});
  models.push_back({"pipe", collide_test::makePipe(96)});
  models.push_back({"dish", collide_test::makeDish(96)});
  models.push_back({"basin", collide_test::makeBasin(96)});
  std::printf(
      "Reach %.3g, %d² maps (front-back16, margin = reach), about %zu lattice points per model; ns/query "
      "serial over the measured points, median of 3; ms = bake (auto: + choice; exact: BVH build).\n\n",
      reach, res, points);
  std::printf(
      "| model | collider | maps | near points | covered %% | measured %% | beyond reach | wrong sign %% | off "
      "distance | "
      "ring guess | mean \\|Δd\\| | max \\|Δd\\| | bytes | ns/query | ms |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Model& m : models) {
    const fluid::MeshView view = m.mesh.view();
    const fluid::Bounds bounds = fluid::meshBounds(view);
    fluid::BakeRecipe recipe;
    recipe.resolution = res;
    recipe.margin = reach;
    std::vector<fluid::MapSpec> specs;
    std::string error;
    if (!fluid::recipeMapSpecs(recipe, bounds, specs, error)) {
      std::fprintf(stderr, "%s: %s\n", m.name, error.c_str());
      return 1;
    }
    auto t = Clock::now();
    fluid::DepthMapCollider axes;
    if (const fluid::BakeStatus st = fluid::bakeDepthMaps(view, specs, {256, threads}, axes); !st.ok()) {
      std::fprintf(stderr, "%s: %s\n", m.name, st.error.c_str());
      return 1;
    }
    const double axes_ms = msSince(t);
    t = Clock::now();
    const fluid::MeshDistance exact(view);
    const double bvh_ms = msSince(t);
    fluid::CoverageDesc cd;
    cd.reach = reach;
    cd.max_points = points;
    cd.threads = threads;
    const float tolerance = fluid::coverageTolerance(specs);
    t = Clock::now();
    const fluid::NearSurfaceSamples choose = fluid::nearSurfaceSamples(exact, bounds, cd);
    fluid::ConcaveCubesDesc cc;
    cc.resolution = res;
    cc.threads = threads;
    const fluid::ConcaveCubesResult cubes = fluid::chooseConcaveCubes(view, exact, choose, specs, axes.maps(), cc);
    const double choose_ms = msSince(t);
    if (!cubes.status.ok()) {
      std::fprintf(stderr, "%s: %s\n", m.name, cubes.status.error.c_str());
      return 1;
    }
    std::vector<fluid::DepthMap> all = axes.maps();
    all.insert(all.end(), cubes.maps.begin(), cubes.maps.end());
    const fluid::DepthMapCollider with_cubes(all, 256);
    cd.seed = 2;
    const fluid::NearSurfaceSamples measure = fluid::nearSurfaceSamples(exact, bounds, cd);
    ExactFallback fallback(axes, exact, bounds.lo - glm::vec3(reach), reach);
    for (std::uint32_t i : cubes.before.unmeasured) fallback.flag(choose.points[i]);
    const fluid::CoverageReport r_axes = fluid::measureCoverage(axes, measure, tolerance, threads);
    const fluid::CoverageReport r_auto = fluid::measureCoverage(with_cubes, measure, tolerance, threads);
    const fluid::CoverageReport r_exact = fluid::measureCoverage(fallback, measure, tolerance, threads, &axes);
    std::vector<glm::vec3> in_fallback;
    for (const glm::vec3& p : measure.points)
      if (fallback.flagged(p)) in_fallback.push_back(p);
    // The cubes by their resolutions (the items themselves are long; bake-collider prints them).
    std::string auto_maps =
        "axes + " + std::to_string(cubes.cubes.size()) + " cube" + (cubes.cubes.size() == 1 ? "" : "s");
    for (std::size_t k = 0; k < cubes.cubes.size(); ++k)
      auto_maps += (k == 0 ? " (" : ", ") + std::to_string(cubes.cubes[k].resolution) + "²" +
                   (k + 1 == cubes.cubes.size() ? ")" : "");
    const glm::vec3 padded = bounds.hi - bounds.lo + glm::vec3(2.0f * reach);
    row(m.name, "axes", "axes", r_axes, axes.bytes(), nsPerQuery(axes, measure.points), axes_ms);
    row(m.name, "auto (cubes)", auto_maps, r_auto, with_cubes.bytes(), nsPerQuery(with_cubes, measure.points),
        axes_ms + choose_ms);
    char kind[96];
    std::snprintf(kind, sizeof kind, "axes + exact in %zu cells (%.1f %% of the points)", fallback.cells(),
                  100.0 * in_fallback.size() / std::max<std::size_t>(measure.points.size(), 1));
    row(m.name, kind, "axes", r_exact, axes.bytes() + exact.bytes() + fallback.maskBytes(padded),
        nsPerQuery(fallback, measure.points), axes_ms + bvh_ms);
    std::printf("| %s | (fallback cells only: maps / exact ns/query) | | %zu | | | | | | | | | | %.0f / %.0f | |\n",
                m.name, in_fallback.size(), nsPerQuery(with_cubes, in_fallback), nsPerQuery(fallback, in_fallback));
    std::fflush(stdout);
  }
  return 0;
}
