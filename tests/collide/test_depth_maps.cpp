// Depth-map colliders (Kolb et al. 2004 §4.1, §4.3): baking, rule (2) queries, the hard
// cases of issue 5, thread-count invariance, and the §3.3.2 particle step on top.
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"
#include "fluid/sph/analytic_colliders.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

namespace {

using collide_test::Mesh;
using fluid::DepthMapFormat;

fluid::DepthMapCollider bake(const Mesh& mesh, const std::vector<fluid::MapSpec>& specs, int threads = 0) {
  fluid::DepthMapCollider collider;
  const fluid::BakeStatus status = fluid::bakeDepthMaps(mesh.view(), specs, {256, threads}, collider);
  EXPECT_TRUE(status.ok()) << status.error;
  return collider;
}

fluid::DepthMapCollider bakeDefault(const Mesh& mesh, int res, DepthMapFormat format, bool cube = false) {
  return bake(mesh, fluid::defaultMapSpecs(fluid::meshBounds(mesh.view()), res, format, cube));
}

std::vector<glm::vec3> randomPoints(std::size_t count, glm::vec3 lo, glm::vec3 hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> p(count);
  for (glm::vec3& q : p) q = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
  return p;
}

bool isInside(const fluid::ColliderSample& s) { return s.valid && s.distance < 0.0f; }

const Mesh& sphere() {
  static const Mesh m = collide_test::makeSphere(1.0f, 24, 48);
  return m;
}

constexpr DepthMapFormat kFormats[] = {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16,
                                       DepthMapFormat::cube8};

fluid::DepthMapCollider sphereCollider(DepthMapFormat format, int res) {
  if (format != DepthMapFormat::cube8) return bakeDefault(sphere(), res, format);
  // A lone depth cube from the centre (which is inside: GREATER), §4.3.
  auto specs = fluid::defaultMapSpecs(fluid::meshBounds(sphere().view()), res, DepthMapFormat::front_back16, true);
  return bake(sphere(), {specs.back()});
}

TEST(DepthMap, SphereClassificationAndDistancePerFormat) {
  for (DepthMapFormat format : kFormats) {
    SCOPED_TRACE(fluid::formatName(format));
    const fluid::DepthMapCollider c = sphereCollider(format, 128);
    EXPECT_EQ(c.depthMapCount(), 6);
    const fluid::MeshDistance exact(sphere().view());
    const auto points = randomPoints(4000, glm::vec3(-1.3f), glm::vec3(1.3f), 11);
    int wrong = 0;
    for (const glm::vec3& p : points) {
      const fluid::ColliderSample s = c.sample(p);
      const fluid::ColliderSample e = exact.sample(p);
      if (isInside(s) != isInside(e)) ++wrong;
      // Deep points are never misclassified.
      if (std::fabs(e.distance) > 0.05f) {
        ASSERT_EQ(isInside(s), isInside(e)) << p.x << " " << p.y << " " << p.z;
      }
      if (s.valid) {
        ASSERT_TRUE(std::isfinite(s.distance));
        ASSERT_NEAR(glm::length(s.normal), 1.0f, 1e-4f);
      }
    }
    EXPECT_LT(wrong, 40);  // < 1 %, all within 0.05 of the surface
  }
}

TEST(DepthMap, PointsExactlyOnTheSurface) {
  // Mesh vertices are on the surface: |f| is bounded by the depth quantisation and the
  // texel footprint, and the normal points outward.
  for (DepthMapFormat format : kFormats) {
    SCOPED_TRACE(fluid::formatName(format));
    const fluid::DepthMapCollider c = sphereCollider(format, 256);
    for (std::size_t k = 0; k < sphere().positions.size(); k += 7) {
      const glm::vec3 p = sphere().positions[k];
      const fluid::ColliderSample s = c.sample(p);
      ASSERT_TRUE(s.valid);
      EXPECT_LT(std::fabs(s.distance), 0.05f) << k;
      EXPECT_GT(glm::dot(s.normal, p), 0.7f) << k;
    }
  }
}

TEST(DepthMap, PointsOnTexelBordersAreConsistent) {
  // A box aligned with the texel grid of its z map: query points exactly on texel borders
  // (u = i/N) get a finite, valid answer that agrees with the neighbouring texel centres.
  const Mesh box = collide_test::makeBox(glm::vec3(-0.5f), glm::vec3(0.5f));
  fluid::MapSpec spec;
  spec.format = DepthMapFormat::float32;
  spec.compare = fluid::DepthCompare::less;
  spec.resolution = 16;
  spec.ortho.half_extent = {1.0f, 1.0f, 1.0f};  // texel = 2/16 = 0.125 collider units
  const fluid::DepthMapCollider c = bake(box, {spec});
  for (int i = 1; i <= 15; ++i) {
    const float x = -1.0f + 0.125f * static_cast<float>(i);  // exactly on a texel border
    for (glm::vec3 p : {glm::vec3(x, 0.0625f, -0.9f), glm::vec3(0.0625f, x, -0.9f)}) {
      const fluid::ColliderSample s = c.sample(p);
      // A border point belongs to the texel on its right; texels touching the box
      // ([−0.625, 0.625) after conservative rasterization) see its face z = −0.5, the
      // others are background, i.e. "far outside" for this enclosing map.
      if (x >= -0.625f && x < 0.625f) {
        ASSERT_TRUE(s.valid) << x;
        EXPECT_NEAR(s.distance, 0.4f, 1e-5f) << x;  // eq. (1): z_scale (depth − p'z)
        EXPECT_EQ(s.normal, glm::vec3(0, 0, -1));
      } else {
        EXPECT_FALSE(s.valid) << x;
      }
    }
  }
}

TEST(DepthMap, OutsideEveryViewVolumeHasNoOpinion) {
  const fluid::DepthMapCollider c = sphereCollider(DepthMapFormat::front_back16, 64);
  // Outside every map's footprint: no opinion (the maps enclose the sphere, so these points
  // are known to be outside; the distance is unknown).
  for (glm::vec3 p : {glm::vec3(3, 3, 3), glm::vec3(-2, 0, 2), glm::vec3(1e30f, 1e30f, 0)}) {
    const fluid::ColliderSample s = c.sample(p);
    EXPECT_FALSE(s.valid);
    EXPECT_EQ(s.distance, FLT_MAX);
  }
  // In front of a map's near plane, within its footprint: eq. (1) along the view axis.
  EXPECT_NEAR(c.sample({5, 0, 0}).distance, 4.0f, 0.01f);
  EXPECT_NEAR(c.sample({0, -7, 0}).distance, 6.0f, 0.01f);
  EXPECT_GT(c.sample({0, -7, 0}).normal.y, -1.01f);
  EXPECT_LT(c.sample({0, -7, 0}).normal.y, -0.99f);
  // A single non-enclosing map: its invalid votes are ignored, not "far outside".
  fluid::MapSpec spec;
  spec.format = DepthMapFormat::float32;
  spec.resolution = 32;
  spec.ortho.half_extent = {0.5f, 0.5f, 2.0f};  // narrower than the sphere
  const fluid::DepthMapCollider partial = bake(sphere(), {spec});
  EXPECT_FALSE(partial.maps()[0].encloses_collider);
  EXPECT_FALSE(partial.sample({0.9f, 0.0f, 0.0f}).valid);  // outside its x range
  EXPECT_TRUE(isInside(partial.sample({0.0f, 0.0f, 0.0f})));
}

TEST(DepthMap, NonFiniteQueryPointsAreReportedNotPropagated) {
  const fluid::DepthMapCollider c = sphereCollider(DepthMapFormat::fixed8, 64);
  std::vector<glm::vec3> p = {{0, 0, 0}, {NAN, 0, 0}, {0, INFINITY, 0}, {0.2f, 0.1f, 0}, {0, 0, -INFINITY}};
  std::vector<fluid::ColliderSample> out(p.size());
  EXPECT_EQ(fluid::queryParallel(c, p, out, {2, 1}), 3u);
  for (const fluid::ColliderSample& s : out) {
    EXPECT_FALSE(std::isnan(s.distance));
    EXPECT_FALSE(std::isnan(s.normal.x));
  }
  EXPECT_TRUE(isInside(out[0]));
  EXPECT_FALSE(out[1].valid);
  EXPECT_FALSE(out[2].valid);
  EXPECT_TRUE(isInside(out[3]));
}

TEST(DepthMap, ThinWallOneTexelThickIsSeenByEveryMap) {
  // Wall 0.0625 thick in x; the default maps at 64² have texels of about 0.066 along y and z
  // in the x map and 0.066 along x in the edge-on y and z maps, i.e. one texel thick.
  const Mesh wall = collide_test::makeBox({-0.03125f, -1.0f, -1.0f}, {0.03125f, 1.0f, 1.0f});
  for (DepthMapFormat format : {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16}) {
    SCOPED_TRACE(fluid::formatName(format));
    const fluid::DepthMapCollider c = bakeDefault(wall, 64, format);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.95f, 0.95f), across(-0.03f, 0.03f);
    for (int k = 0; k < 2000; ++k) {
      const glm::vec3 p{across(rng), u(rng), u(rng)};
      const fluid::ColliderSample s = c.sample(p);
      ASSERT_TRUE(isInside(s)) << p.x << " " << p.y << " " << p.z;
      EXPECT_GT(std::fabs(s.normal.x), 0.99f);  // the wall's big faces decide
    }
    EXPECT_FALSE(isInside(c.sample({0.2f, 0.0f, 0.0f})));
    EXPECT_FALSE(isInside(c.sample({-0.2f, 0.3f, 0.0f})));
  }
}

