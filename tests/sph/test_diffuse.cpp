// Foam and bubbles (fluid/sph/diffuse.hpp, Ihmsen et al. 2012): the classification by neighbour
// count, the trapped-air and wave-crest potentials on hand-made particle sets, the births of eq. 2
// and the coarse fluid grid the GPU sprites read.
#include "fluid/sph/diffuse.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

namespace {

constexpr float kSpacing = 0.08f;  // the fountain's d = 2 r
constexpr float kH = 0.16f;        // its support H = 2 d

fluid::DiffuseParams params() {
  fluid::DiffuseParams p;
  p.radius = kH;
  p.k_min = 0.0f;  // every moving particle is active (I_k > 0)
  return p;
}

TEST(DiffuseClass, ByNeighbourCount) {
  using fluid::DiffuseClass;
  EXPECT_EQ(fluid::classifyDiffuse(0.0f), DiffuseClass::spray);
  EXPECT_EQ(fluid::classifyDiffuse(5.0f), DiffuseClass::spray);
  EXPECT_EQ(fluid::classifyDiffuse(5.99f), DiffuseClass::spray);
  EXPECT_EQ(fluid::classifyDiffuse(6.0f), DiffuseClass::foam);
  EXPECT_EQ(fluid::classifyDiffuse(13.0f), DiffuseClass::foam);
  EXPECT_EQ(fluid::classifyDiffuse(20.0f), DiffuseClass::foam);
  EXPECT_EQ(fluid::classifyDiffuse(20.5f), DiffuseClass::bubble);
  EXPECT_EQ(fluid::classifyDiffuse(40.0f), DiffuseClass::bubble);
  EXPECT_EQ(fluid::classifyDiffuse(std::numeric_limits<float>::quiet_NaN()), DiffuseClass::spray);
  EXPECT_EQ(fluid::classifyDiffuse(3.0f, 2, 4), DiffuseClass::foam);
  EXPECT_EQ(fluid::classifyDiffuse(5.0f, 2, 4), DiffuseClass::bubble);
}

TEST(DiffusePotential, ClampOfEquationOne) {
  EXPECT_FLOAT_EQ(fluid::clampPotential(1.0f, 2.0f, 4.0f), 0.0f);
  EXPECT_FLOAT_EQ(fluid::clampPotential(3.0f, 2.0f, 4.0f), 0.5f);
  EXPECT_FLOAT_EQ(fluid::clampPotential(9.0f, 2.0f, 4.0f), 1.0f);
  EXPECT_FLOAT_EQ(fluid::clampPotential(std::numeric_limits<float>::infinity(), 2.0f, 4.0f), 0.0f);
  EXPECT_FLOAT_EQ(fluid::clampPotential(5.0f, 4.0f, 4.0f), 1.0f);
}

// Eq. 4: two particles approaching each other trap air; separating, they do not.
TEST(DiffusePotential, TrappedAirOfApproachingPair) {
  const glm::vec3 a(0.0f), b(0.1f, 0.0f, 0.0f);
  // Head on: |v_ij| = 2, v^.x^ = -1, W = 1 - 0.1 / 0.16.
  const float expected = 2.0f * 2.0f * (1.0f - 0.1f / kH);
  EXPECT_NEAR(fluid::trappedAirTerm(a, {1, 0, 0}, b, {-1, 0, 0}, kH), expected, 1e-5f);
  EXPECT_FLOAT_EQ(fluid::trappedAirTerm(a, {-1, 0, 0}, b, {1, 0, 0}, kH), 0.0f);                // separating
  EXPECT_FLOAT_EQ(fluid::trappedAirTerm(a, {1, 0, 0}, b, {1, 0, 0}, kH), 0.0f);                 // moving together
  EXPECT_FLOAT_EQ(fluid::trappedAirTerm(a, {1, 0, 0}, glm::vec3(1.0f), {-1, 0, 0}, kH), 0.0f);  // beyond h
  // Sideways shear: v^.x^ = 0, half the head-on value.
  EXPECT_NEAR(fluid::trappedAirTerm(a, {0, 1, 0}, b, {0, -1, 0}, kH), 0.5f * expected, 1e-5f);

  const std::vector<glm::vec3> x{a, b};
  fluid::DiffuseScratch scratch;
  fluid::DiffusePotentials out;
  std::vector<glm::vec3> v{{1, 0, 0}, {-1, 0, 0}};
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  EXPECT_NEAR(out.trapped_air[0], expected, 1e-5f);
  EXPECT_NEAR(out.trapped_air[1], expected, 1e-5f);
  EXPECT_EQ(out.neighbours[0], 1u);
  v = {{-1, 0, 0}, {1, 0, 0}};
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  EXPECT_FLOAT_EQ(out.trapped_air[0], 0.0f);
  EXPECT_FLOAT_EQ(out.trapped_air[1], 0.0f);
}

std::vector<glm::vec3> lattice(int nx, int ny, int nz) {
  std::vector<glm::vec3> x;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int i = 0; i < nx; ++i) x.emplace_back(i * kSpacing, y * kSpacing, z * kSpacing);
  return x;
}

