// No allocation per frame after warm-up (DESIGN.md habit 3). Counts global operator new calls
// in this executable during repeated extractions of the same-sized input.
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> gAllocations{0};
}

void* operator new(std::size_t size) {
  gAllocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

TEST(SurfaceAllocation, NoOperatorNewAfterWarmUp) {
  const fluid::ParticlePositions ps = surface_test::loadSet("spray.xyz");
  for (int threads : {1, 2, 3}) {
    fluid::SurfaceParams p;
    p.threads = threads;
    p.blockCubes = 32;
    fluid::SurfaceExtractor ex;
    fluid::SurfaceMesh m;
    // Warm-up: the first frames grow every buffer. Which worker meets which block varies from
    // frame to frame (more so on a loaded machine); the extractor grows every worker to the
    // largest scratch any worker needed, so after the frames that met every block, nothing
    // allocates whatever the schedule.
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(ex.extract(surface_test::inputOf(ps), p, m).ok());
    const long before = gAllocations.load();
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(ex.extract(surface_test::inputOf(ps), p, m).ok());
    const long after = gAllocations.load();
    std::printf("operator new calls in 5 warm frames of spray.xyz, %d thread(s): %ld\n", threads, after - before);
    EXPECT_EQ(after - before, 0) << "allocations in 5 warm frames, " << threads << " thread(s)";
  }
}
