// Each blob behaviour reaches its goal, measured as a number (issue 19, "Measured, not claimed").
// The measured values are printed ("[blob] ...") so a run of this file is the table's source.
#include "blob_test_level.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <cstdio>

namespace {

using blobtest::runUntilGoal;
using fluid::BlobBehaviour;
using fluid::BlobBehaviourKind;

TEST(BlobBehaviours, EmergeRisesOutOfTheSewerWithinFourSeconds) {
  fluid::BlobWorld w;
  ASSERT_TRUE(fluid::initBlob(w, glm::vec3(0.0f)).ok());
  const float pipe = 0.4f;
  w.colliders.push_back(blobtest::collider(std::make_shared<blobtest::SewerGround>(pipe)));
  // Start as a column inside the pipe, its top just under the grate.
  ASSERT_TRUE(fluid::placeBlob(w, fluid::blobColumn(w.params, glm::vec3(0.0f, -0.05f, 0.0f), pipe)).ok());
  const float radius = fluid::blobBodyRadius(w.params);
  EXPECT_LT(fluid::blobCentroid(w.particles.position).y, -radius);  // honestly starts deep down
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::emerge;
  b.point = glm::vec3(0.0f);  // the grate
  b.speed = 1.0f;
  const float t = runUntilGoal(w, b, 4.0f);
  std::printf("[blob] emerge: centroid %.2f m above the grate after %.2f s (goal: body radius %.2f m)\n",
              fluid::blobCentroid(w.particles.position).y, t, radius);
  EXPECT_GT(t, 0.0f) << "centroid height " << fluid::blobCentroid(w.particles.position).y;
  EXPECT_GE(blobtest::minDistance(w, 0), -0.01f * w.params.spacing);
}

TEST(BlobBehaviours, BallReachesSphericity09WithinThreeSeconds) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  const float before = fluid::blobSphericity(w.particles.position);
  EXPECT_LT(before, 0.8f);  // the rest shape is a flattened blob
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::ball;
  const float t = runUntilGoal(w, b, 3.0f, glm::vec3(0.0f), false);
  const float after = fluid::blobSphericity(w.particles.position);
  std::printf("[blob] ball: sphericity %.3f -> %.3f, >= 0.9 first after %.2f s (3 s run)\n", before, after, t);
  EXPECT_GT(t, 0.0f);
  EXPECT_GE(after, 0.9f);
}

// Mean distance of surface vertices from their tentacle's axis, near the base and near the tip,
// on the marching-slices mesh with the particles' strength and radius scale (paper §7).
void tentacleMeshRadii(const fluid::BlobWorld& w, float& base, float& tip) {
  const auto& x = w.particles.position;
  const fluid::SurfaceInput in{fluid::pointView(x), w.particles.strength, w.particles.radius_scale, {}};
  fluid::SurfaceParams sp;
  sp.rc = 2.0f * w.params.spacing;
  sp.cube = w.params.spacing / 4.0f;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh mesh;
  const fluid::SurfaceStatus st = ex.extract(in, sp, mesh);
  ASSERT_TRUE(st.ok()) << st.error;
  ASSERT_GT(mesh.positions.size(), 100u);
  double sum[2] = {0, 0};
  int count[2] = {0, 0};
  for (const glm::vec3& v : mesh.positions) {
    std::size_t best = 0;
    float bd = 1e30f;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const float d2 = glm::dot(v - x[i], v - x[i]);
      if (d2 < bd) bd = d2, best = i;
    }
    const float s = w.particles.length_coord[best];
    const int bin = s >= 0.1f && s <= 0.3f ? 0 : s >= 0.7f && s <= 0.9f ? 1 : -1;
    if (bin < 0) continue;
    const glm::vec3 r = v - x[best];
    const glm::vec3 t = w.particles.tangent[best];
    sum[bin] += glm::length(r - glm::dot(r, t) * t);
    ++count[bin];
  }
  ASSERT_GT(count[0], 10);
  ASSERT_GT(count[1], 10);
  base = static_cast<float>(sum[0] / count[0]);
  tip = static_cast<float>(sum[1] / count[1]);
}

TEST(BlobBehaviours, TentaclesReachTheirLengthAndTaperOnTheMesh) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::tentacles;
  b.tentacles = 4;
  b.tentacle_length = 1.5f;
  const glm::vec3 target(6.0f, 1.0f, 0.0f);
  const float t = runUntilGoal(w, b, 3.0f, target, false);
  const std::vector<float> reach = fluid::blobTentacleReach(w);
  ASSERT_EQ(reach.size(), 4u);
  const float shortest = *std::min_element(reach.begin(), reach.end());
  float base = 0.0f, tip = 0.0f;
  tentacleMeshRadii(w, base, tip);
  std::printf(
      "[blob] tentacles: 4 x %zu particles, shortest reach %.2f m of %.2f (goal 0.8 L first at %.2f s); "
      "mesh radius base %.3f m, tip %.3f m\n",
      w.target.tentacle_particles[0].size(), shortest, b.tentacle_length, t, base, tip);
  EXPECT_GT(t, 0.0f);
  EXPECT_GE(shortest, 0.8f * b.tentacle_length);
  EXPECT_LT(tip, 0.85f * base);
  // Particles are ordered along each tentacle: the length coordinate grows with the distance from the base.
  for (std::size_t k = 0; k < 4; ++k) {
    const auto& chain = w.target.tentacle_particles[k];
    for (std::size_t j = 1; j < chain.size(); ++j)
      EXPECT_GT(w.particles.length_coord[chain[j]], w.particles.length_coord[chain[j - 1]]);
    const glm::vec3 basep = w.target.tentacle_base[k];
    EXPECT_GT(glm::length(w.particles.position[chain.back()] - basep),
              glm::length(w.particles.position[chain[chain.size() / 2]] - basep));
  }
}

