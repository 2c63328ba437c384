// Solver behaviour on the measurement scenes: a column at rest, hydrostatic pressure, the dam
// break's energy and containment, two-way coupling forces, determinism and thread invariance,
// and no allocation per step after warm-up.
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <numeric>
#include <span>

// Counting global allocator for the no-allocation test (test binary only). GCC cannot see that
// these new/delete replacements pair malloc with free and warns at inlined call sites.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace {
std::atomic<long> g_allocations{0};
}
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using namespace fluid;

using Overrides = std::vector<std::pair<std::string, std::string>>;

SphScene scene(const std::string& name, SphSolverKind solver, const Overrides& o) {
  SphScene s;
  const SphStatus st = makeSphScene(name, solver, o, s);
  EXPECT_TRUE(st.ok()) << st.error;
  return s;
}

float maxSpeed(const SphWorld& w) {
  float v = 0.0f;
  for (const glm::vec3& x : w.particles.velocity) v = std::max(v, glm::length(x));
  return v;
}

bool allInside(const SphScene& s, float tol) {
  for (const glm::vec3& p : s.world.particles.position)
    for (int a = 0; a < 3; ++a)
      if (!(p[a] >= s.box_min[a] - tol && p[a] <= s.box_max[a] + tol)) return false;
  return true;
}

const Overrides kSmallColumn{{"width", "0.06"}, {"height", "0.12"}, {"depth", "0.06"}, {"spacing", "0.01"}};

void columnStaysAtRest(SphSolverKind solver, float max_error) {
  SphScene s = scene("column", solver, kSmallColumn);
  ASSERT_EQ(s.world.particles.size(), 6u * 12u * 6u);
  SphStatus st = advanceSph(s.world, 1.75, [](const SphStepStats&) {});
  ASSERT_TRUE(st.ok()) << st.error;
  // Hydrostatic pressure: mean pressure per layer, averaged over the last 0.25 s (DFSPH's pressure
  // is a per-step impulse and fluctuates from step to step), grows linearly with depth.
  const float d = 0.01f, top = 0.12f;
  std::vector<double> depth_sum(12, 0.0), p_sum(12, 0.0), count(12, 0.0);
  st = advanceSph(s.world, 0.25, [&](const SphStepStats&) {
    for (std::size_t i = 0; i < s.world.particles.size(); ++i) {
      const float depth = top - s.world.particles.position[i].y;
      const int layer = std::clamp(static_cast<int>(depth / d), 0, 11);
      depth_sum[layer] += depth;
      p_sum[layer] += s.world.particles.pressure[i];
      count[layer] += 1.0;
    }
  });
  ASSERT_TRUE(st.ok()) << st.error;
  float mean = 0, max = 0;
  sphDensityError(s.world, mean, max);
  EXPECT_LT(mean, max_error) << sphSolverName(solver);
  EXPECT_LT(maxSpeed(s.world), 0.1f) << sphSolverName(solver);  // at rest: below 0.1 m/s
  EXPECT_TRUE(allInside(s, 1e-5f));
  // Least squares over the layers below the top two (the surface layer has p ~ 0 by the clamp).
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, k = 0;
  for (int l = 2; l < 11; ++l) {
    if (count[l] == 0) continue;
    const double x = depth_sum[l] / count[l], y = p_sum[l] / count[l];
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
    k += 1;
  }
  const double slope = (k * sxy - sx * sy) / (k * sxx - sx * sx);
  const double r = (k * sxy - sx * sy) / std::sqrt((k * sxx - sx * sx) * (k * syy - sy * sy));
  EXPECT_GT(r, 0.97) << "pressure not linear in depth, " << sphSolverName(solver);
  EXPECT_NEAR(slope, 1000.0 * 9.81, 0.35 * 1000.0 * 9.81) << sphSolverName(solver);
}

TEST(SphSolvers, ColumnAtRestDfsph) { columnStaysAtRest(SphSolverKind::dfsph, 0.01f); }
TEST(SphSolvers, ColumnAtRestWcsph) { columnStaysAtRest(SphSolverKind::wcsph, 0.03f); }