TEST(DepthMap, FastParticleCrossingAThinWall) {
  const Mesh wall = collide_test::makeBox({-0.03125f, -1.0f, -1.0f}, {0.03125f, 1.0f, 1.0f});
  const fluid::DepthMapCollider c = bakeDefault(wall, 64, DepthMapFormat::front_back16);
  const float dt = 0.01f;
  std::vector<glm::vec3> previous = {{-0.5f, 0.0f, 0.0f}};
  const glm::vec3 v{100.0f, 0.0f, 0.0f};  // 1 unit per step, 16x the wall thickness
  fluid::CollideScratch scratch;
  fluid::CollideDesc desc;
  desc.dt = dt;
  desc.material = {0.0f, 0.5f, 0.0f};
  // The paper's double check samples only the two end points: the particle tunnels.
  {
    std::vector<glm::vec3> pos = {previous[0] + v * dt}, vel = {v};
    const fluid::CollideCounts n = fluid::collideParticles(c, {}, previous, pos, vel, desc, scratch);
    EXPECT_EQ(n.reacted + n.pushed_out, 0u);
    EXPECT_GT(pos[0].x, 0.1f);
  }
  // Sampling the step every max_step (< the wall thickness) stops it at the near face.
  {
    desc.max_step = 0.03f;
    std::vector<glm::vec3> pos = {previous[0] + v * dt}, vel = {v};
    const fluid::CollideCounts n = fluid::collideParticles(c, {}, previous, pos, vel, desc, scratch);
    EXPECT_EQ(n.reacted, 1u);
    EXPECT_EQ(n.swept, 1u);
    EXPECT_LT(pos[0].x, -0.03125f);
    EXPECT_GT(pos[0].x, -0.1f);
    EXPECT_NEAR(vel[0].x, -50.0f, 0.1f);  // −ε v⊥ with ε = 0.5 (normal quantised by the L1 index)
  }
  // The end point past the middle of the wall (inside, nearer the far face): the end sample alone
  // pushes the particle out through the far face; the sweep finds the entry at the near face.
  {
    const std::vector<glm::vec3> from = {{-0.3f, 0.0f, 0.0f}};
    const glm::vec3 end{0.02f, 0.0f, 0.0f};
    desc.max_step = 0.0f;
    std::vector<glm::vec3> pos = {end}, vel = {v};
    fluid::collideParticles(c, {}, from, pos, vel, desc, scratch);
    EXPECT_GT(pos[0].x, 0.03125f) << "without the sweep: out through the far face";
    desc.max_step = 0.03f;
    pos = {end};
    vel = {v};
    const fluid::CollideCounts n = fluid::collideParticles(c, {}, from, pos, vel, desc, scratch);
    EXPECT_EQ(n.swept, 1u);
    EXPECT_LT(pos[0].x, -0.03125f);
    EXPECT_LT(vel[0].x, 0.0f);
  }
}

