// The SPH step's health counters (fluid::SphStepStats: pushed_out, max_push_depth, speed_clamps,
// dt_held_at_min, nonfinite), which the overlay, the replay CSV and the run summaries show: each
// scene forces exactly one of them and checks that it counts, and that a quiet scene reads zero.
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/sph.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

namespace {

using namespace fluid;

// A 2x2x2 lattice of particles (d = 5 cm) in free fall, no colliders.
SphWorld smallBlock(glm::vec3 velocity) {
  SphWorld w;
  w.params.particle_radius = 0.025f;
  const float d = sphSpacing(w.params);
  addSphBlock(w, glm::vec3(0.0f), glm::vec3(2.0f * d), velocity);
  return w;
}

TEST(SphHealthCounters, SpeedClampCountsEachClampedParticle) {
  SphWorld w = smallBlock(glm::vec3(3.0f, 0.0f, 0.0f));
  ASSERT_EQ(w.particles.size(), 8u);
  w.params.max_speed = 1.0f;
  SphStepStats stats;
  ASSERT_TRUE(stepSph(w, 0.001f, &stats).ok());
  EXPECT_EQ(stats.speed_clamps, 8u);
  for (const glm::vec3& v : w.particles.velocity) EXPECT_LE(glm::length(v), 1.0f + 1e-5f);

  SphWorld free_block = smallBlock(glm::vec3(3.0f, 0.0f, 0.0f));  // no cap: nothing clamped
  ASSERT_TRUE(stepSph(free_block, 0.001f, &stats).ok());
  EXPECT_EQ(stats.speed_clamps, 0u);
  EXPECT_FALSE(stats.dt_held_at_min);
  EXPECT_EQ(stats.pushed_out, 0u);
  EXPECT_EQ(stats.nonfinite, 0u);
}

TEST(SphHealthCounters, MinTimeStepClampIsReported) {
  // At 10 m/s the CFL bound is 0.4 * 0.05 / 10 = 2 ms; min_time_step 4 ms holds the step above it.
  SphWorld w = smallBlock(glm::vec3(10.0f, 0.0f, 0.0f));
  w.params.force_bound = 0.0f;
  w.params.min_time_step = 0.004f;
  SphStepStats stats;
  ASSERT_TRUE(stepSph(w, 0.0f, &stats).ok());
  EXPECT_TRUE(stats.dt_held_at_min);
  EXPECT_FLOAT_EQ(stats.dt, 0.004f);

  SphWorld slow = smallBlock(glm::vec3(0.1f, 0.0f, 0.0f));  // CFL 0.2 s: the 5 ms cap binds, not the floor
  slow.params.force_bound = 0.0f;
  slow.params.min_time_step = 0.004f;
  ASSERT_TRUE(stepSph(slow, 0.0f, &stats).ok());
  EXPECT_FALSE(stats.dt_held_at_min);
  EXPECT_FLOAT_EQ(stats.dt, slow.params.max_time_step);
}

TEST(SphHealthCounters, ParticlesPushedOutOfAColliderAreCountedOnceWithTheirDepth) {
  SphWorld w;
  SphCollider floor;
  floor.shape = std::make_shared<PlaneShape>(glm::vec3(0.0f, 1.0f, 0.0f), 0.0f);
  floor.integrate_pose = false;
  floor.boundary_pressure = false;  // collision only: nothing holds the particles off the floor
  floor.material.resilience = 0.0f;
  w.colliders = {floor};
  // Two particles 1 cm above the floor falling at 5 m/s: a 4 ms step ends them 1 cm inside.
  // A third one high above it stays clear.
  addSphParticle(w, glm::vec3(0.0f, 0.01f, 0.0f), glm::vec3(0.0f, -5.0f, 0.0f));
  addSphParticle(w, glm::vec3(0.5f, 0.01f, 0.0f), glm::vec3(0.0f, -5.0f, 0.0f));
  addSphParticle(w, glm::vec3(0.0f, 1.0f, 0.0f));
  w.params.cfl = 1.0f;
  w.params.force_bound = 0.0f;
  w.params.viscosity = 0.0f;
  SphStepStats stats;
  ASSERT_TRUE(stepSph(w, 0.004f, &stats).ok());
  ASSERT_FLOAT_EQ(stats.dt, 0.004f);
  EXPECT_EQ(stats.pushed_out, 2u);
  EXPECT_GE(stats.collisions, 2u);
  // Both ended about 1 cm (plus the gravity drop) inside before the push-out.
  EXPECT_GT(stats.max_push_depth, 0.009f);
  EXPECT_LT(stats.max_push_depth, 0.012f);
  for (const glm::vec3& x : w.particles.position) EXPECT_GE(x.y, 0.0f);

  // The next step starts on the floor at rest along y: gravity alone brings them at most a skin
  // inside, far below the warning depth of a particle radius.
  ASSERT_TRUE(stepSph(w, 0.004f, &stats).ok());
  EXPECT_LT(stats.max_push_depth, 0.25f * w.params.particle_radius);
}

TEST(SphHealthCounters, AParticlePushedByTwoCollidersCountsOnce) {
  // A corner: floor y = 0 and wall x = 0; the particle ends about 1 cm inside both.
  SphWorld w;
  for (const glm::vec3 normal : {glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f)}) {
    SphCollider c;
    c.shape = std::make_shared<PlaneShape>(normal, 0.0f);
    c.integrate_pose = false;
    c.boundary_pressure = false;
    c.material.resilience = 0.0f;
    w.colliders.push_back(c);
  }
  addSphParticle(w, glm::vec3(0.01f, 0.01f, 0.0f), glm::vec3(-5.0f, -5.0f, 0.0f));
  w.params.cfl = 1.0f;
  w.params.force_bound = 0.0f;
  w.params.viscosity = 0.0f;
  SphStepStats stats;
  ASSERT_TRUE(stepSph(w, 0.004f, &stats).ok());
  EXPECT_GE(stats.collisions, 2u);  // one reaction per collider
  EXPECT_EQ(stats.pushed_out, 1u);  // one particle
  EXPECT_GE(w.particles.position[0].x, 0.0f);
  EXPECT_GE(w.particles.position[0].y, 0.0f);
}

