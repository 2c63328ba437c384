// Anisotropic kernels (fluid/sph/anisotropy.hpp, Yu & Turk 2013): the Jacobi eigen-solver, G of
// hand-built neighbourhoods (a line, a plane, a ball, too few neighbours), the centre smoothing,
// degenerate sets (no NaN, no inf) and bit-equal results on 1 and 2 threads.
#include "fluid/sph/anisotropy.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace {

using fluid::Anisotropy;
using fluid::AnisotropyParams;
using fluid::AnisotropyScratch;

void expectMatNear(const glm::mat3& a, const glm::mat3& b, float tol, const char* what) {
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(a[c][r], b[c][r], tol) << what << " [" << c << "][" << r << "]";
}

// Runs the pass on `points` and returns particle 0's results.
struct One {
  glm::mat3 g;
  glm::vec3 centre;
  float max_axis;
  std::uint32_t neighbours;
};
One particleZero(const std::vector<glm::vec3>& points, const AnisotropyParams& p) {
  Anisotropy out;
  AnisotropyScratch scratch;
  fluid::computeAnisotropy(points, p, scratch, out);
  return {out.g[0], out.centre[0], out.max_axis[0], out.neighbours[0]};
}

TEST(AnisotropyEigen, ReconstructsRandomSymmetricMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int t = 0; t < 200; ++t) {
    glm::mat3 a;
    for (int c = 0; c < 3; ++c)
      for (int r = c; r < 3; ++r) a[c][r] = a[r][c] = u(rng);
    glm::vec3 s;
    glm::mat3 v;
    fluid::symmetricEigen3(a, s, v);
    EXPECT_GE(s[0], s[1]);
    EXPECT_GE(s[1], s[2]);
    glm::mat3 back(0.0f);
    for (int k = 0; k < 3; ++k) back += s[k] * glm::outerProduct(v[k], v[k]);
    expectMatNear(back, a, 2e-6f, "R S R^T");
    expectMatNear(glm::transpose(v) * v, glm::mat3(1.0f), 2e-6f, "R^T R");
    EXPECT_GT(glm::determinant(v), 0.0f);
  }
  // Non-finite input: zeros and the identity, nothing propagates.
  glm::mat3 bad(1.0f);
  bad[0][1] = bad[1][0] = std::nanf("");
  glm::vec3 s;
  glm::mat3 v;
  fluid::symmetricEigen3(bad, s, v);
  EXPECT_EQ(s, glm::vec3(0.0f));
  EXPECT_EQ(v, glm::mat3(1.0f));
}

// Neighbours on a line through the particle (direction not along an axis): covariance of rank 1,
// the two short axes clamped to σ1 / k_r, so g stretches along the line by k_r^(2/3) and shrinks
// across it to k_r^(-1/3) (axis ratio exactly k_r, volume the sphere's).
TEST(Anisotropy, LineOfNeighboursStretchesAlongTheLineClampedByKr) {
  const glm::vec3 dir = glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f));
  std::vector<glm::vec3> pts{glm::vec3(0.0f)};
  for (float s : {-0.6f, -0.3f, 0.3f, 0.6f}) pts.push_back(s * dir);
  AnisotropyParams p;
  p.radius = 1.0f;
  p.k_n = 3;
  for (float k_r : {2.0f, 4.0f, 8.0f}) {
    p.k_r = k_r;
    const One o = particleZero(pts, p);
    EXPECT_EQ(o.neighbours, 4u);
    const float along = std::pow(k_r, 2.0f / 3.0f), across = std::pow(k_r, -1.0f / 3.0f);
    const glm::mat3 uu = glm::outerProduct(dir, dir);
    const glm::mat3 expected = uu / along + (glm::mat3(1.0f) - uu) / across;
    expectMatNear(o.g, expected, 2e-5f, "line g");
    EXPECT_NEAR(o.max_axis, along, 1e-5f);
    // The semi-axis along the line over the one across: k_r.
    const float a_along = 1.0f / glm::length(o.g * dir);
    const glm::vec3 ortho = glm::normalize(glm::cross(dir, glm::vec3(0, 0, 1)));
    const float a_across = 1.0f / glm::length(o.g * ortho);
    EXPECT_NEAR(a_along / a_across, k_r, 1e-4f * k_r);
    EXPECT_NEAR(glm::determinant(o.g), 1.0f, 1e-5f);  // k_s = 1: the sphere's volume
    EXPECT_NEAR(glm::length(o.centre), 0.0f, 1e-6f);  // symmetric: the mean is the particle
  }
}