// Counts the points a collideParticles call asks the shape about.
class CountingShape final : public fluid::SignedDistanceShape {
 public:
  explicit CountingShape(const fluid::SignedDistanceShape& inner) : inner_(inner) {}
  void query(std::span<const glm::vec3> points, std::span<fluid::ColliderSample> out) const override {
    queries_ += points.size();
    inner_.query(points, out);
  }
  std::size_t queries() const { return queries_.load(); }

 private:
  const fluid::SignedDistanceShape& inner_;
  mutable std::atomic<std::size_t> queries_{0};
};

// CollideDesc::bounded skips the steps that miss the box where the shape can be inside, without
// changing a bit of the result, and the result does not depend on the threads; the per-particle
// outcomes agree with the counts.
TEST(CollideParticles, InsideBoxCullAndThreadsChangeNothing) {
  const glm::vec3 half(0.5f, 0.05f, 0.5f);  // a thin plate, exact (analytic) distance
  const fluid::BoxShape plate(half);
  fluid::ColliderPose pose;
  pose.rotation = glm::angleAxis(0.4f, glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)));
  pose.translation = {0.3f, -0.2f, 0.1f};
  pose.linear_velocity = {0.0f, 1.0f, 0.0f};
  pose.angular_velocity = {0.0f, 0.0f, 2.0f};
  const float dt = 0.01f;
  // Up to 30 m/s: steps up to 0.5, ten plate thicknesses, so the sweep matters.
  const std::vector<glm::vec3> previous = randomPoints(8000, glm::vec3(-1.2f), glm::vec3(1.8f), 21);
  const std::vector<glm::vec3> velocity = randomPoints(previous.size(), glm::vec3(-30.0f), glm::vec3(30.0f), 22);
  std::vector<glm::vec3> predicted(previous.size());
  for (std::size_t i = 0; i < previous.size(); ++i) predicted[i] = previous[i] + velocity[i] * dt;
  struct Run {
    std::vector<glm::vec3> position, velocity;
    fluid::CollideCounts counts;
    std::vector<fluid::CollisionOutcome> outcome;
    std::size_t queries = 0;
  };
  auto run = [&](bool bounded, fluid::Bounds inside, int threads) {
    Run r{predicted, velocity, {}, {}, 0};
    const CountingShape counting(plate);
    fluid::CollideDesc desc;
    desc.dt = dt;
    desc.material = {0.2f, 0.4f, 0.0f};
    desc.max_step = 0.02f;
    desc.bounded = bounded;
    desc.inside = inside;
    desc.parallel = {threads, 64};
    fluid::CollideScratch scratch;
    r.counts = fluid::collideParticles(counting, pose, previous, r.position, r.velocity, desc, scratch);
    r.outcome = scratch.outcome;
    r.queries = counting.queries();
    return r;
  };
  const Run all = run(false, {}, 1);
  const Run culled = run(true, {-half, half}, 2);
  EXPECT_GT(all.counts.reacted, 40u);
  EXPECT_GT(all.counts.pushed_out, 5u);
  EXPECT_GT(all.counts.swept, 20u);
  std::size_t reacted = 0, pushed_out = 0, differ = 0;
  for (std::size_t i = 0; i < previous.size(); ++i) {
    reacted += all.outcome[i] == fluid::CollisionOutcome::reacted;
    pushed_out += all.outcome[i] == fluid::CollisionOutcome::pushed_out;
    differ += all.position[i] != culled.position[i] || all.velocity[i] != culled.velocity[i] ||
              all.outcome[i] != culled.outcome[i];
  }
  EXPECT_EQ(reacted, all.counts.reacted);
  EXPECT_EQ(pushed_out, all.counts.pushed_out);
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(culled.counts.reacted, all.counts.reacted);
  EXPECT_EQ(culled.counts.pushed_out, all.counts.pushed_out);
  EXPECT_EQ(culled.counts.swept, all.counts.swept);
  EXPECT_LT(culled.queries, all.queries / 2);
  std::printf("[collide] inside-box cull: %zu queries of %zu, %zu reacted, %zu pushed out, %zu swept\n", culled.queries,
              all.queries, all.counts.reacted, all.counts.pushed_out, all.counts.swept);
  // An empty box: nothing can be inside, so nothing is asked and nothing moves.
  const Run none = run(true, {glm::vec3(1.0f), glm::vec3(-1.0f)}, 1);
  EXPECT_EQ(none.queries, 0u);
  EXPECT_EQ(none.counts.reacted + none.counts.pushed_out, 0u);
  EXPECT_EQ(none.position, predicted);
}