// Eqs. 5-6: a flat surface has no curvature, even rising along its normal.
TEST(DiffusePotential, FlatSurfaceHasNoWaveCrest) {
  const int n = 14, layers = 5;
  const std::vector<glm::vec3> x = lattice(n, layers, n);
  const std::vector<glm::vec3> v(x.size(), glm::vec3(0.0f, 2.0f, 0.0f));
  fluid::DiffuseScratch scratch;
  fluid::DiffusePotentials out;
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  int top = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const glm::vec3 p = x[i];
    // Away from the sides (their edges are convex corners).
    const float margin = 2.0f * kH;
    if (p.x < margin || p.z < margin || p.x > (n - 1) * kSpacing - margin || p.z > (n - 1) * kSpacing - margin)
      continue;
    EXPECT_LT(out.wave_crest[i], 1e-4f) << "particle " << i << " at y " << p.y;
    EXPECT_FLOAT_EQ(out.trapped_air[i], 0.0f);  // a rigid motion traps no air
    if (p.y > (layers - 1) * kSpacing - 1e-4f) {
      ++top;
      EXPECT_GT(out.normal[i].y, 0.999f) << "the top's normal points up";
    }
  }
  EXPECT_GT(top, 20);
}

// A convex crest moving outward: a ball of water expanding has curvature at its surface.
TEST(DiffusePotential, ConvexCrestMovingOutward) {
  std::vector<glm::vec3> x;
  const float radius = 0.3f;
  for (const glm::vec3& p : lattice(9, 9, 9)) {
    const glm::vec3 c = p - glm::vec3(4.0f * kSpacing);
    if (glm::length(c) <= radius) x.push_back(c);
  }
  std::vector<glm::vec3> v;
  for (const glm::vec3& p : x) v.push_back(glm::length(p) > 0.0f ? 2.0f * glm::normalize(p) : glm::vec3(0.0f));
  fluid::DiffuseScratch scratch;
  fluid::DiffusePotentials out;
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  std::size_t top = 0;
  for (std::size_t i = 0; i < x.size(); ++i)  // the top of the ball, on its axis
    if (x[i].y - std::hypot(x[i].x, x[i].z) > x[top].y - std::hypot(x[top].x, x[top].z)) top = i;
  EXPECT_GT(out.normal[top].y, 0.9f);
  // The cap's centre is nearly flat on the lattice (a few thousandths); its rim bends over.
  EXPECT_GT(out.wave_crest[top], 0.0f);
  float most = 0.0f;
  for (float k : out.wave_crest) most = std::max(most, k);
  EXPECT_GT(most, 0.1f);
  std::printf("ball of %zu: I_wc %.4f at the top, %.3f at most\n", x.size(), out.wave_crest[top], most);
  // The same ball falling back in (moving against its normals) is no crest (δ^vn = 0).
  for (glm::vec3& u : v) u = -u;
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  for (float k : out.wave_crest) EXPECT_EQ(k, 0.0f);
  // Converging, the water traps air everywhere it meets.
  EXPECT_GT(out.trapped_air[top], 1.0f);
}