void damBreakStaysSane(SphSolverKind solver, const Overrides& o, double seconds) {
  SphScene s = scene("dambreak", solver, o);
  const double pe0 = sphPotentialEnergy(s.world);
  double worst = -1e30;
  std::size_t steps = 0;
  SphStatus st = advanceSph(s.world, seconds, [&](const SphStepStats& stats) {
    ++steps;
    const double released = pe0 - sphPotentialEnergy(s.world);
    worst = std::max(worst, stats.kinetic_energy - released);
  });
  ASSERT_TRUE(st.ok()) << st.error;
  EXPECT_GT(steps, 10u);
  // Kinetic energy never exceeds the potential energy released (1 % of the initial PE slack for
  // the discrete energy bookkeeping).
  EXPECT_LT(worst, 0.01 * pe0) << sphSolverName(solver);
  EXPECT_TRUE(allInside(s, 1e-5f)) << sphSolverName(solver);
  for (const glm::vec3& p : s.world.particles.position) ASSERT_TRUE(std::isfinite(p.x + p.y + p.z));
  EXPECT_GT(sphSurgeFront(s.world), 0.1f * 3.0f);  // the water has left the column
}

TEST(SphSolvers, DamBreakThreeSecondsDfsph) {
  damBreakStaysSane(SphSolverKind::dfsph, {{"width", "0.1"}, {"spacing", "0.01"}}, 3.0);
}
TEST(SphSolvers, DamBreakThreeSecondsWcsph) {
  damBreakStaysSane(SphSolverKind::wcsph, {{"width", "0.1"}, {"spacing", "0.02"}}, 3.0);
}

TEST(SphSolvers, FloorCarriesTheWeight) {
  // Two-way coupling: once the column has settled, the floor collider feels the fluid's weight.
  SphScene s = scene("column", SphSolverKind::dfsph, kSmallColumn);
  ASSERT_TRUE(advanceSph(s.world, 1.0, [](const SphStepStats&) {}).ok());
  ASSERT_TRUE(advanceSph(s.world, 0.2, [](const SphStepStats&) {}).ok());  // force = average over 0.2 s
  const double weight = s.world.particles.size() * sphParticleMass(s.world.params) * 9.81;
  // Collider 2 is the floor (normal +y): it is pushed down by about the weight.
  const SphCollider& floor = s.world.colliders[2];
  EXPECT_NEAR(-floor.force.y, weight, 0.15 * weight);
  EXPECT_LT(std::abs(floor.force.x) + std::abs(floor.force.z), 0.05 * weight);
  // Side walls feel equal and opposite pushes.
  EXPECT_NEAR(s.world.colliders[0].force.x, -s.world.colliders[1].force.x,
              0.05 * weight + 0.2 * std::abs(s.world.colliders[0].force.x));
  EXPECT_LT(s.world.colliders[0].force.x, 0.0f);  // the x = 0 wall is pushed towards -x
}

struct Snapshot {
  std::vector<glm::vec3> x, v;
  std::vector<std::uint32_t> id;
};
Snapshot run(SphSolverKind solver, int threads, int steps, const std::string& name = "dambreak",
             const Overrides& o = {{"width", "0.1"}, {"spacing", "0.01"}}) {
  Snapshot out;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    SphScene s = scene(name, solver, o);
    for (int i = 0; i < steps; ++i) EXPECT_TRUE(stepSph(s.world, 0.0f).ok());
    out.x = s.world.particles.position;
    out.v = s.world.particles.velocity;
    out.id = s.world.particles.id;
  });
  return out;
}

TEST(SphSolvers, BitIdenticalForOneAndManyThreads) {
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    const Snapshot a = run(solver, 1, 60), b = run(solver, 4, 60), c = run(solver, 3, 60);
    ASSERT_EQ(a.id, b.id);
    ASSERT_EQ(a.id, c.id);
    EXPECT_EQ(0, std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(glm::vec3))) << sphSolverName(solver);
    EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(glm::vec3))) << sphSolverName(solver);
    EXPECT_EQ(0, std::memcmp(a.x.data(), c.x.data(), a.x.size() * sizeof(glm::vec3))) << sphSolverName(solver);
  }
}