TEST(DepthMap, ConcaveBasinNeedsTheExtraMap) {
  const Mesh basin = collide_test::makeBasin(64);
  const fluid::Bounds bounds = fluid::meshBounds(basin.view());
  auto specs = fluid::defaultMapSpecs(bounds, 128, DepthMapFormat::front_back16);
  const fluid::DepthMapCollider plain = bake(basin, specs);
  specs.push_back(collide_test::basinCavityCube(128));
  const fluid::DepthMapCollider extra = bake(basin, specs);
  const fluid::MeshDistance exact(basin.view());
  // Points in the cavity under the overhanging rim: invisible from above.
  int plain_wrong = 0, extra_wrong = 0, total = 0;
  double plain_err = 0.0, extra_err = 0.0;
  for (int k = 0; k < 36; ++k) {
    const float a = glm::radians(10.0f * static_cast<float>(k));
    for (float r : {0.86f, 0.9f}) {
      const glm::vec3 p{r * std::cos(a), r * std::sin(a), 0.75f};
      const fluid::ColliderSample e = exact.sample(p);
      ASSERT_FALSE(isInside(e));
      ++total;
      plain_wrong += isInside(plain.sample(p));
      extra_wrong += isInside(extra.sample(p));
    }
    // Cavity points near the floor and the wall: the extra map also fixes the distance.
    for (glm::vec3 p : {glm::vec3(0.3f * std::cos(a), 0.3f * std::sin(a), 0.3f),
                        glm::vec3(0.85f * std::cos(a), 0.85f * std::sin(a), 0.5f)}) {
      const float d = exact.sample(p).distance;
      plain_err += std::fabs(plain.sample(p).distance - d);
      extra_err += std::fabs(extra.sample(p).distance - d);
    }
  }
  EXPECT_EQ(plain_wrong, total);  // the axis maps alone call the whole region inside
  EXPECT_EQ(extra_wrong, 0);
  EXPECT_LT(extra_err, 0.5 * plain_err);
  // The walls themselves stay solid with the extra map.
  for (int k = 0; k < 36; ++k) {
    const float a = glm::radians(10.0f * static_cast<float>(k));
    EXPECT_TRUE(isInside(extra.sample({1.1f * std::cos(a), 1.1f * std::sin(a), 0.6f})));
    EXPECT_TRUE(isInside(extra.sample({0.5f * std::cos(a), 0.5f * std::sin(a), 0.07f})));
  }
}

