// Kernels (normalisation, gradient symmetry and consistency) and the neighbour grid (every
// particle's neighbour set against brute force, determinism across thread counts).
#include "fluid/sph/kernels.hpp"
#include "fluid/sph/neighbor_grid.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace {

using fluid::CubicSplineKernel;

TEST(SphKernel, IntegratesToOne) {
  for (float H : {0.1f, 1.0f, 2.5f}) {
    const CubicSplineKernel k = CubicSplineKernel::make(H);
    // Midpoint rule on a fine grid over the support cube.
    const int n = 120;
    const double h = 2.0 * H / n;
    double sum = 0.0;
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const double px = -H + (x + 0.5) * h, py = -H + (y + 0.5) * h, pz = -H + (z + 0.5) * h;
          sum += k.value(static_cast<float>(std::sqrt(px * px + py * py + pz * pz)));
        }
    EXPECT_NEAR(sum * h * h * h, 1.0, 2e-3) << "H = " << H;
  }
}

TEST(SphKernel, CompactSupportAndPositive) {
  const CubicSplineKernel k = CubicSplineKernel::make(0.2f);
  EXPECT_EQ(k.value(0.2f), 0.0f);
  EXPECT_EQ(k.value(0.21f), 0.0f);
  EXPECT_EQ(k.gradient(glm::vec3(0.3f, 0.0f, 0.0f)), glm::vec3(0.0f));
  for (int i = 0; i < 100; ++i) {
    EXPECT_GE(k.value(0.002f * i), 0.0f);
    EXPECT_LE(k.derivative(0.002f * i), 0.0f);
  }
  // Continuous at q = 1/2 (both branches give sigma/4).
  EXPECT_NEAR(k.value(0.1f - 1e-6f), k.value(0.1f + 1e-6f), 1e-3f * k.value(0.0f));
}

TEST(SphKernel, GradientIsOddAndMatchesFiniteDifferences) {
  const CubicSplineKernel k = CubicSplineKernel::make(1.0f);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.7f, 0.7f);
  for (int t = 0; t < 200; ++t) {
    const glm::vec3 x(u(rng), u(rng), u(rng));
    const glm::vec3 g = k.gradient(x), gm = k.gradient(-x);
    EXPECT_EQ(g, -gm);  // exact antisymmetry: pressure forces conserve momentum
    const float e = 1e-3f;
    for (int a = 0; a < 3; ++a) {
      glm::vec3 dx(0.0f);
      dx[a] = e;
      const float fd = (k.value(glm::length(x + dx)) - k.value(glm::length(x - dx))) / (2.0f * e);
      EXPECT_NEAR(g[a], fd, 2e-3f * k.sigma + 1e-3f * std::abs(fd));
    }
  }
  // Points toward the neighbour (W decreases outward): grad_i W(x_i - x_j) . (x_i - x_j) < 0.
  EXPECT_LT(glm::dot(k.gradient(glm::vec3(0.3f, 0.1f, 0.0f)), glm::vec3(0.3f, 0.1f, 0.0f)), 0.0f);
}

std::vector<glm::vec3> randomCloud(std::size_t n, unsigned seed, float extent) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, extent);
  std::vector<glm::vec3> p(n);
  for (auto& x : p) x = glm::vec3(u(rng), u(rng), u(rng));
  // Duplicates and a few far strays exercise the clamping of the grid.
  for (std::size_t i = 0; i < n / 50; ++i) p[i * 7 % n] = p[i];
  if (n > 10) {
    p[3] = glm::vec3(1e4f, -3e3f, 5.0f);
    p[5] = glm::vec3(-2e3f, 7.0f, 1e5f);
  }
  return p;
}