// The eight-lane pair loops run as AVX2 code where the CPU has it and as a portable loop
// elsewhere; both must give the same bits (same IEEE operations in the same order). Covers a
// dam break (full and partial lane blocks, walls) and particles stacked on one point (the
// coincident-pair path), with viscosity on.
Snapshot runPairLoops(bool portable, SphScene s, int steps) {
  s.world.scratch.portable_pair_loops = portable;
  for (int i = 0; i < steps; ++i) EXPECT_TRUE(stepSph(s.world, 0.0f).ok());
  return {s.world.particles.position, s.world.particles.velocity, s.world.particles.id};
}

TEST(SphSolvers, PortableAndSimdPairLoopsAreBitIdentical) {
  const SphScene dam = scene("dambreak", SphSolverKind::dfsph, {{"width", "0.1"}, {"spacing", "0.01"}});
  SphScene stacked = scene("dambreak", SphSolverKind::dfsph, {{"width", "0.1"}, {"spacing", "0.01"}});
  for (int i = 0; i < 40; ++i) addSphParticle(stacked.world, glm::vec3(0.3f, 0.05f, 0.05f));
  for (const SphScene* s : std::initializer_list<const SphScene*>{&dam, &stacked}) {
    ASSERT_GT(s->world.params.viscosity, 0.0f);
    const Snapshot a = runPairLoops(true, *s, 40), b = runPairLoops(false, *s, 40);
    ASSERT_EQ(a.id, b.id);
    EXPECT_EQ(0, std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(glm::vec3)));
    EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(glm::vec3)));
    // The runs did move the fluid (a comparison of two untouched states would prove nothing).
    float moved = 0.0f;
    for (std::size_t i = 0; i < a.x.size(); ++i)
      moved = std::max(moved, std::abs(a.x[i].y - s->world.particles.position[a.id[i]].y));  // ids = start indices
    EXPECT_GT(moved, 0.005f);
  }
}

// SphCollider::lipschitz_distance lets the end-of-step collision check skip particles whose step
// stayed outside a static collider. The dam break's walls are planes (exact distances, no normal
// flips), so the result must be bit-identical with and without the flag while the walls are
// asked about far fewer points.
class CountingShape final : public SignedDistanceShape {
 public:
  CountingShape(std::shared_ptr<const SignedDistanceShape> inner, std::atomic<long>* points)
      : inner_(std::move(inner)), points_(points) {}
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override {
    points_->fetch_add(static_cast<long>(local_points.size()), std::memory_order_relaxed);
    inner_->query(local_points, out);
  }

 private:
  std::shared_ptr<const SignedDistanceShape> inner_;
  std::atomic<long>* points_;
};

TEST(SphSolvers, LipschitzQuerySkipsKeepResultsBitIdentical) {
  Snapshot out[2];
  long points[2] = {0, 0};
  for (int flag = 0; flag < 2; ++flag) {
    std::atomic<long> count{0};
    SphScene s = scene("dambreak", SphSolverKind::dfsph, {{"width", "0.1"}, {"spacing", "0.01"}});
    ASSERT_GE(s.world.colliders.size(), 2u);  // several walls: the multi-collider passes run too
    std::vector<std::shared_ptr<const SignedDistanceShape>> inner;
    for (SphCollider& c : s.world.colliders) {
      inner.push_back(c.shape);
      c.lipschitz_distance = flag == 1;
    }
    for (int i = 0; i < 80; ++i) {
      // A new shape object every step: nothing is carried from one step to the next
      // (SphScratch::SampleCarry), so the counts compare the end-of-step queries alone.
      for (std::size_t c = 0; c < inner.size(); ++c)
        s.world.colliders[c].shape = std::make_shared<CountingShape>(inner[c], &count);
      ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
    }
    out[flag] = {s.world.particles.position, s.world.particles.velocity, s.world.particles.id};
    points[flag] = count.load();
  }
  ASSERT_EQ(out[0].id, out[1].id);
  EXPECT_EQ(0, std::memcmp(out[0].x.data(), out[1].x.data(), out[0].x.size() * sizeof(glm::vec3)));
  EXPECT_EQ(0, std::memcmp(out[0].v.data(), out[1].v.data(), out[0].v.size() * sizeof(glm::vec3)));
  // Every step queries each wall once at the start; the end-of-step queries are mostly skipped.
  EXPECT_LT(points[1], points[0] * 3 / 4) << points[0] << " vs " << points[1];
  // The column did collapse (identical untouched states would prove nothing).
  float fastest = 0.0f;
  for (const glm::vec3& v : out[1].v) fastest = std::max(fastest, glm::length(v));
  EXPECT_GT(fastest, 0.2f);
}