TEST(Bake, RejectsEmptyAndBrokenMeshesAndSkipsDegenerateTriangles) {
  const std::vector<fluid::MapSpec> specs = fluid::defaultMapSpecs({glm::vec3(-1), glm::vec3(1)}, 32);
  fluid::DepthMapCollider c;
  EXPECT_NE(fluid::bakeDepthMaps({}, specs, {}, c).error.find("empty"), std::string::npos);
  const std::vector<glm::vec3> pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {NAN, 0, 0}};
  const std::vector<std::uint32_t> bad_index = {0, 1, 7};
  EXPECT_NE(fluid::bakeDepthMaps({pos, bad_index}, specs, {}, c).error.find("index 7 out of range"), std::string::npos);
  const std::vector<std::uint32_t> nan_tri = {0, 1, 3};
  EXPECT_NE(fluid::bakeDepthMaps({pos, nan_tri}, specs, {}, c).error.find("non-finite"), std::string::npos);
  const std::vector<std::uint32_t> not_triangles = {0, 1};
  EXPECT_FALSE(fluid::bakeDepthMaps({pos, not_triangles}, specs, {}, c).ok());
  const std::vector<std::uint32_t> only_degenerate = {0, 0, 1, 1, 1, 1};
  EXPECT_NE(fluid::bakeDepthMaps({pos, only_degenerate}, specs, {}, c).error.find("degenerate"), std::string::npos);
  EXPECT_TRUE(c.maps().empty());  // failures leave the output alone

  // Degenerate triangles mixed into a good mesh: skipped and counted, result unchanged.
  Mesh box = collide_test::makeBox(glm::vec3(-0.5f), glm::vec3(0.5f));
  const fluid::DepthMapCollider clean = bakeDefault(box, 32, DepthMapFormat::float32);
  box.positions.push_back({0.2f, 0.2f, 0.2f});
  const auto extra = static_cast<std::uint32_t>(box.positions.size() - 1);
  box.indices.insert(box.indices.end(), {0, 0, 3, 0, 7, 7, extra, extra, extra, 0, 7, 7});
  box.indices.insert(box.indices.end(), {0, 6, 6});
  fluid::DepthMapCollider dirty;
  const fluid::BakeStatus st = fluid::bakeDepthMaps(
      box.view(), fluid::defaultMapSpecs(fluid::meshBounds(box.view()), 32, DepthMapFormat::float32), {}, dirty);
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_EQ(st.degenerate_triangles, 5u);
  ASSERT_EQ(dirty.maps().size(), clean.maps().size());
  for (std::size_t m = 0; m < clean.maps().size(); ++m) EXPECT_EQ(dirty.maps()[m].texels, clean.maps()[m].texels);

  // Bad specs name the map and field.
  auto bad = specs;
  bad[1].resolution = 2;
  EXPECT_NE(fluid::bakeDepthMaps(box.view(), bad, {}, c).error.find("map 1: resolution 2"), std::string::npos);
  bad = specs;
  bad[0].ortho.up = bad[0].ortho.forward;
  EXPECT_NE(fluid::bakeDepthMaps(box.view(), bad, {}, c).error.find("parallel"), std::string::npos);
}

