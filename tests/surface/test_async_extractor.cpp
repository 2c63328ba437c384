// fluid::AsyncSurfaceExtractor (Janisz §3.2.6): the mesh a job returns is the one a plain
// extractor gives for the input handed to start(), bit for bit, whatever the caller does to its
// arrays after start(); collect() returns the jobs in order, one frame behind in a frame loop.
#include "fluid/surface/async_extractor.hpp"
#include "random_sets.hpp"
#include "tests/support/mesh_bits.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <glm/vec4.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace {

using test_support::meshBitsDiffer;

TEST(AsyncSurfaceExtractor, MeshesTheInputItWasHandedBitForBit) {
  fluid::AsyncSurfaceExtractor async;
  fluid::SurfaceExtractor plain;
  fluid::SurfaceMesh want, got;
  int meshed = 0;
  for (std::uint64_t seed = 1; seed <= 24; ++seed) {
    surface_test::RandomSet set = surface_test::drawRandomSet(seed);
    const fluid::SurfaceStatus want_status = plain.extract(set.input(), set.params, want);
    // Odd seeds hand over a padded view (stride 16, as a vec4 store): the job's copy packs it.
    std::vector<glm::vec4> padded(set.points.size());
    for (std::size_t i = 0; i < padded.size(); ++i) padded[i] = glm::vec4(set.points[i], 7.0f);
    fluid::SurfaceInput in = set.input();
    if (seed % 2) in.positions = {padded.empty() ? nullptr : &padded[0].x, padded.size(), sizeof(glm::vec4)};
    async.start(in, set.params);
    ASSERT_TRUE(async.pending());
    // The caller moves on at once: its particles change while the job runs.
    for (glm::vec3& q : set.points) q.x += 1e3f * set.params.cube, q.y = -q.y;
    for (glm::vec4& q : padded) q.x += 1e3f * set.params.cube, q.y = -q.y;
    const fluid::SurfaceStatus got_status = async.collect(got);
    EXPECT_FALSE(async.pending());
    ASSERT_EQ(got_status.error, want_status.error) << "seed " << seed << " (" << set.what << ")";
    if (!want_status.ok()) continue;
    EXPECT_EQ(meshBitsDiffer(got, want), "") << "seed " << seed << " (" << set.what << ")";
    meshed += want.indices.empty() ? 0 : 1;
  }
  EXPECT_GE(meshed, 12) << "most seeds give a surface to compare";
}

// A frame loop: start(frame N) after collect() gave frame N-1's surface.
TEST(AsyncSurfaceExtractor, CollectReturnsThePreviousFramesSurfaceInAFrameLoop) {
  fluid::AsyncSurfaceExtractor async;
  fluid::SurfaceExtractor plain;
  std::vector<surface_test::RandomSet> frames;
  for (std::uint64_t seed = 40; seed < 48; ++seed) frames.push_back(surface_test::drawRandomSet(seed));
  fluid::SurfaceMesh shown, want;
  async.start(frames[0].input(), frames[0].params);
  for (std::size_t f = 1; f < frames.size(); ++f) {
    const fluid::SurfaceStatus st = async.collect(shown);
    async.start(frames[f].input(), frames[f].params);
    const fluid::SurfaceStatus want_status = plain.extract(frames[f - 1].input(), frames[f - 1].params, want);
    ASSERT_EQ(st.error, want_status.error) << "frame " << f;
    EXPECT_EQ(meshBitsDiffer(shown, want), "") << "frame " << f << " shows frame " << f - 1;
  }
  EXPECT_TRUE(async.pending()) << "the last job is still out; the destructor waits for it";
}

TEST(AsyncSurfaceExtractor, ErrorsComeWithCollect) {
  fluid::AsyncSurfaceExtractor async;
  fluid::SurfaceMesh mesh;
  EXPECT_NE(async.collect(mesh).error.find("no extraction was started"), std::string::npos);
  const std::vector<glm::vec3> ps{{0.0f, 0.0f, 0.0f}, {std::nanf(""), 0.0f, 0.0f}};
  async.start({fluid::pointView(ps)}, fluid::SurfaceParams{});
  const fluid::SurfaceStatus st = async.collect(mesh);
  EXPECT_FALSE(st.ok()) << "a NaN position is refused by the worker's extract";
  EXPECT_TRUE(mesh.indices.empty());
}

