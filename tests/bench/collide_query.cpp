// Issue 5 performance bar: batch queries of N (default 1M) points against a 6-map depth-map
// collider (three front-back16 textures along the axes, Kolb et al. 2004 §4.3) on T threads,
// against exact signed mesh distance on the same points (BVH on all points; the plain loop over
// every triangle on a subset), with the misclassification rate next to it.
// Usage: bench_collide_query [--points N] [--threads T] [--res R] [--reps K] [--brute N]
#include "bench_timing.hpp"
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace {

using benchtiming::median;

using Clock = std::chrono::steady_clock;

class BruteForce final : public fluid::SignedDistanceShape {
 public:
  explicit BruteForce(const fluid::MeshDistance& exact) : exact_(exact) {}
  void query(std::span<const glm::vec3> p, std::span<fluid::ColliderSample> out) const override {
    for (std::size_t k = 0; k < p.size(); ++k) out[k] = exact_.sampleBruteForce(p[k]);
  }

 private:
  const fluid::MeshDistance& exact_;
};

double timeNs(const fluid::SignedDistanceShape& shape, const std::vector<glm::vec3>& points,
              std::vector<fluid::ColliderSample>& out, int threads, int reps) {
  std::vector<double> ns;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    fluid::queryParallel(shape, points, out, {threads, 4096});
    ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / double(points.size()));
  }
  return median(ns);
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t count = 1000000, brute = 2000;
  int threads = 2, res = 256, reps = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--points")
      count = std::strtoull(argv[i + 1], nullptr, 10);
    else if (a == "--threads")
      threads = std::atoi(argv[i + 1]);
    else if (a == "--res")
      res = std::atoi(argv[i + 1]);
    else if (a == "--reps")
      reps = std::atoi(argv[i + 1]);
    else if (a == "--brute")
      brute = std::strtoull(argv[i + 1], nullptr, 10);
    else {
      std::fprintf(stderr, "usage: %s [--points N] [--threads T] [--res R] [--reps K] [--brute N]\n", argv[0]);
      return 2;
    }
  }
  if (argc % 2 == 0 || count == 0 || threads < 1 || res < 4 || reps < 1 || brute == 0) {
    std::fprintf(stderr, "usage: %s [--points N] [--threads T] [--res R] [--reps K] [--brute N]\n", argv[0]);
    return 2;
  }
  const struct {
    const char* name;
    collide_test::Mesh mesh;
  } shapes[] = {{"sphere", collide_test::makeSphere(1.0f, 48, 96)},
                {"torus", collide_test::makeTorus(1.0f, 0.35f, 96, 32)},
                {"basin", collide_test::makeBasin(96)}};
  std::printf(
      "%zu points (seeded, uniform in the bounds padded by 10%%), %d threads, %d² maps (three front-back16 "
      "textures), %d alternating runs: depth maps on all points, exact BVH on the first 100000; medians; "
      "speedup = median (and min) of the per-run BVH/depth ratios; plain loop once on the first %zu points; "
      "misclass against the exact BVH answer on all points\n\n",
      count, threads, res, reps, brute);
  std::printf(
      "| shape | triangles | depth maps | depth-map ns/query | exact BVH ns/query | exact plain loop ns/query | "
      "speedup vs BVH | speedup vs plain loop | misclass %% |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& shape : shapes) {
    const fluid::Bounds b = fluid::meshBounds(shape.mesh.view());
    const glm::vec3 ext = b.hi - b.lo;
    const float pad = 0.1f * std::max({ext.x, ext.y, ext.z});
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<glm::vec3> points(count);
    for (glm::vec3& p : points)
      p = b.lo - glm::vec3(pad) + (ext + glm::vec3(2 * pad)) * glm::vec3(u(rng), u(rng), u(rng));
    fluid::DepthMapCollider collider;
    const fluid::BakeStatus st = fluid::bakeDepthMaps(
        shape.mesh.view(), fluid::defaultMapSpecs(b, res, fluid::DepthMapFormat::front_back16), {}, collider);
    if (!st.ok()) {
      std::fprintf(stderr, "bake: %s\n", st.error.c_str());
      return 1;
    }
    const fluid::MeshDistance exact(shape.mesh.view());
    const BruteForce plain(exact);
    std::vector<fluid::ColliderSample> depth(count), reference(count);
    // The exact reference on every point (for the misclassification rate), then timing runs
    // that alternate depth maps (all points) and BVH (the first `timed_exact` points) so both
    // see the same machine load; the speedup is the median of the per-run ratios.
    timeNs(exact, points, reference, threads, 1);
    const std::size_t timed_exact = std::min<std::size_t>(count, 100000);
    std::vector<glm::vec3> exact_points(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(timed_exact));
    std::vector<fluid::ColliderSample> exact_out(timed_exact);
    std::vector<double> depth_runs, bvh_runs, ratios;
    for (int r = 0; r < reps; ++r) {
      depth_runs.push_back(timeNs(collider, points, depth, threads, 1));
      bvh_runs.push_back(timeNs(exact, exact_points, exact_out, threads, 1));
      ratios.push_back(bvh_runs.back() / depth_runs.back());
    }
    const double depth_ns = median(depth_runs), bvh_ns = median(bvh_runs);
    std::vector<glm::vec3> subset(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(std::min(brute, count)));
    std::vector<fluid::ColliderSample> subset_out(subset.size());
    const double plain_ns = timeNs(plain, subset, subset_out, threads, 1);
    std::size_t wrong = 0;
    for (std::size_t k = 0; k < count; ++k) {
      wrong += (reference[k].distance < 0.0f) != (depth[k].valid && depth[k].distance < 0.0f);
    }
    std::printf("| %s | %zu | %d | %.1f | %.0f | %.0f | %.0fx (min %.0fx) | %.0fx | %.3f |\n", shape.name,
                shape.mesh.indices.size() / 3, collider.depthMapCount(), depth_ns, bvh_ns, plain_ns, median(ratios),
                *std::min_element(ratios.begin(), ratios.end()), plain_ns / depth_ns,
                100.0 * double(wrong) / double(count));
    std::fflush(stdout);
  }
  return 0;
}