TEST(Bake, ResultsDoNotDependOnThreadCount) {
  const Mesh torus = collide_test::makeTorus(1.0f, 0.35f, 48, 16);
  auto specs = fluid::defaultMapSpecs(fluid::meshBounds(torus.view()), 96, DepthMapFormat::fixed8, true);
  const fluid::DepthMapCollider one = bake(torus, specs, 1);
  const fluid::DepthMapCollider two = bake(torus, specs, 2);
  for (std::size_t m = 0; m < one.maps().size(); ++m) ASSERT_EQ(one.maps()[m].texels, two.maps()[m].texels) << m;
  const auto points = randomPoints(20000, glm::vec3(-1.5f), glm::vec3(1.5f), 3);
  std::vector<fluid::ColliderSample> a(points.size()), b(points.size());
  fluid::queryParallel(one, points, a, {1});
  fluid::queryParallel(one, points, b, {2, 257});
  for (std::size_t k = 0; k < points.size(); ++k) {
    ASSERT_EQ(std::memcmp(&a[k].distance, &b[k].distance, 4), 0);
    ASSERT_EQ(a[k].normal, b[k].normal);
    ASSERT_EQ(a[k].valid, b[k].valid);
  }
}

TEST(DepthMap, TexelBytesFollowTheDocumentedEncoding) {
  // Decode one texel per format by hand, exactly as the GLSL side will, and compare with the
  // collider's answer at that texel's centre.
  const Mesh box = collide_test::makeBox(glm::vec3(-0.5f), glm::vec3(0.5f));
  for (DepthMapFormat format : {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16}) {
    SCOPED_TRACE(fluid::formatName(format));
    fluid::MapSpec spec;
    spec.format = format;
    spec.compare = fluid::DepthCompare::less;
    spec.resolution = 8;
    spec.ortho.half_extent = glm::vec3(1.0f);
    const fluid::DepthMapCollider c = bake(box, {spec});
    const fluid::DepthMap& m = c.maps()[0];
    const std::size_t texel = 3 * 8 + 4;  // (i, j) = (4, 3): centre (x, y) = (0.125, −0.125)
    const std::uint8_t* t = m.texels.data() + texel * fluid::texelBytes(format);
    float depth = 0.0f;
    glm::vec3 normal(0.0f);
    if (format == DepthMapFormat::float32) {
      float v[4];
      std::memcpy(v, t, 16);
      normal = {v[0], v[1], v[2]};
      depth = v[3];
    } else if (format == DepthMapFormat::fixed8) {
      depth = static_cast<float>(t[2] * 256 + t[3]) * 1.52590219e-05f;
      normal = fluid::l1TexelNormal({t[0], t[1]}, 256);
    } else {
      std::uint16_t index, half;
      std::memcpy(&index, t, 2);
      std::memcpy(&half, t + 4, 2);
      depth = fluid::halfToFloat(half);
      normal = fluid::l1TexelNormal({index & 0xFF, index >> 8}, 256);
    }
    EXPECT_NEAR(depth, 0.25f, 1e-3f);  // top face z = −0.5 in a volume z ∈ [−1, 1]
    EXPECT_LT(glm::length(normal - glm::vec3(0, 0, -1)), 1e-2f);
    const fluid::ColliderSample s = c.sample({0.125f, -0.125f, -0.75f});
    EXPECT_EQ(s.distance, 2.0f * (depth - 0.125f));
    EXPECT_EQ(s.normal, normal);
  }
}

