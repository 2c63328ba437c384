// fluid::par (fluid/core/parallel.hpp): its thread cap is oneTBB's max_allowed_parallelism in every
// build (`simulate --threads N`), including TSan builds where it starts std::threads of its own.
// (Moved here from the deleted CPU sprite stand-in's tests, whose loop used it.)
#include "fluid/core/parallel.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace {

TEST(Parallel, LoopsHonourTheThreadCap) {
  for (const std::size_t cap : {1u, 2u, 3u}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cap);
    std::atomic<int> running{0}, most{0};
    std::atomic<std::size_t> visited{0};
    fluid::par::parallelFor(fluid::par::Range<std::size_t>(0, 48, 1), [&](const fluid::par::Range<std::size_t>& r) {
      const int now = ++running;
      int seen = most.load();
      while (now > seen && !most.compare_exchange_weak(seen, now)) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // long enough for bodies to overlap
      visited += r.size();
      --running;
    });
    EXPECT_EQ(visited.load(), 48u);
    EXPECT_GE(most.load(), 1);
    EXPECT_LE(most.load(), static_cast<int>(cap)) << "cap " << cap;
  }
}

}  // namespace