// The next step's boundary sampling reuses the last collision pass's samples where the collider
// (shape object, pose) and the particle's position are bit-for-bit the ones queried
// (SphScratch::SampleCarry). The reference run wraps every collider in a new shape object before
// each step, so nothing is carried and every sample is queried afresh; both runs must give the
// same bits, through emitters, a sink and the re-sort (indices change every step), a collider
// that moves, and positions written between steps (two particles swapped, one put inside a wall:
// a carried sample is only valid at its own position).
TEST(SphSolvers, CarriedColliderSamplesKeepResultsBitIdentical) {
  const Overrides o{{"spacing", "0.04"},   {"budget", "500"},      {"rate", "3000"},
                    {"basin_size", "0.5"}, {"drain_size", "0.25"}, {"nozzle_radius", "0.1"}};
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    Snapshot out[2];
    long points[2] = {0, 0};
    std::size_t removed = 0;
    for (int fresh = 0; fresh < 2; ++fresh) {
      std::atomic<long> count{0};
      SphScene s = scene("fountain", solver, o);
      ASSERT_GE(s.world.colliders.size(), 2u);
      std::vector<std::shared_ptr<const SignedDistanceShape>> inner;
      for (SphCollider& c : s.world.colliders) {
        inner.push_back(c.shape);
        c.shape = std::make_shared<CountingShape>(c.shape, &count);
        c.lipschitz_distance = false;  // every particle is queried at the end of a step (as for depth maps)
      }
      // The +z wall slides slowly outwards: its pose changes every step (never carried).
      SphCollider& moving = s.world.colliders.back();
      ASSERT_EQ(dynamic_cast<const PlaneShape&>(*inner.back()).normal(), glm::vec3(0.0f, 0.0f, -1.0f));
      moving.integrate_pose = true;
      moving.pose.linear_velocity = glm::vec3(0.0f, 0.0f, 0.05f);
      bool moved_by_hand = false;
      while (s.world.time < 1.0) {
        if (fresh)
          for (std::size_t c = 0; c < inner.size(); ++c)
            s.world.colliders[c].shape = std::make_shared<CountingShape>(inner[c], &count);
        if (!moved_by_hand && s.world.time >= 0.7) {
          moved_by_hand = true;
          std::vector<glm::vec3>& x = s.world.particles.position;
          ASSERT_GT(x.size(), 20u);
          std::swap(x[3], x[x.size() - 4]);
          x[10] = glm::vec3(x[10].x, -0.01f, x[10].z);  // into the floor: the step must push it out
        }
        SphStepStats st;
        ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
        if (fresh == 0) removed += st.removed;
      }
      out[fresh] = {s.world.particles.position, s.world.particles.velocity, s.world.particles.id};
      points[fresh] = count.load();
    }
    ASSERT_EQ(out[0].id, out[1].id) << sphSolverName(solver);
    EXPECT_EQ(0, std::memcmp(out[0].x.data(), out[1].x.data(), out[0].x.size() * sizeof(glm::vec3)))
        << sphSolverName(solver);
    EXPECT_EQ(0, std::memcmp(out[0].v.data(), out[1].v.data(), out[0].v.size() * sizeof(glm::vec3)))
        << sphSolverName(solver);
    EXPECT_GT(out[0].id.size(), 100u);  // the jet filled the basin
    EXPECT_GT(removed, 0u);             // and the sink drained some of it
    // The start-of-step queries of the still walls were carried: fewer points asked for.
    EXPECT_LT(points[0], points[1] * 3 / 4) << sphSolverName(solver) << ": " << points[0] << " vs " << points[1];
  }
}