TEST(DepthMap, MovingColliderPoseAndParticleStep) {
  const Mesh box = collide_test::makeBox({-1.0f, -1.0f, -0.1f}, {1.0f, 1.0f, 0.1f});  // a plate
  const fluid::DepthMapCollider c = bakeDefault(box, 64, DepthMapFormat::float32);
  fluid::ColliderPose pose;
  pose.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(1, 0, 0));  // plate now in the xz plane
  pose.translation = {0.0f, 2.0f, 0.0f};
  pose.linear_velocity = {0.0f, 1.0f, 0.0f};
  std::vector<glm::vec3> world = {{0.0f, 2.05f, 0.0f}, {0.0f, 2.5f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  std::vector<fluid::ColliderSample> out(world.size());
  std::vector<glm::vec3> scratch;
  fluid::queryWorld(c, pose, world, out, scratch);
  EXPECT_TRUE(isInside(out[0]));
  EXPECT_NEAR(out[1].distance, 0.4f, 1e-3f);
  EXPECT_GT(out[1].normal.y, 0.999f);         // world-space normal
  EXPECT_NEAR(out[2].distance, 1.9f, 1e-3f);  // below the plate's other face
  EXPECT_LT(out[2].normal.y, -0.999f);

  // A particle resting on the plate's top face as the plate moves up into it: pushed out
  // and given the plate's velocity (relative velocity reflected, §3.3.2).
  std::vector<glm::vec3> previous = {{0.3f, 2.11f, 0.2f}};
  std::vector<glm::vec3> predicted = {{0.3f, 2.09f, 0.2f}};
  std::vector<glm::vec3> velocity = {{0.0f, 0.0f, 0.0f}};
  fluid::CollideScratch s;
  fluid::CollideDesc desc;
  desc.material = {0.0f, 0.0f, 0.0f};
  const fluid::CollideCounts n = fluid::collideParticles(c, pose, previous, predicted, velocity, desc, s);
  EXPECT_EQ(n.reacted, 1u);
  EXPECT_NEAR(predicted[0].y, 2.1f + desc.skin, 1e-3f);
  EXPECT_NEAR(velocity[0].y, 1.0f, 1e-4f);  // resilience 0: moves with the plate
}

TEST(MeshDistance, BvhMatchesBruteForce) {
  const Mesh torus = collide_test::makeTorus(1.0f, 0.35f, 32, 12);
  const fluid::MeshDistance exact(torus.view());
  for (const glm::vec3& p : randomPoints(2000, glm::vec3(-1.6f), glm::vec3(1.6f), 9)) {
    const fluid::ColliderSample a = exact.sample(p), b = exact.sampleBruteForce(p);
    ASSERT_NEAR(a.distance, b.distance, 1e-5f) << p.x << " " << p.y << " " << p.z;
  }
  // Against the analytic torus distance, up to the tessellation error.
  for (const glm::vec3& p : randomPoints(500, glm::vec3(-1.6f), glm::vec3(1.6f), 10)) {
    const float ring = std::sqrt(p.x * p.x + p.y * p.y) - 1.0f;
    const float analytic = std::sqrt(ring * ring + p.z * p.z) - 0.35f;
    ASSERT_NEAR(exact.sample(p).distance, analytic, 0.02f);
  }
}

TEST(MapSpec, ParsesItemsAndNamesBadOnes) {
  const fluid::Bounds b{glm::vec3(-1), glm::vec3(1)};
  std::vector<fluid::MapSpec> specs;
  std::string error;
  ASSERT_TRUE(fluid::parseMapSpec("axes,cube", b, 64, DepthMapFormat::front_back16, specs, error)) << error;
  EXPECT_EQ(specs.size(), 4u);
  ASSERT_TRUE(fluid::parseMapSpec("x,cube@0:0:0.5:1", b, 64, DepthMapFormat::fixed8, specs, error)) << error;
  ASSERT_EQ(specs.size(), 3u);
  EXPECT_EQ(specs[2].kind, fluid::MapKind::cube);
  EXPECT_EQ(specs[2].cube.center.z, 0.5f);
  EXPECT_FALSE(fluid::parseMapSpec("axes,bogus", b, 64, DepthMapFormat::fixed8, specs, error));
  EXPECT_NE(error.find("'bogus'"), std::string::npos);
  EXPECT_FALSE(fluid::parseMapSpec("cube@1:2:3", b, 64, DepthMapFormat::fixed8, specs, error));
  EXPECT_FALSE(fluid::parseMapSpec("cube@0:0:0:-1", b, 64, DepthMapFormat::fixed8, specs, error));
}

}  // namespace

namespace {

TEST(TestMeshes, ConvexOnesAreWoundOutwardConsistently) {
  for (const Mesh& m : {collide_test::makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)), sphere()}) {
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
      const glm::vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
                      c = m.positions[m.indices[t + 2]];
      const glm::vec3 n = glm::cross(b - a, c - a);
      ASSERT_GT(glm::dot(n, (a + b + c) / 3.0f), 0.0f) << t / 3;
    }
  }
}

