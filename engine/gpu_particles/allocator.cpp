// §3.3.1 of Kolb et al. 2004: allocation is serial by nature, so it stays on the CPU. The heap
// variant always returns the smallest free index, which keeps live particles packed in the
// first texels; the passes then only cover the active range.
#include "engine/gpu_particles/gpu_particles.hpp"

#include <algorithm>
#include <cassert>
#include <functional>
#include <numeric>

namespace engine {

void initAllocator(IndexAllocator& allocator, std::uint32_t capacity, std::uint32_t budget) {
  allocator.free_heap.resize(budget == 0 ? capacity : std::min(budget, capacity));
  // 0..n-1 ascending is already a valid min-heap.
  std::iota(allocator.free_heap.begin(), allocator.free_heap.end(), 0u);
  allocator.live.assign(capacity, 0);
  allocator.live_count = 0;
  allocator.active_range = 0;
}

bool allocateIndex(IndexAllocator& allocator, std::uint32_t& out) {
  if (allocator.free_heap.empty()) return false;
  std::pop_heap(allocator.free_heap.begin(), allocator.free_heap.end(), std::greater<>());
  const std::uint32_t index = allocator.free_heap.back();
  allocator.free_heap.pop_back();
  assert(allocator.live[index] == 0 && "allocator handed out a live index");
  allocator.live[index] = 1;
  ++allocator.live_count;
  allocator.active_range = std::max(allocator.active_range, index + 1);
  out = index;
  return true;
}

void releaseIndex(IndexAllocator& allocator, std::uint32_t index) {
  assert(index < allocator.live.size() && allocator.live[index] != 0 && "release of a free index");
  allocator.live[index] = 0;
  --allocator.live_count;
  allocator.free_heap.push_back(index);
  std::push_heap(allocator.free_heap.begin(), allocator.free_heap.end(), std::greater<>());
  // Shrink the active range past trailing free indices (amortised O(1) per release).
  while (allocator.active_range > 0 && allocator.live[allocator.active_range - 1] == 0) --allocator.active_range;
}

}  // namespace engine