TEST(SphSolvers, EmittersAndSinksAreThreadCountInvariant) {
  const Overrides o{
      {"spacing", "0.04"}, {"budget", "400"}, {"rate", "3000"}, {"basin_size", "0.4"}, {"drain_size", "0.2"}};
  const Snapshot a = run(SphSolverKind::dfsph, 1, 250, "fountain", o),
                 b = run(SphSolverKind::dfsph, 4, 250, "fountain", o);
  ASSERT_GT(a.id.size(), 50u);
  ASSERT_EQ(a.id, b.id);
  EXPECT_EQ(0, std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(glm::vec3)));
  EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(glm::vec3)));
}

TEST(SphSolvers, NoAllocationPerStepAfterWarmUp) {
#if defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "TSan builds run the parallel loops on std::threads (fluid/core/parallel.hpp), which allocate "
                  "their thread state per loop; the oneTBB path checked here is the one every other build runs";
#endif
  for (SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    SphScene s = scene("dambreak", solver, {{"width", "0.1"}, {"spacing", "0.01"}});
    reserveSph(s.world, s.world.particles.size());
    tbb::task_arena arena(1);  // TBB's own task pools are warmed up by the first steps too
    arena.execute([&] {
      for (int i = 0; i < 30; ++i) ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
      const long before = g_allocations.load();
      for (int i = 0; i < 20; ++i) ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
      EXPECT_EQ(g_allocations.load() - before, 0) << sphSolverName(solver);
    });
  }
}

// DFSPH's pair arrays in lane blocks (fluid/sph/pair_loops.hpp): i's pairs start at a multiple of
// 8 (pair_start[i]) of 32-byte aligned views of grad_x/y/z and pair_offset, and the slots after
// its last pair up to the next block hold zero gradients and neighbour 0 (what the AVX2 loops add
// as exact zeros). Dam break with stacked particles: lists of many lengths, coincident pairs.
TEST(SphSolvers, DfsphPairBlocksAreAlignedAndZeroPadded) {
  SphScene s = scene("dambreak", SphSolverKind::dfsph, {{"width", "0.1"}, {"spacing", "0.01"}});
  for (int i = 0; i < 13; ++i) addSphParticle(s.world, glm::vec3(0.03f, 0.05f, 0.05f));
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
  const SphScratch& w = s.world.scratch;
  const std::size_t n = s.world.particles.size();
  ASSERT_EQ(w.pair_start.size(), n + 1);
  // The views start at the first 32-byte aligned element of each array.
  auto view = [](const auto& v) {
    const auto address = reinterpret_cast<std::uintptr_t>(v.data());
    return v.data() + ((32 - address % 32) % 32) / sizeof(v[0]);
  };
  const float *gx = view(w.grad_x), *gy = view(w.grad_y), *gz = view(w.grad_z);
  const std::uint32_t* nb16 = view(w.pair_offset);
  ASSERT_LE(static_cast<std::size_t>(gx - w.grad_x.data()) + w.pair_start[n], w.grad_x.size());
  std::size_t padded = 0, pairs = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t b = w.pair_start[i], e = w.pair_start[i + 1], count = w.neighbors.counts[i];
    ASSERT_EQ(b % 8, 0u) << i;
    ASSERT_EQ(e - b, (count + 7) / 8 * 8) << i;
    for (std::uint32_t k = b; k < b + count; ++k)
      ASSERT_EQ(nb16[k], w.neighbors.indices[w.neighbors.offsets[i] + (k - b)] << 4) << i;
    for (std::uint32_t k = b + count; k < e; ++k) {
      ASSERT_EQ(nb16[k], 0u) << i;
      ASSERT_TRUE(gx[k] == 0.0f && gy[k] == 0.0f && gz[k] == 0.0f) << i;
      ++padded;
    }
    pairs += count;
  }
  EXPECT_GT(padded, 0u);  // the layout was exercised: some lists are not whole blocks
  EXPECT_GT(pairs, 20 * n);
}