TEST(Bake, InvertedWindingGivesTheSameCollider) {
  Mesh flipped = sphere();
  for (std::size_t t = 0; t < flipped.indices.size(); t += 3) std::swap(flipped.indices[t + 1], flipped.indices[t + 2]);
  const fluid::DepthMapCollider a = bakeDefault(sphere(), 32, DepthMapFormat::fixed8, true);
  const fluid::DepthMapCollider b = bakeDefault(flipped, 32, DepthMapFormat::fixed8, true);
  // The same texels, except where a texel centre or ray meets an edge shared by two
  // triangles: the vertex order changes which one wins the tie.
  std::size_t same = 0, total = 0;
  for (std::size_t m = 0; m < a.maps().size(); ++m) {
    const auto& ta = a.maps()[m].texels;
    const auto& tb = b.maps()[m].texels;
    ASSERT_EQ(ta.size(), tb.size());
    for (std::size_t k = 0; k < ta.size(); k += 4, ++total) same += std::equal(&ta[k], &ta[k] + 4, &tb[k]);
  }
  EXPECT_GT(static_cast<double>(same), 0.99 * static_cast<double>(total));
  // And normals point outward either way.
  for (const glm::vec3& p : randomPoints(2000, glm::vec3(-1.1f), glm::vec3(1.1f), 5)) {
    if (std::fabs(glm::length(p) - 1.0f) > 0.05f) continue;
    EXPECT_GT(glm::dot(a.sample(p).normal, glm::normalize(p)), 0.8f);
    EXPECT_GT(glm::dot(b.sample(p).normal, glm::normalize(p)), 0.8f);
  }
}

// The batch query (blocks of points, each map over the block, the texels fetched before the
// votes) must answer exactly like the one-point sample(): same distance and normal bits, same
// validity, for every format, margin rings, a LESS cavity cube, points outside every map, points on
// texel borders and non-finite points, whatever the span length (block edges at 64).
TEST(DepthMap, BatchQueryEqualsPointSamplesBitForBit) {
  const Mesh basin = collide_test::makeBasin(48);
  const fluid::Bounds bounds = fluid::meshBounds(basin.view());
  auto ringed = fluid::defaultMapSpecs(bounds, 64, DepthMapFormat::front_back16);
  for (fluid::MapSpec& s : ringed) s.margin = 0.1f;
  ringed.push_back(collide_test::basinCavityCube(64));
  std::vector<std::pair<const char*, fluid::DepthMapCollider>> colliders;
  for (DepthMapFormat format : kFormats) colliders.emplace_back(fluid::formatName(format), sphereCollider(format, 64));
  colliders.emplace_back("basin, margin rings and a LESS cavity cube", bake(basin, ringed));
  std::vector<glm::vec3> points = randomPoints(3000, glm::vec3(-1.6f), glm::vec3(1.6f), 11);
  // Texel borders of the sphere's maps (a 64-texel map over the padded bounds) and the map volumes' faces.
  for (int k = -70; k <= 70; ++k) points.push_back(glm::vec3(static_cast<float>(k) / 32.0f, 0.25f, -0.5f));
  for (float v : {-1.2f, 1.2f, 0.0f}) points.push_back(glm::vec3(v, v, v));
  points.insert(points.begin() + 63, glm::vec3(NAN, 0.0f, 0.0f));
  points.insert(points.begin() + 64, glm::vec3(0.0f, INFINITY, 0.0f));
  points.push_back(glm::vec3(0.0f, 0.0f, -INFINITY));
  auto same = [](const fluid::ColliderSample& a, const fluid::ColliderSample& b) {
    return a.valid == b.valid && std::memcmp(&a.distance, &b.distance, sizeof(float)) == 0 &&
           std::memcmp(&a.normal, &b.normal, sizeof(glm::vec3)) == 0;
  };
  for (const auto& [name, collider] : colliders) {
    SCOPED_TRACE(name);
    std::size_t inside = 0, outside = 0;
    for (const std::size_t length :
         {std::size_t{1}, std::size_t{2}, std::size_t{63}, std::size_t{64}, std::size_t{65}, points.size()}) {
      std::vector<fluid::ColliderSample> batch(points.size());
      for (std::size_t b = 0; b < points.size(); b += length) {
        const std::size_t count = std::min(length, points.size() - b);
        collider.query(std::span<const glm::vec3>(points).subspan(b, count),
                       std::span<fluid::ColliderSample>(batch).subspan(b, count));
      }
      std::size_t differ = 0;
      for (std::size_t k = 0; k < points.size(); ++k) {
        const fluid::ColliderSample one = collider.sample(points[k]);
        if (!same(batch[k], one) && ++differ <= 3)
          ADD_FAILURE() << "length " << length << " point " << points[k].x << " " << points[k].y << " " << points[k].z
                        << ": batch " << batch[k].distance << " sample " << one.distance;
        if (length == 1) {
          inside += isInside(one);
          outside += one.valid && one.distance >= 0.0f;
        }
      }
      EXPECT_EQ(differ, 0u) << "length " << length;
    }
    // The points reach both sides of the surface (a collider answering nothing would pass above).
    EXPECT_GT(inside, 100u);
    EXPECT_GT(outside, 100u);
  }
}

}  // namespace