// Eq. 2 multiplies by I_k: particles below tau_k,min get no potentials (and are not searched).
TEST(DiffusePotential, SlowParticlesAreSkipped) {
  const std::vector<glm::vec3> x{glm::vec3(0.0f), glm::vec3(0.1f, 0.0f, 0.0f), glm::vec3(1.0f)};
  const std::vector<glm::vec3> v{{1, 0, 0}, {-1, 0, 0}, {0, 0, 0}};
  fluid::DiffuseParams p = params();
  p.k_min = 0.6f;  // E_k = 0.5: below
  fluid::DiffuseScratch scratch;
  fluid::DiffusePotentials out;
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, p, scratch, out));
  EXPECT_EQ(out.trapped_air[0], 0.0f);
  EXPECT_EQ(out.neighbours[0], 0u);
  EXPECT_FLOAT_EQ(out.kinetic[0], 0.5f);
  p.k_min = 0.4f;
  ASSERT_TRUE(fluid::computeDiffusePotentials(x, v, p, scratch, out));
  EXPECT_GT(out.trapped_air[0], 0.0f);
  EXPECT_EQ(out.neighbours[0], 1u);
  EXPECT_EQ(out.neighbours[2], 0u);  // the still particle, alone
}

TEST(DiffusePotential, NonFiniteInputIsRefused) {
  std::vector<glm::vec3> x{glm::vec3(0.0f), glm::vec3(std::numeric_limits<float>::quiet_NaN())};
  std::vector<glm::vec3> v(2, glm::vec3(0.0f));
  fluid::DiffuseScratch scratch;
  fluid::DiffusePotentials out;
  EXPECT_FALSE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  ASSERT_EQ(out.trapped_air.size(), 2u);
  EXPECT_EQ(out.trapped_air[0], 0.0f);
  x[1] = glm::vec3(1.0f);
  v[0] = glm::vec3(INFINITY, 0.0f, 0.0f);
  EXPECT_FALSE(fluid::computeDiffusePotentials(x, v, params(), scratch, out));
  EXPECT_FALSE(fluid::computeDiffusePotentials(x, std::vector<glm::vec3>(1), params(), scratch, out));
}

// Eq. 2: n_d = I_k (k_ta I_ta + k_wc I_wc) dt, rounded per particle without bias, typed by the
// parent's neighbour count, seeded.
TEST(DiffuseBirths, RateClassAndSeed) {
  const std::size_t n = 2000;
  std::vector<glm::vec3> x(n), v(n, glm::vec3(0.0f, -4.0f, 0.0f));
  for (std::size_t i = 0; i < n; ++i) x[i] = glm::vec3(static_cast<float>(i), 0.0f, 0.0f);
  fluid::DiffusePotentials pot;
  pot.kinetic.assign(n, 8.0f);      // |v|^2 / 2
  pot.trapped_air.assign(n, 6.0f);  // Φ = 0.5 on [2, 10]
  pot.wave_crest.assign(n, 0.0f);
  pot.neighbours.assign(n, 0u);
  for (std::size_t i = 0; i < n; ++i) pot.neighbours[i] = i % 3 == 0 ? 3u : (i % 3 == 1 ? 12u : 30u);
  pot.normal.assign(n, glm::vec3(0.0f));
  fluid::DiffuseParams p = params();
  p.k_min = 0.0f;
  p.k_max = 16.0f;  // Φ = 0.5
  p.k_ta = 60.0f;
  const float dt = 1.0f / 60.0f;
  std::vector<fluid::DiffuseBirth> births;
  const std::size_t count = fluid::generateDiffuse(x, v, pot, p, dt, 7, 1u << 20, births);
  const double expected = n * 0.5 * 60.0 * 0.5 * dt;  // 500
  EXPECT_NEAR(static_cast<double>(count), expected, 4.0 * std::sqrt(expected));
  int classes[3] = {0, 0, 0};
  for (const fluid::DiffuseBirth& b : births) {
    ++classes[static_cast<int>(b.type)];
    const auto parent = static_cast<std::size_t>(std::lround(b.position.x));
    ASSERT_LT(parent, n);
    // §4.1: within the cylinder of radius h / 4 along v dt, moving with the parent.
    const glm::vec3 d = b.position - x[parent];
    EXPECT_LE(std::hypot(d.x, d.z), 0.25f * kH + 1e-5f);
    EXPECT_LE(d.y, 1e-6f);
    EXPECT_GE(d.y, -4.0f * dt - 1e-6f);
    EXPECT_NEAR(b.velocity.y, -4.0f, 1e-4f);
    const fluid::DiffuseClass want = fluid::classifyDiffuse(static_cast<float>(pot.neighbours[parent]));
    EXPECT_EQ(b.type, want);
  }
  for (int c : classes) EXPECT_GT(c, 100);
  std::vector<fluid::DiffuseBirth> again;
  fluid::generateDiffuse(x, v, pot, p, dt, 7, 1u << 20, again);
  ASSERT_EQ(again.size(), births.size());
  for (std::size_t k = 0; k < births.size(); ++k) EXPECT_EQ(again[k].position, births[k].position);
  // The cap, and nothing without kinetic energy.
  EXPECT_EQ(fluid::generateDiffuse(x, v, pot, p, dt, 7, 10, again), 10u);
  pot.kinetic.assign(n, 0.0f);
  again.clear();
  EXPECT_EQ(fluid::generateDiffuse(x, v, pot, p, dt, 7, 1u << 20, again), 0u);
}