TEST(SphSolvers, FountainEmitsDrainsAndRespectsBudget) {
  SphScene s =
      scene("fountain", SphSolverKind::dfsph,
            {{"spacing", "0.04"}, {"budget", "600"}, {"rate", "2000"}, {"basin_size", "0.6"}, {"drain_size", "0.3"}});
  std::size_t emitted = 0, removed = 0, peak = 0;
  ASSERT_TRUE(advanceSph(s.world, 1.5, [&](const SphStepStats& st) {
                emitted += st.emitted;
                removed += st.removed;
                peak = std::max(peak, st.particles);
              }).ok());
  EXPECT_GT(emitted, 100u);
  EXPECT_LE(peak, 600u);
  EXPECT_GT(removed, 0u);  // the drain took some water
  EXPECT_EQ(s.world.particles.size(), emitted - removed);
  // Ids stay unique.
  std::vector<std::uint32_t> ids = s.world.particles.id;
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(std::adjacent_find(ids.begin(), ids.end()), ids.end());
}

TEST(SphScenes, UnknownKeysAndBadValuesAreErrors) {
  SphScene s;
  SphStatus st = makeSphScene("dambreak", SphSolverKind::dfsph, {{"colour", "blue"}}, s);
  EXPECT_NE(st.error.find("unknown key 'colour'"), std::string::npos) << st.error;
  st = makeSphScene("dambreak", SphSolverKind::dfsph, {{"width", "abc"}}, s);
  EXPECT_NE(st.error.find("'abc'"), std::string::npos) << st.error;
  st = makeSphScene("dambreak", SphSolverKind::dfsph, {{"width", "nan"}}, s);
  EXPECT_FALSE(st.ok());
  st = makeSphScene("dambreak", SphSolverKind::dfsph, {{"cfl", "7"}}, s);
  EXPECT_NE(st.error.find("out of range"), std::string::npos) << st.error;
  st = makeSphScene("lake", SphSolverKind::dfsph, {}, s);
  EXPECT_NE(st.error.find("unknown scene"), std::string::npos) << st.error;
  // The box scene reproduces SPlisHSPlasH's particle count.
  ASSERT_TRUE(makeSphScene("dambreak_box", SphSolverKind::dfsph, {}, s).ok());
  EXPECT_EQ(s.world.particles.size(), 24389u);
}

}  // namespace

namespace {

TEST(SphSolvers, WcsphVerletListsEqualAFreshSearch) {
  // WCSPH reuses a Verlet list over several steps; every step's exact lists must still hold
  // exactly the pairs within the support at the step-start positions (kept in old_position).
  SphScene s = scene("dambreak", SphSolverKind::wcsph, {{"width", "0.1"}, {"spacing", "0.01"}});
  const float H = sphSupport(s.world.params);
  std::size_t checked = 0;
  for (int step = 0; step < 40; ++step) {
    ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
    if (step % 7 != 6) continue;
    const auto& x = s.world.scratch.old_position;
    const auto& nb = s.world.scratch.neighbors;
    // Layout of the step's exact lists (sph.hpp, SphScratch::neighbors): i's neighbours are
    // indices[offsets[i] .. offsets[i] + counts[i]) inside its Verlet range.
    ASSERT_EQ(nb.offsets.size(), x.size() + 1);
    ASSERT_EQ(nb.counts.size(), x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      std::vector<std::uint32_t> expected;
      for (std::size_t j = 0; j < x.size(); ++j) {
        const glm::vec3 d = x[i] - x[j];
        if (j != i && glm::dot(d, d) < H * H) expected.push_back(static_cast<std::uint32_t>(j));
      }
      ASSERT_LE(nb.offsets[i] + nb.counts[i], nb.offsets[i + 1]);
      std::vector<std::uint32_t> got(nb.indices.begin() + nb.offsets[i],
                                     nb.indices.begin() + nb.offsets[i] + nb.counts[i]);
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, expected) << "step " << step << " particle " << i;
      checked += expected.size();
    }
  }
  EXPECT_GT(checked, 1000u);
}

}  // namespace
