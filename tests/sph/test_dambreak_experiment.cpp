// The dam break against experiment: J. C. Martin & W. J. Moyce 1952, "An experimental study of the
// collapse of liquid columns on a rigid horizontal plane", Phil. Trans. R. Soc. A 244, 312-324,
// figure 3: the surge front Z = x / a against T = t sqrt(2 g / a) for a column of water of width
// a = 2.25 in (0.05715 m) and height 2a (n^2 = 2); the points in tests/support/martin_moyce.hpp.
//
// Scene: `fluiddemo simulate --scene dambreak --set width=0.05715 --set height_ratio=2` (13,600
// particles; the scene's viscosity is the least its spacing resolves, sph_scenes.cpp), with the box lengthened to 12 a
// so that the far wall is not reached within the figure's last point. The front is the 99.5th percentile of x, as the
// issue measured it: the largest x follows single drops thrown ahead of the sheet.
//
// Tolerance. The experiment carries its own spread: the figure's two column widths (1.125 in and
// 2.25 in) differ by up to 8 % at equal T, single digitised points sit up to 10 % off a smooth
// curve through their neighbours (T = 4.03 -> 4.42: Z 4.94 -> 5.88), and the gate took time to
// open where the simulation releases the column at once, which puts a simulation ahead early.
// We ask every point within -10 % .. +20 % and the mean |error| within 12 %. A fluid ten thousand
// times as viscous as water (the scene's viscosity before, 0.01 m^2/s) is 18 % (in 1/200 s calls)
// to a third (on the solver's own steps) behind at the last point and fails the per-point bound.
#include "fluid/sph/sph_scenes.hpp"
#include "tests/support/martin_moyce.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace fluid;

using fluid_test::FrontPoint;
using fluid_test::kMartinMoyce2a;
constexpr double kWidth = fluid_test::kMartinMoyceWidth;
constexpr double kGravity = 9.81;

enum class Route { frames, own_steps };

// Z at each of the figure's T: `frames` steps with advanceSph to each sample time (the game's and
// the old simulate's route), `own_steps` with advanceSphUntil (simulate's route now), whose state
// at a sample may be up to one step past it.
std::vector<double> simulatedFronts(SphSolverKind solver, Route route,
                                    std::vector<std::pair<std::string, std::string>> extra = {}) {
  std::vector<std::pair<std::string, std::string>> keys = {
      {"width", "0.05715"}, {"height_ratio", "2"}, {"length_ratio", "12"}};
  keys.insert(keys.end(), extra.begin(), extra.end());
  SphScene scene;
  const SphStatus made = makeSphScene("dambreak", solver, keys, scene);
  EXPECT_TRUE(made.ok()) << made.error;
  std::vector<double> fronts;
  std::vector<float> scratch;
  for (const FrontPoint& point : kMartinMoyce2a) {
    const double t = point.t_scaled / std::sqrt(2.0 * kGravity / kWidth);
    const SphStatus st = route == Route::frames ? advanceSph(scene.world, t - scene.world.time, [](const auto&) {})
                                                : advanceSphUntil(scene.world, t, [](const auto&) {});
    EXPECT_TRUE(st.ok()) << st.error;
    fronts.push_back(sphSurgeFrontQuantile(scene.world, 0.995, scratch) / kWidth);
  }
  return fronts;
}

void expectTracksExperiment(const std::vector<double>& fronts, const char* what) {
  ASSERT_EQ(fronts.size(), kMartinMoyce2a.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < fronts.size(); ++k) {
    const double error = (fronts[k] - kMartinMoyce2a[k].front) / kMartinMoyce2a[k].front;
    sum += std::abs(error);
    EXPECT_GE(error, -0.10) << what << ": behind the experiment at T = " << kMartinMoyce2a[k].t_scaled
                            << " (Z = " << fronts[k] << ", measured " << kMartinMoyce2a[k].front << ")";
    EXPECT_LE(error, 0.20) << what << ": ahead of the experiment at T = " << kMartinMoyce2a[k].t_scaled
                           << " (Z = " << fronts[k] << ", measured " << kMartinMoyce2a[k].front << ")";
  }
  EXPECT_LE(sum / static_cast<double>(fronts.size()), 0.12) << what << ": mean |error| against Martin & Moyce";
}

TEST(DamBreakExperiment, DfsphFrontTracksMartinMoyce) {
  expectTracksExperiment(simulatedFronts(SphSolverKind::dfsph, Route::own_steps), "dfsph");
}

TEST(DamBreakExperiment, WcsphFrontTracksMartinMoyce) {
  expectTracksExperiment(simulatedFronts(SphSolverKind::wcsph, Route::own_steps), "wcsph");
}

// How the steps fall must not change the answer: simulate takes the solver's own steps, the game
// lands on its frames. At the scene's old viscosity (0.01 m^2/s) the two routes put the front at
// 5.5 a and 7.1 a at 0.3 s (sph_scenes.cpp).
TEST(DamBreakExperiment, FrontDoesNotDependOnTheSteppingRoute) {
  const std::vector<std::pair<std::string, std::string>> thin = {{"depth", "0"}};
  const std::vector<double> frames = simulatedFronts(SphSolverKind::dfsph, Route::frames, thin);
  const std::vector<double> own = simulatedFronts(SphSolverKind::dfsph, Route::own_steps, thin);
  for (std::size_t k = 0; k < frames.size(); ++k)
    EXPECT_NEAR(own[k], frames[k], 0.03 * frames[k]) << "T = " << kMartinMoyce2a[k].t_scaled;
}

}  // namespace