void expectMatchesBruteForce(const std::vector<glm::vec3>& p, float radius, glm::vec3 dmin, glm::vec3 dmax,
                             float cell_fraction = 1.0f) {
  fluid::NeighborGrid grid;
  fluid::NeighborLists lists;
  fluid::buildNeighborGrid(grid, p, radius * cell_fraction, dmin, dmax);
  // The grid's order must be a permutation sorted by cell key.
  std::vector<std::uint32_t> sorted = grid.order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  for (std::size_t e = 1; e < grid.order.size(); ++e)
    ASSERT_LE(grid.particle_key[grid.order[e - 1]], grid.particle_key[grid.order[e]]);
  fluid::findNeighbors(grid, p, radius, lists);
  ASSERT_EQ(lists.offsets.size(), p.size() + 1);
  const float r2 = radius * radius;
  std::size_t total = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::vector<std::uint32_t> expected;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const glm::vec3 d = p[i] - p[j];
      if (j != i && glm::dot(d, d) < r2) expected.push_back(static_cast<std::uint32_t>(j));
    }
    std::vector<std::uint32_t> got(lists.indices.begin() + lists.offsets[i],
                                   lists.indices.begin() + lists.offsets[i + 1]);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, expected) << "particle " << i;
    total += expected.size();
  }
  EXPECT_GT(total, p.size() / 2);  // the test cloud really has neighbours
}

TEST(SphNeighborGrid, MatchesBruteForce) {
  expectMatchesBruteForce(randomCloud(3000, 1, 1.0f), 0.08f, glm::vec3(-1e30f), glm::vec3(1e30f));
}

TEST(SphNeighborGrid, MatchesBruteForceWithSmallerCells) {
  // The SPH step uses cells a little wider than the support; the query must stay exact for any ratio.
  expectMatchesBruteForce(randomCloud(3000, 6, 1.0f), 0.08f, glm::vec3(-1e30f), glm::vec3(1e30f), 0.5f);
  expectMatchesBruteForce(randomCloud(2000, 7, 1.0f), 0.1f, glm::vec3(0.3f), glm::vec3(0.6f), 0.5f);
  expectMatchesBruteForce(randomCloud(2000, 8, 1.0f), 0.08f, glm::vec3(-1e30f), glm::vec3(1e30f), 0.3f);
}

TEST(SphNeighborGrid, MatchesBruteForceWithClampedDomain) {
  // Domain smaller than the cloud: outside particles are clamped into border cells.
  expectMatchesBruteForce(randomCloud(2000, 2, 1.0f), 0.1f, glm::vec3(0.3f), glm::vec3(0.6f));
}

TEST(SphNeighborGrid, MatchesBruteForceWhenCellsExceedAxisCap) {
  // 1024 cells per axis cap: a long thin cloud with a tiny radius forces clamping.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> p(2000);
  for (auto& x : p) x = glm::vec3(u(rng) * 200.0f, u(rng) * 0.05f, u(rng) * 0.05f);
  expectMatchesBruteForce(p, 0.15f, glm::vec3(-1e30f), glm::vec3(1e30f));
}

TEST(SphNeighborGrid, EmptyAndSingle) {
  fluid::NeighborGrid grid;
  fluid::NeighborLists lists;
  std::vector<glm::vec3> none;
  fluid::buildNeighborGrid(grid, none, 0.1f);
  fluid::findNeighbors(grid, none, 0.1f, lists);
  EXPECT_EQ(lists.offsets.size(), 1u);
  std::vector<glm::vec3> one{glm::vec3(1.0f)};
  fluid::buildNeighborGrid(grid, one, 0.1f);
  fluid::findNeighbors(grid, one, 0.1f, lists);
  EXPECT_EQ(lists.indices.size(), 0u);
}

TEST(SphNeighborGrid, SameListsForOneAndFourThreads) {
  const auto p = randomCloud(20000, 4, 1.0f);
  fluid::NeighborGrid g1, g4;
  fluid::NeighborLists l1, l4;
  tbb::task_arena(1).execute([&] {
    fluid::buildNeighborGrid(g1, p, 0.05f, glm::vec3(0.0f), glm::vec3(1.0f));
    fluid::findNeighbors(g1, p, 0.05f, l1);
  });
  tbb::task_arena(4).execute([&] {
    fluid::buildNeighborGrid(g4, p, 0.05f, glm::vec3(0.0f), glm::vec3(1.0f));
    fluid::findNeighbors(g4, p, 0.05f, l4);
  });
  EXPECT_EQ(g1.order, g4.order);
  EXPECT_EQ(l1.offsets, l4.offsets);
  EXPECT_EQ(l1.indices, l4.indices);
}

}  // namespace