TEST(SphHealthCounters, NonFiniteParticleIsCountedAndTheStepRefused) {
  SphWorld w = smallBlock(glm::vec3(0.0f));
  ASSERT_TRUE(stepSph(w, 0.001f).ok());
  const std::uint64_t steps = w.step_count;
  w.particles.velocity[3].y = std::numeric_limits<float>::quiet_NaN();
  w.particles.position[5].x = std::numeric_limits<float>::infinity();
  SphStepStats stats;
  stats.dt = 1.0f;
  const SphStatus status = stepSph(w, 0.001f, &stats);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.error.find("non-finite"), std::string::npos) << status.error;
  EXPECT_EQ(stats.nonfinite, 2u);
  EXPECT_EQ(stats.dt, 0.0f);
  EXPECT_EQ(w.step_count, steps);  // refused: nothing advanced

  // advanceSph hands the refused step's count to its callback before returning the error.
  SphStepTotals totals;
  const SphStatus advanced = advanceSph(w, 0.01, [&](const SphStepStats& s) { addStepTotals(totals, s); });
  EXPECT_FALSE(advanced.ok());
  EXPECT_EQ(totals.nonfinite, 2u);
  EXPECT_EQ(totals.steps, 0u);
  EXPECT_TRUE(sphTotalsWarn(totals, 1.0f));
}

TEST(SphHealthCounters, TotalsSumStepsAndWarnOnlyOnClampsNonFiniteOrDeepPushes) {
  SphStepStats a, b;
  a.dt = b.dt = 0.001f;
  a.avg_density_error = 0.001f;
  b.avg_density_error = 0.003f;
  a.max_density_error = 0.02f;
  b.max_density_error = 0.01f;
  a.pushed_out = 3;
  a.max_push_depth = 0.002f;
  b.dt_limited_by_request = true;
  a.density_iterations = 3;
  a.divergence_iterations = 1;
  b.density_iterations = 2;
  SphStepTotals t;
  addStepTotals(t, a);
  addStepTotals(t, b);
  EXPECT_EQ(t.steps, 2u);
  EXPECT_NEAR(t.meanDensityError(), 0.002f, 1e-7f);
  EXPECT_FLOAT_EQ(t.max_density_error, 0.02f);
  EXPECT_EQ(t.pushed_out, 3u);
  EXPECT_EQ(t.dt_request_cuts, 1u);
  EXPECT_EQ(t.solver_iterations, 6u) << "both solvers' iterations over both steps";
  // Shallow pushes and request cuts are not warnings.
  EXPECT_FALSE(sphTotalsWarn(t, 0.025f));
  EXPECT_TRUE(sphTotalsWarn(t, 0.001f));  // 2 mm deep against a 1 mm threshold
  for (int which = 0; which < 3; ++which) {
    SphStepStats c;
    c.dt = 0.001f;
    if (which == 0) c.speed_clamps = 1;
    if (which == 1) c.dt_held_at_min = true;
    if (which == 2) c.nonfinite = 1;
    SphStepTotals u = t;
    addStepTotals(u, c);
    EXPECT_TRUE(sphTotalsWarn(u, 0.025f)) << which;
    SphStepTotals sum;
    addStepTotals(sum, u);  // totals of totals keep it
    EXPECT_TRUE(sphTotalsWarn(sum, 0.025f)) << which;
    EXPECT_EQ(sum.steps, 3u);
    EXPECT_EQ(sum.solver_iterations, 6u);
  }
}

}  // namespace
