// Step control (advanceSph): the output rate must not change the physics. A column of water at
// rest in a box that fits it is advanced in calls of 1/F seconds (as `fluiddemo simulate --fps F`
// and the game's fixed step do) and must stay still for every F; the step sequence must not
// depend on how time is split into calls; a frame's state is shown at its own time.
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace {

using namespace fluid;

using Overrides = std::vector<std::pair<std::string, std::string>>;

// 6 x 12 x 6 particles at d = 1 cm: h = 0.12 m.
const Overrides kColumn{{"width", "0.06"}, {"height", "0.12"}, {"depth", "0.06"}, {"spacing", "0.01"}};
constexpr double kHeight = 0.12;

SphScene column(SphSolverKind solver) {
  SphScene s;
  const SphStatus st = makeSphScene("column", solver, kColumn, s);
  EXPECT_TRUE(st.ok()) << st.error;
  return s;
}

double fluidMass(const SphWorld& w) {
  return static_cast<double>(w.particles.size()) * static_cast<double>(sphParticleMass(w.params));
}

// Time-weighted mean of sqrt(2 KE / M) over the steps that end in (1 s, 1.5 s], advancing in calls
// of 1/fps s.
double restingSpeed(SphSolverKind solver, int fps) {
  SphScene s = column(solver);
  const double mass = fluidMass(s.world);
  double sum = 0.0, time = 0.0;
  for (int frame = 0; frame < (3 * fps + 1) / 2; ++frame) {
    const SphStatus st = advanceSph(s.world, 1.0 / fps, [&](const SphStepStats& stats) {
      if (s.world.time <= 1.0 || s.world.time > 1.5) return;
      sum += std::sqrt(2.0 * stats.kinetic_energy / mass) * stats.dt;
      time += stats.dt;
    });
    EXPECT_TRUE(st.ok()) << st.error;
    if (!st.ok()) return NAN;
  }
  return time > 0.0 ? sum / time : NAN;
}

void columnStaysStillAtEveryFrameRate(SphSolverKind solver) {
  const double bound = 0.01 * std::sqrt(9.81 * kHeight);  // 1 % of the shallow-water wave speed
  const double at1 = restingSpeed(solver, 1);
  for (const int fps : {1, 10, 30, 60}) {
    const double v = fps == 1 ? at1 : restingSpeed(solver, fps);
    std::printf("[ metric ] %s column at rest, %d calls per second: v_rms %.3f mm/s (bound %.3f)\n",
                sphSolverName(solver), fps, 1e3 * v, 1e3 * bound);
    EXPECT_LT(v, bound) << sphSolverName(solver) << " at " << fps << " calls per second";
    EXPECT_NEAR(v, at1, 0.1 * at1) << sphSolverName(solver) << " at " << fps << " vs 1 call per second";
  }
}

TEST(SphStepControl, ColumnAtRestStaysStillAtEveryFrameRateDfsph) {
  columnStaysStillAtEveryFrameRate(SphSolverKind::dfsph);
}
TEST(SphStepControl, ColumnAtRestStaysStillAtEveryFrameRateWcsph) {
  columnStaysStillAtEveryFrameRate(SphSolverKind::wcsph);
}

// The world takes the same steps whether it is advanced in one call or in many short ones: the
// state after the same number of steps is bit-identical, and no step is shorter than the solver's
// own choice (here the force bound: every step has the same length).
TEST(SphStepControl, StepsDoNotDependOnHowTimeIsSplitIntoCalls) {
  for (const SphSolverKind solver : {SphSolverKind::dfsph, SphSolverKind::wcsph}) {
    SphScene one = column(solver), many = column(solver);
    float shortest = 1e30f, longest = 0.0f;
    ASSERT_TRUE(advanceSph(one.world, 0.3, [](const SphStepStats&) {}).ok());
    for (int call = 0; call < 30; ++call)
      ASSERT_TRUE(advanceSph(many.world, 0.01, [&](const SphStepStats& st) {
                    shortest = std::min(shortest, st.dt);
                    longest = std::max(longest, st.dt);
                  }).ok());
    // Both have passed 0.3 s by less than one step.
    EXPECT_GE(one.world.time, 0.3 - 1e-7);
    EXPECT_LT(one.world.time - one.world.last_dt, 0.3);
    EXPECT_NEAR(one.world.lead, one.world.time - 0.3, 1e-9);
    ASSERT_EQ(one.world.step_count, many.world.step_count) << sphSolverName(solver);
    EXPECT_EQ(one.world.time, many.world.time);
    EXPECT_TRUE(one.world.particles.position == many.world.particles.position) << sphSolverName(solver);
    EXPECT_TRUE(one.world.particles.velocity == many.world.particles.velocity) << sphSolverName(solver);
    EXPECT_GE(shortest, 0.5f * longest) << sphSolverName(solver) << ": a step was cut short";
  }
}

// A call shorter than the world's lead takes no step; the next one makes up for it.
TEST(SphStepControl, ShortCallsAccumulate) {
  SphScene s = column(SphSolverKind::dfsph);
  ASSERT_TRUE(advanceSph(s.world, 0.0105, [](const SphStepStats&) {}).ok());
  const std::uint64_t steps = s.world.step_count;
  const double lead = s.world.lead;
  ASSERT_GT(lead, 1e-6);
  std::size_t taken = 0;
  ASSERT_TRUE(advanceSph(s.world, 0.5 * lead, [&](const SphStepStats&) { ++taken; }).ok());
  EXPECT_EQ(taken, 0u);
  EXPECT_EQ(s.world.step_count, steps);
  EXPECT_NEAR(s.world.lead, 0.5 * lead, 1e-12);
  // The caller's clock is now 0.0105 + lead / 2; this call brings it to 0.0305.
  ASSERT_TRUE(advanceSph(s.world, 0.02 - 0.5 * lead, [](const SphStepStats&) {}).ok());
  EXPECT_GE(s.world.time, 0.0305 - 1e-7);
  EXPECT_LT(s.world.time - s.world.last_dt, 0.0305);
}

// sphPositionsAt gives the last step's start and end positions at its ends and the straight path
// between them inside it.
TEST(SphStepControl, PositionsAtInterpolateWithinTheLastStep) {
  SphScene s = column(SphSolverKind::dfsph);
  std::vector<glm::vec3> out;
  sphPositionsAt(s.world, 0.0, out);  // no step yet: the current positions
  EXPECT_TRUE(out == s.world.particles.position);
  ASSERT_TRUE(advanceSph(s.world, 0.05, [](const SphStepStats&) {}).ok());
  const std::vector<glm::vec3> end = s.world.particles.position;
  const double t1 = s.world.time, t0 = t1 - s.world.last_dt;
  sphPositionsAt(s.world, t1 + 1.0, out);
  EXPECT_TRUE(out == end);
  std::vector<glm::vec3> start, mid;
  sphPositionsAt(s.world, t0, start);
  sphPositionsAt(s.world, 0.5 * (t0 + t1), mid);
  double moved = 0.0;
  for (std::size_t i = 0; i < end.size(); ++i) {
    moved += glm::length(end[i] - start[i]);
    EXPECT_LT(glm::length(mid[i] - 0.5f * (start[i] + end[i])), 1e-6f);
  }
  EXPECT_GT(moved, 0.0);  // the fluid moved during that step (settling under gravity)
}

}  // namespace