TEST(BlobBehaviours, CoatWallPutsEightyPercentWithinTwoRadiiOfTheWall) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  w.colliders.push_back(blobtest::wall(1.2f, 0.3f));
  const float band = 2.0f * fluid::blobParticleRadius(w.params);
  const float before = fluid::blobFractionNearWall(w, 1, band);
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::coat_wall;
  b.point = glm::vec3(1.2f, 1.3f, 0.0f);
  b.wall_collider = 1;
  const float t = runUntilGoal(w, b, 4.0f, glm::vec3(0.0f), false);
  const float after = fluid::blobFractionNearWall(w, 1, band);
  std::printf(
      "[blob] coat_wall: %.0f %% -> %.0f %% of particles within 2 radii of the wall, >= 80 %% first at %.2f s\n",
      100.0f * before, 100.0f * after, t);
  EXPECT_LT(before, 0.2f);
  EXPECT_GT(t, 0.0f);
  EXPECT_GE(after, 0.8f);
  EXPECT_GE(blobtest::minDistance(w, 1), -0.01f * w.params.spacing);
}

TEST(BlobBehaviours, ChaseClosesOnAMovingTargetAtTheConfiguredSpeed) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::chase;
  b.speed = 1.5f;
  b.catch_distance = 0.5f;
  const float runner = 0.5f;  // the target walks away at 0.5 m/s: the gap should close at 1.0 m/s
  glm::vec3 target(5.0f, 0.0f, 0.0f);
  fluid::startBlobBehaviour(w, b, target);
  auto gap = [&] {
    glm::vec3 d = target - fluid::blobCentroid(w.particles.position);
    d.y = 0.0f;
    return glm::length(d);
  };
  float gap1 = 0.0f;
  const int steps = static_cast<int>(4.0f / w.params.step);
  for (int s = 0; s < steps; ++s) {
    target.x += runner * w.params.step;
    fluid::updateBlobBehaviour(w, b, target, w.params.step);
    ASSERT_TRUE(fluid::stepBlob(w).ok());
    if (s + 1 == static_cast<int>(1.0f / w.params.step)) gap1 = gap();
  }
  const float gap4 = gap();
  const float rate = (gap1 - gap4) / 3.0f;
  std::printf("[blob] chase: gap %.2f m at 1 s, %.2f m at 4 s: closing %.2f m/s (configured %.2f - %.2f = %.2f)\n",
              gap1, gap4, rate, b.speed, runner, b.speed - runner);
  EXPECT_NEAR(rate, b.speed - runner, 0.2f * (b.speed - runner));
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
}

TEST(BlobBehaviours, ChaseGoesAroundAWallInItsWay) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  w.colliders.push_back(blobtest::wall(1.5f, 0.3f, 2.0f, 1.0f));  // 2 m wide, 2 m high, across the way
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::chase;
  b.speed = 1.5f;
  b.catch_distance = 0.8f;
  const glm::vec3 target(4.0f, 0.0f, 0.0f);
  const float t = runUntilGoal(w, b, 5.0f, target);
  std::printf("[blob] chase around a 2 m wall: target (4 m away behind it) caught after %.2f s\n", t);
  EXPECT_GT(t, 0.0f);
  EXPECT_GE(blobtest::minDistance(w, 1), -0.01f * w.params.spacing);
}

TEST(BlobBehaviours, ReassemblesIntoTheRestShapeAfterABlast) {
  fluid::BlobWorld w = blobtest::restingBlob();
  w.colliders.push_back(blobtest::ground());
  runUntilGoal(w, BlobBehaviour{}, 0.5f);
  const float radius = fluid::blobBodyRadius(w.params);
  const glm::vec3 c = fluid::blobCentroid(w.particles.position);
  EXPECT_GT(fluid::blastBlob(w, blobtest::blastOfSpeed(w, c + glm::vec3(0.1f, -0.2f, 0.05f), 15.0f, 2.0f * radius)),
            w.particles.size() / 2);
  // Limp for half a second (an idle state with weight 0, as a program would say "stunned"): the
  // goo flies apart and splashes down.
  BlobBehaviour limp;
  limp.weight = 0.0f;
  runUntilGoal(w, limp, 0.5f);
  const float blown = fluid::blobShapeError(w.particles.position, w.particles.rest);
  BlobBehaviour b;
  b.kind = BlobBehaviourKind::reassemble;
  const float t = runUntilGoal(w, b, 5.0f, glm::vec3(0.0f), false);
  // Against the rest shape's slots as the behaviour matched them to the scattered particles.
  const float after = fluid::blobShapeError(w.particles.position, w.target.offset);
  std::printf("[blob] reassemble: shape error %.2f -> %.3f body radii after 5 s (<= 0.1 first at %.2f s)\n",
              blown / radius, after / radius, t);
  EXPECT_GT(blown, 1.0f * radius);
  EXPECT_GT(t, 0.0f);
  EXPECT_LE(after, 0.1f * radius);
}

}  // namespace
