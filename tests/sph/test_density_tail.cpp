// The tail of the density error: the solvers stop at a mean tolerance (DFSPH 0.05 %), so single
// particles may stay compressed beyond it. Where they are and why (docs/sph.md, "Largest single-
// particle compression"): particles at a wall in the step a surge hits it (within 0.2 r of the wall
// or just projected onto it by the collision pass, with 9 to 16 fluid neighbours): the wall's
// boundary volume counts as about half a neighbourhood of fluid at rest distance 0, so a particle
// that a CFL step carried that close reads up to +50 % until the next step's solve pushes it out.
// Pinned here: the 99th percentile over particles (the water as a whole) and the max (those few),
// over every step, on the dam break and on a calm fountain.
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace fluid;

struct Tail {
  float p99 = 0.0f, max = 0.0f;
  double mean = 0.0;
};

Tail densityTail(const std::string& name, const std::vector<std::pair<std::string, std::string>>& keys, double from,
                 double to) {
  SphScene scene;
  const SphStatus made = makeSphScene(name, SphSolverKind::dfsph, keys, scene);
  EXPECT_TRUE(made.ok()) << made.error;
  Tail tail;
  std::size_t steps = 0;
  const SphStatus st = advanceSph(scene.world, to, [&](const SphStepStats& s) {
    if (scene.world.time <= from) return;
    EXPECT_LE(s.avg_density_error, s.p99_density_error + 1e-6f);  // a mean below its 99th percentile
    EXPECT_LE(s.p99_density_error, s.max_density_error);
    tail.p99 = std::max(tail.p99, s.p99_density_error);
    tail.max = std::max(tail.max, s.max_density_error);
    tail.mean += s.avg_density_error;
    ++steps;
  });
  EXPECT_TRUE(st.ok()) << st.error;
  tail.mean /= static_cast<double>(std::max<std::size_t>(steps, 1));
  std::printf("[ metric ] %s %.2f..%.2f s: density error mean %.4f %%, p99 (worst step) %.3f %%, max %.2f %%\n",
              name.c_str(), from, to, 100.0 * tail.mean, 100.0 * tail.p99, 100.0 * tail.max);
  return tail;
}

// `fluiddemo simulate --scene dambreak --set width=0.05715 --set height_ratio=2 --seconds 0.36`:
// p99 0.60 %, max 8.8 %.
TEST(SphDensityTail, DamBreak) {
  const Tail t = densityTail("dambreak", {{"width", "0.05715"}, {"height_ratio", "2"}}, 0.0, 0.36);
  EXPECT_LE(t.p99, 0.01f);
  EXPECT_LE(t.max, 0.15f);
}

// The library's fountain once the basin holds water (2 to 4 s, jet running, drain open): p99
// 0.15 %, max 6.1 %.
TEST(SphDensityTail, CalmFountain) {
  const Tail t = densityTail("fountain", {}, 2.0, 4.0);
  EXPECT_LE(t.p99, 0.003f);
  EXPECT_LE(t.max, 0.10f);
}

}  // namespace