// start() twice without collect(): the first job is waited for and dropped.
TEST(AsyncSurfaceExtractor, AStartWithoutCollectDropsTheEarlierJob) {
  fluid::AsyncSurfaceExtractor async;
  fluid::SurfaceExtractor plain;
  const surface_test::RandomSet a = surface_test::drawRandomSet(3), b = surface_test::drawRandomSet(11);
  fluid::SurfaceMesh got, want;
  async.start(a.input(), a.params);
  async.start(b.input(), b.params);
  const fluid::SurfaceStatus st = async.collect(got);
  ASSERT_EQ(st.error, plain.extract(b.input(), b.params, want).error);
  EXPECT_EQ(meshBitsDiffer(got, want), "");
}

// The default arena is half the parallelism the caller may use, at least one slot: the whole
// oneTBB worker pool is never the mesher's.
TEST(AsyncSurfaceExtractor, DefaultSlotsAreHalfTheCallersParallelism) {
  EXPECT_EQ(fluid::asyncMeshSlots(3), 3) << "a positive count is taken as given";
  auto slotsUnder = [](std::size_t allowed, int arena_slots) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, allowed);
    int slots = -1;
    tbb::task_arena(arena_slots).execute([&] { slots = fluid::asyncMeshSlots(0); });
    return slots;
  };
  EXPECT_EQ(slotsUnder(1, 8), 1);
  EXPECT_EQ(slotsUnder(2, 8), 1) << "fluiddemo replay --threads 2: the worker alone";
  EXPECT_EQ(slotsUnder(3, 8), 1);
  EXPECT_EQ(slotsUnder(8, 8), 4);
  EXPECT_EQ(slotsUnder(16, 8), 4) << "at most the caller's arena's slots";
  EXPECT_EQ(slotsUnder(16, 16), 8);
  EXPECT_EQ(fluid::asyncMeshSlots(-1), fluid::asyncMeshSlots(0));
  // And the extractor made by default takes that width: 4 slots under a cap of 8 in an 8-slot arena.
  int job_slots = -1;
  {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 8);
    tbb::task_arena(8).execute([&] {
      fluid::AsyncSurfaceExtractor async;
      async.startJob([&job_slots](fluid::SurfaceExtractor&, fluid::SurfaceMesh&) {
        job_slots = tbb::this_task_arena::max_concurrency();
        return fluid::SurfaceStatus{};
      });
      fluid::SurfaceMesh mesh;
      EXPECT_TRUE(async.collect(mesh).ok());
    });
  }
  EXPECT_EQ(job_slots, 4);
}

// The jobs run in an arena of the worker's slots, so their parallel loops and an extraction with
// threads = 0 leave the rest of oneTBB's workers to the caller's loops.
TEST(AsyncSurfaceExtractor, JobsRunInAnArenaOfTheWorkersSlots) {
  const tbb::global_control two_cores(tbb::global_control::max_allowed_parallelism, 2);
  for (int threads : {0, 1, 2}) {
    std::unique_ptr<fluid::AsyncSurfaceExtractor> async = threads == 0
                                                              ? std::make_unique<fluid::AsyncSurfaceExtractor>()
                                                              : std::make_unique<fluid::AsyncSurfaceExtractor>(threads);
    int slots = -1;
    async->startJob([&slots](fluid::SurfaceExtractor&, fluid::SurfaceMesh&) {
      slots = tbb::this_task_arena::max_concurrency();
      return fluid::SurfaceStatus{};
    });
    fluid::SurfaceMesh mesh;
    ASSERT_TRUE(async->collect(mesh).ok());
    EXPECT_EQ(slots, threads == 0 ? 1 : threads) << "AsyncSurfaceExtractor(" << threads << "), 0: the default, on 2 cores";
  }
  // start() with SurfaceParams::threads = 0 meshes on the worker's one slot (2 cores): one worker's scratch,
  // as a plain extraction with threads = 1 (a two-slot run would sum two workers' peaks).
  std::vector<glm::vec3> grid;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) grid.push_back({float(i), float(j), float((i * 7 + j * 3) % 5)});
  fluid::SurfaceParams p;
  p.blockCubes = 8;
  p.threads = 1;
  fluid::SurfaceExtractor plain;
  fluid::SurfaceMesh want, got;
  ASSERT_TRUE(plain.extract({fluid::pointView(grid)}, p, want).ok());
  ASSERT_GT(want.stats.blocks, 8u);
  p.threads = 0;
  fluid::AsyncSurfaceExtractor async;
  async.start({fluid::pointView(grid)}, p);
  ASSERT_TRUE(async.collect(got).ok());
  EXPECT_EQ(got.stats.workingBytesAllWorkers, want.stats.workingBytesAllWorkers);
  EXPECT_EQ(meshBitsDiffer(got, want), "");
}

}  // namespace
