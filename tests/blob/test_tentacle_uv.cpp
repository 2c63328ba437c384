// Tentacle texturing through the marching-slices policy (paper §7): v grows monotonically from base
// to tip along every tentacle on the extracted mesh, u goes all the way round.
#include "blob_test_level.hpp"
#include "fluid/blob/tentacle_uv.hpp"
#include "fluid/surface/marching_slices_policy.hpp"

#include <cmath>
#include <cstdio>

namespace {

// u of every vertex with a tentacle share from the nearest tentacle particle by a scan of all of
// them (the definition blobTentacleU's grid must reproduce exactly).
std::vector<float> bruteForceU(const fluid::SurfaceMesh& mesh, const fluid::BlobWorld& w) {
  std::vector<float> u(mesh.positions.size(), -1.0f);
  for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
    if (mesh.attributes[k].z < 0.05f) continue;
    std::uint32_t best = 0;
    float best_d2 = INFINITY;
    for (const auto& chain : w.target.tentacle_particles)
      for (std::uint32_t i : chain) {
        const glm::vec3 d = mesh.positions[k] - w.particles.position[i];
        if (glm::dot(d, d) < best_d2) best_d2 = glm::dot(d, d), best = i;
      }
    const glm::vec3 t = w.particles.tangent[best], n = w.particles.normal[best];
    const glm::vec3 rel = mesh.positions[k] - w.particles.position[best];
    u[k] = std::atan2(glm::dot(rel, glm::cross(t, n)), glm::dot(rel, n)) / 6.28318530717958f + 0.5f;
    if (u[k] >= 1.0f) u[k] = 0.0f;
  }
  return u;
}

TEST(BlobTentacleUv, VGrowsFromBaseToTipAndUGoesRound) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  fluid::BlobBehaviour b;
  b.kind = fluid::BlobBehaviourKind::tentacles;
  b.tentacles = 3;
  b.tentacle_length = 1.5f;
  blobtest::runUntilGoal(w, b, 1.0f, glm::vec3(6.0f, 1.0f, 0.0f), false);

  const fluid::SurfaceInput in{
      fluid::pointView(w.particles.position), w.particles.strength, w.particles.radius_scale, {}};
  fluid::SurfaceParams sp;
  sp.rc = 2.0f * w.params.spacing;
  sp.cube = w.params.spacing / 4.0f;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh mesh;
  const fluid::SurfaceStatus st =
      fluid::extractWithPolicy(ex, in, sp, fluid::BlobTentaclePolicy{w.particles.length_coord.data()}, mesh);
  ASSERT_TRUE(st.ok()) << st.error;
  ASSERT_EQ(mesh.attributes.size(), mesh.positions.size());
  fluid::blobTentacleU(mesh, w);
  // The grid search finds the same nearest particle as a scan of all of them: u bit-identical.
  const std::vector<float> reference = bruteForceU(mesh, w);
  std::size_t textured = 0, differ = 0;
  for (std::size_t k = 0; k < reference.size(); ++k) {
    if (reference[k] < 0.0f) continue;
    ++textured;
    differ += mesh.attributes[k].x != reference[k];
  }
  EXPECT_GT(textured, 1000u);
  EXPECT_EQ(differ, 0u) << "of " << textured;
  // Far vertices (the mesh moved 3 m away: outside the grid, every cell empty) take the scan.
  fluid::SurfaceMesh far = mesh;
  for (glm::vec3& p : far.positions) p += glm::vec3(3.0f, 0.0f, 0.0f);
  fluid::blobTentacleU(far, w);
  const std::vector<float> far_reference = bruteForceU(far, w);
  differ = 0;
  for (std::size_t k = 0; k < far_reference.size(); ++k)
    differ += far_reference[k] >= 0.0f && far.attributes[k].x != far_reference[k];
  EXPECT_EQ(differ, 0u);

  for (std::size_t k = 0; k < w.target.tentacle_particles.size(); ++k) {
    // Vertices of this tentacle (mostly tentacle field, near this tentacle's axis), binned by the
    // distance along the tentacle's direction from its base.
    const glm::vec3 base = w.target.tentacle_base[k];
    const glm::vec3 dir = w.target.tentacle_dir[k];
    const float length = w.target.tentacle_length[k];
    constexpr int kBins = 8;
    double sum_v[kBins] = {}, count[kBins] = {};
    int low_u = 0, high_u = 0;
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const glm::vec4 a = mesh.attributes[v];
      if (a.z < 0.9f) continue;
      const glm::vec3 rel = mesh.positions[v] - base;
      const float along = glm::dot(rel, dir);
      if (glm::length(rel - along * dir) > 0.3f || along < 0.0f || along >= length) continue;
      const int bin = std::min(kBins - 1, static_cast<int>(along / length * kBins));
      sum_v[bin] += a.y;
      count[bin] += 1.0;
      EXPECT_GE(a.x, 0.0f);
      EXPECT_LT(a.x, 1.0f);
      low_u += a.x < 0.25f;
      high_u += a.x > 0.75f;
    }
    double previous = -1.0;
    std::printf("[blob] tentacle %zu mean v per eighth of its length:", k);
    for (int bin = 0; bin < kBins; ++bin) {
      ASSERT_GT(count[bin], 0.0) << "tentacle " << k << " bin " << bin;
      const double mean = sum_v[bin] / count[bin];
      std::printf(" %.3f", mean);
      EXPECT_GT(mean, previous) << "tentacle " << k << " bin " << bin;
      previous = mean;
    }
    std::printf("\n");
    EXPECT_GT(low_u, 10);  // u goes all the way round the tube
    EXPECT_GT(high_u, 10);
  }
}

}  // namespace