// The coarse grid: every particle counted once with its velocity; the neighbour estimate of an
// interior cell is the lattice density times the neighbourhood's volume.
TEST(FluidCellGrid, CountsVelocitiesAndNeighbourScale) {
  std::vector<glm::vec3> x = lattice(16, 16, 16);
  // A stray particle half a spacing below the corner keeps the lattice off the cell faces (one
  // rounding either way would put a plane of particles into the next cell).
  x.push_back(glm::vec3(-0.5f * kSpacing));
  std::vector<glm::vec3> v(x.size(), glm::vec3(1.0f, 0.0f, -0.5f));
  fluid::FluidCellGrid grid;
  ASSERT_TRUE(fluid::buildFluidCellGrid(x, v, kH, kH, 64, grid));
  double count = 0.0;
  glm::dvec3 sum(0.0);
  for (const glm::vec4& c : grid.cells) {
    count += c.w;
    sum += glm::dvec3(c);
  }
  EXPECT_EQ(count, static_cast<double>(x.size()));
  EXPECT_NEAR(sum.x, static_cast<double>(x.size()), 1e-3);
  EXPECT_NEAR(sum.z, -0.5 * static_cast<double>(x.size()), 1e-3);
  // 8 particles per interior cell (cell = 2 d) times (4/3 π h^3) / cell^3 = 33.5, the paper's
  // neighbour count of an interior particle at h = 2 d with jitter (the exact lattice has 26 at
  // distances below h and 6 exactly at h).
  const glm::ivec3 mid = grid.size / 2;
  const glm::vec4 c = grid.cells[(static_cast<std::size_t>(mid.z) * grid.size.y + mid.y) * grid.size.x + mid.x];
  EXPECT_EQ(c.w, 8.0f);
  EXPECT_NEAR(c.w * grid.neighbour_scale, 8.0f * 4.0f / 3.0f * std::numbers::pi_v<float>, 1e-3f);
  // The cap on cells per axis grows the cells.
  ASSERT_TRUE(fluid::buildFluidCellGrid(x, v, 0.001f, kH, 32, grid));
  EXPECT_LE(grid.size.x, 32);
  EXPECT_GT(grid.cell, 0.001f);
  // Nothing finite: no grid.
  std::vector<glm::vec3> bad(3, glm::vec3(NAN));
  EXPECT_FALSE(fluid::buildFluidCellGrid(bad, bad, kH, kH, 64, grid));
  EXPECT_TRUE(grid.cells.empty());
}

}  // namespace
