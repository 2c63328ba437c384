// The CI slice of the mesher's randomised property sweep (tests/surface/random_sets.hpp; the
// full sweep is `bench_surface_seeds --from A --to B`): seeds 1..kSeeds, every property on each.
#include "random_sets.hpp"

#include <gtest/gtest.h>

#include <string>

using namespace surface_test;

namespace {

constexpr int kSeeds = 320;  // 8 ctest cases of 40 seeds (every kind 5 times in each)
constexpr int kChunk = 40;

class RandomSets : public ::testing::TestWithParam<int> {};

// checkRandomSet with the set's route (the default: the dense scan) and with §4 seeding and Alg. 1's
// walk (the §6 cache, as every policy with corner data takes it), so seeding and seam propagation
// stay tested on spherical kernels: the first failure, labelled with its route, or empty.
std::string checkBothRoutes(const RandomSet& r, RandomSetChecker& ck) {
  if (std::string failure = checkRandomSet(r, ck); !failure.empty()) return "default route: " + failure;
  RandomSet walk = r;
  walk.params.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
  if (std::string failure = checkRandomSet(walk, ck); !failure.empty()) return "the walk (particle cache): " + failure;
  return {};
}

}  // namespace

TEST_P(RandomSets, ClosedOrientedThreadInvariantAndEqualToTheDenseOracle) {
  RandomSetChecker checker;
  const int first = GetParam();
  std::size_t triangles = 0;
  for (int seed = first; seed < first + kChunk; ++seed) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    const std::string failure = checkBothRoutes(r, checker);
    EXPECT_TRUE(failure.empty()) << "seed " << seed << " (" << r.what << ", " << r.points.size()
                                 << " particles): " << failure << "\n  reproduce: bench_surface_seeds --from " << seed
                                 << " --to " << seed;
    triangles += checker.ref.indices.size() / 3;
  }
  // The sets must produce surfaces (a generator drawing empty meshes would test nothing).
  EXPECT_GT(triangles, std::size_t(kChunk) * 50);
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSets, ::testing::Range(1, kSeeds + 1, kChunk),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return "from" + std::to_string(p.param) + "to" + std::to_string(p.param + kChunk - 1);
                         });

// The same properties with anisotropic kernels (Yu & Turk 2013; SurfaceInput::stretch), random
// ellipsoids and the sets' own kernels in turn (withStretch): closed, oriented, thread-count
// invariant, and equal to the dense oracle summing the same stretched terms.
class AnisotropicRandomSets : public ::testing::TestWithParam<int> {};

TEST_P(AnisotropicRandomSets, ClosedOrientedThreadInvariantAndEqualToTheDenseOracle) {
  RandomSetChecker checker;
  const int first = GetParam();
  std::size_t triangles = 0, stretched = 0;
  for (int seed = first; seed < first + kChunk; ++seed) {
    RandomSet r = drawRandomSet(std::uint64_t(seed));
    withStretch(r, std::uint64_t(seed));
    for (const glm::mat3& g : r.stretch) stretched += g != glm::mat3(1.0f);
    std::string failure = checkRandomSet(r, checker);
    if (failure.empty()) failure = checkCrossingsByBruteForce(r, checker.mesh[0]);
    EXPECT_TRUE(failure.empty()) << "seed " << seed << " (" << r.what << ", " << r.points.size()
                                 << " particles): " << failure;
    triangles += checker.ref.indices.size() / 3;
  }
  EXPECT_GT(triangles, std::size_t(kChunk) * 50);
  EXPECT_GT(stretched, std::size_t(kChunk) * 5);  // the kernels are not all spheres
}

INSTANTIATE_TEST_SUITE_P(Seeds, AnisotropicRandomSets, ::testing::Range(1, 2 * kChunk + 1, kChunk),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return "from" + std::to_string(p.param) + "to" + std::to_string(p.param + kChunk - 1);
                         });

// Seeds that left holes at block seams with margins of ceil(Rc/S) cubes (Rc/S whole: a particle
// just over m - 1/2 cubes outside a block's interior seeded from the block's zero boundary, see
// marginCubes()); closed and equal to the oracle with ceil(Rc/S + 1/2).
TEST(RandomSets, SeamHolesOfTheOldMarginAreClosed) {
  RandomSetChecker checker;
  for (int seed : {31, 117, 125, 143}) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    EXPECT_EQ(checkBothRoutes(r, checker), "") << "seed " << seed << " (" << r.what << ")";
  }
}

// Seeds that left holes at block seams because a descent (§4) from a margin corner stopped after
// Rc + S, still inside, on "a particle below seeds it" while that particle was not among the
// block's particles (it does not reach the block's interior); closed since margin steps do not
// count (BlockMesher::seed).
TEST(RandomSets, SeamHolesOfMarginDescentsAreClosed) {
  RandomSetChecker checker;
  for (int seed : {77, 1981, 2957, 3327}) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    EXPECT_EQ(checkBothRoutes(r, checker), "") << "seed " << seed << " (" << r.what << ")";
  }
}

// Seeds that left holes at block seams: a surface component crossing a seam had a piece in one
// block's interior that none of that block's own §4 seeds reached, while a neighbour marched the
// rest. The block's field in its margin sums only the particles reaching its interior, so (312,
// 2363, 4168, 6392) the nearest corner of the particles around that piece lies in the margin and
// reads outside there, or (4395, 5888, 6560) the piece joins what the block does seed only through
// the neighbour's interior, while the particles at the piece itself seed nothing (their nearest
// corners are outside, Rc = S in 6560; or their descents stay inside for Rc and stop on §4's "a
// particle below seeds it", 4395, where the piece is a side wall). Closed by seam propagation
// (BlockMesher::seedFromNeighbours): a seam square crossed from one side seeds the other side.
TEST(RandomSets, SeamHolesOfPartialMarginFieldsAreClosed) {
  RandomSetChecker checker;
  for (int seed : {312, 2363, 4168, 4395, 5888, 6392, 6560}) {
    const RandomSet r = drawRandomSet(std::uint64_t(seed));
    EXPECT_EQ(checkBothRoutes(r, checker), "") << "seed " << seed << " (" << r.what << ")";
  }
}