// Neighbours on two rings in a plane: isotropic in the plane, nothing across it: a flat disc whose
// normal axis is k_r times shorter than the in-plane ones.
TEST(Anisotropy, PlaneOfNeighboursGivesAFlatDisc) {
  const glm::vec3 n = glm::normalize(glm::vec3(0.2f, 1.0f, -0.4f));
  const glm::vec3 e1 = glm::normalize(glm::cross(n, glm::vec3(1, 0, 0))), e2 = glm::cross(n, e1);
  std::vector<glm::vec3> pts{glm::vec3(0.0f)};
  for (float radius : {0.3f, 0.6f})
    for (int k = 0; k < 8; ++k) {
      const float a = 6.2831853f * static_cast<float>(k) / 8.0f;
      pts.push_back(radius * (std::cos(a) * e1 + std::sin(a) * e2));
    }
  AnisotropyParams p;
  p.radius = 1.0f;
  p.k_n = 10;
  p.k_r = 4.0f;
  const One o = particleZero(pts, p);
  EXPECT_EQ(o.neighbours, 16u);
  const float in_plane = std::pow(4.0f, 1.0f / 3.0f), normal = std::pow(4.0f, -2.0f / 3.0f);
  const glm::mat3 nn = glm::outerProduct(n, n);
  expectMatNear(o.g, (glm::mat3(1.0f) - nn) / in_plane + nn / normal, 2e-5f, "disc g");
  EXPECT_NEAR(1.0f / glm::length(o.g * n), normal, 1e-5f);
  EXPECT_NEAR(1.0f / glm::length(o.g * e1), in_plane, 1e-5f);
}

// Neighbours on the cube's 6 faces and 8 corners: isotropic second moments, g = I / k_s.
TEST(Anisotropy, BallOfNeighboursStaysIsotropic) {
  std::vector<glm::vec3> pts{glm::vec3(0.0f)};
  for (int a = 0; a < 3; ++a)
    for (float s : {-0.4f, 0.4f}) {
      glm::vec3 q(0.0f);
      q[a] = s;
      pts.push_back(q);
    }
  for (int k = 0; k < 8; ++k) pts.push_back(0.3f * glm::vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1));
  AnisotropyParams p;
  p.radius = 1.0f;
  p.k_n = 10;
  for (float k_s : {1.0f, 1.5f}) {
    p.k_s = k_s;
    const One o = particleZero(pts, p);
    EXPECT_EQ(o.neighbours, 14u);
    expectMatNear(o.g, glm::mat3(1.0f / k_s), 2e-5f, "ball g");
    EXPECT_NEAR(o.max_axis, k_s, 1e-5f);
  }
}

// k_n or fewer neighbours: exactly the sphere (the isotropic renderers' particle).
TEST(Anisotropy, TooFewNeighboursStaySpheres) {
  const glm::vec3 dir(1.0f, 0.0f, 0.0f);
  std::vector<glm::vec3> pts{glm::vec3(0.0f), 0.3f * dir, -0.3f * dir, 0.6f * dir, -0.6f * dir};
  AnisotropyParams p;
  p.radius = 1.0f;
  p.k_n = 4;  // 4 neighbours: not more than k_n
  const One o = particleZero(pts, p);
  EXPECT_EQ(o.neighbours, 4u);
  EXPECT_EQ(o.g, glm::mat3(1.0f));
  EXPECT_EQ(o.max_axis, 1.0f);
  // Neighbours beyond r do not count.
  p.k_n = 1;
  p.radius = 0.5f;
  EXPECT_EQ(particleZero(pts, p).neighbours, 2u);
}

// Eq. 6: x̄ = (1 - λ) x + λ x^w with the weights 1 - (d / r)^3, checked by hand: one neighbour at
// distance 0.5 of r = 1 weighs 0.875, so x^w = 0.875 * 0.5 / 1.875 along it.
TEST(Anisotropy, CentreSmoothingMovesTowardsTheWeightedMean) {
  const glm::vec3 x0(1.0f, 2.0f, 3.0f), d(0.5f, 0.0f, 0.0f);
  const std::vector<glm::vec3> pts{x0, x0 + d};
  AnisotropyParams p;
  p.radius = 1.0f;
  const float mean = 0.875f * 0.5f / 1.875f;
  for (float lambda : {0.0f, 0.5f, 0.9f, 1.0f}) {
    p.lambda = lambda;
    const One o = particleZero(pts, p);
    EXPECT_NEAR(o.centre.x, x0.x + lambda * mean, 1e-6f) << lambda;
    EXPECT_EQ(o.centre.y, x0.y);
    EXPECT_EQ(o.centre.z, x0.z);
    if (lambda == 0.0f) {
      EXPECT_EQ(o.centre, x0);
    }
  }
}

bool finite(const glm::mat3& m) {
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// Coincident particles, pairs, exact lines and planes with k_r = 1, far from the origin, tiny r:
// every output finite, g positive definite.
TEST(Anisotropy, DegenerateSetsStayFinite) {
  std::vector<std::vector<glm::vec3>> sets;
  sets.push_back(std::vector<glm::vec3>(40, glm::vec3(0.5f)));      // all coincident
  sets.push_back({glm::vec3(0.0f), glm::vec3(1e-7f, 0.0f, 0.0f)});  // a close pair
  sets.push_back({glm::vec3(0.0f)});                                // alone
  std::vector<glm::vec3> line, plane, far, mixed;
  for (int k = 0; k < 40; ++k) line.push_back(glm::vec3(0.01f * k, 0.0f, 0.0f));
  for (int k = 0; k < 49; ++k) plane.push_back(glm::vec3(0.01f * (k % 7), 0.0f, 0.01f * (k / 7)));
  for (int k = 0; k < 40; ++k) far.push_back(glm::vec3(1e5f + 0.01f * (k % 4), 0.01f * (k / 4 % 4), -1e5f));
  for (int k = 0; k < 30; ++k) mixed.push_back(k < 20 ? glm::vec3(0.2f) : glm::vec3(0.2f + 0.01f * k, 0.2f, 0.2f));
  sets.push_back(line);
  sets.push_back(plane);
  sets.push_back(far);
  sets.push_back(mixed);
  for (float k_r : {1.0f, 4.0f, 1e6f})
    for (const auto& s : sets) {
      AnisotropyParams p;
      p.radius = 0.05f;
      p.k_n = 2;
      p.k_r = k_r;
      Anisotropy out;
      AnisotropyScratch scratch;
      fluid::computeAnisotropy(s, p, scratch, out);
      for (std::size_t i = 0; i < s.size(); ++i) {
        ASSERT_TRUE(finite(out.g[i])) << "set of " << s.size() << " particle " << i;
        ASSERT_TRUE(std::isfinite(out.centre[i].x) && std::isfinite(out.centre[i].y) && std::isfinite(out.centre[i].z));
        ASSERT_TRUE(std::isfinite(out.max_axis[i]));
        EXPECT_GT(glm::determinant(out.g[i]), 0.0f);
      }
    }
  // A non-finite position: refused, every particle a sphere at its own position, nothing searched.
  {
    std::vector<glm::vec3> bad_set = line;
    bad_set[7].y = std::nanf("");
    AnisotropyParams p;
    p.radius = 0.05f;
    Anisotropy out;
    AnisotropyScratch scratch;
    EXPECT_FALSE(fluid::computeAnisotropy(bad_set, p, scratch, out));
    ASSERT_EQ(out.g.size(), bad_set.size());
    EXPECT_EQ(out.g[0], glm::mat3(1.0f));
    EXPECT_EQ(out.centre[3], bad_set[3]);
    EXPECT_EQ(out.stretched, 0u);
    EXPECT_TRUE(fluid::computeAnisotropy(line, p, scratch, out));
  }
  // Garbage tunables are clamped, not propagated.
  AnisotropyParams bad;
  bad.radius = std::nanf("");
  bad.k_r = -3.0f;
  bad.k_s = std::numeric_limits<float>::infinity();
  bad.lambda = 7.0f;
  bad.k_n = -5;
  Anisotropy out;
  AnisotropyScratch scratch;
  fluid::computeAnisotropy(line, bad, scratch, out);
  for (std::size_t i = 0; i < line.size(); ++i) ASSERT_TRUE(finite(out.g[i]));
}

// Thread-count invariance: a random blob with a dense core and loose spray, 1 thread and 2
// threads, every output bit-equal.
TEST(Anisotropy, OneAndTwoThreadsAreBitEqual) {
  std::mt19937 rng(11);
  std::normal_distribution<float> core(0.0f, 0.15f);
  std::uniform_real_distribution<float> spray(-1.0f, 1.0f);
  std::vector<glm::vec3> pts;
  for (int k = 0; k < 6000; ++k) pts.push_back(glm::vec3(core(rng), core(rng), core(rng)));
  for (int k = 0; k < 1000; ++k) pts.push_back(glm::vec3(spray(rng), spray(rng), spray(rng)));
  AnisotropyParams p;
  p.radius = 0.06f;
  p.k_n = 10;
  auto run = [&](std::size_t threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Anisotropy out;
    AnisotropyScratch scratch;
    fluid::computeAnisotropy(pts, p, scratch, out);
    return out;
  };
  const Anisotropy a = run(1), b = run(2);
  ASSERT_EQ(a.g.size(), pts.size());
  EXPECT_EQ(std::memcmp(a.g.data(), b.g.data(), a.g.size() * sizeof(glm::mat3)), 0);
  EXPECT_EQ(std::memcmp(a.centre.data(), b.centre.data(), a.centre.size() * sizeof(glm::vec3)), 0);
  EXPECT_EQ(std::memcmp(a.max_axis.data(), b.max_axis.data(), a.max_axis.size() * sizeof(float)), 0);
  EXPECT_EQ(a.neighbours, b.neighbours);
  EXPECT_EQ(a.stretched, b.stretched);
  EXPECT_GT(a.stretched, 1000u);       // the core is stretched somewhere
  EXPECT_LT(a.stretched, pts.size());  // the spray is not
}

}  // namespace
