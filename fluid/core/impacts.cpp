#include "fluid/core/impacts.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace fluid {
namespace {

template <class T>
const T& at(const T* base, std::size_t stride, std::size_t i) {
  return *reinterpret_cast<const T*>(reinterpret_cast<const unsigned char*>(base) + i * stride);
}

std::uint64_t cellKey(glm::vec3 p, float inv_cell) {
  // 21 bits per axis around the origin (+-2^20 cells): the level fits many times over.
  const auto axis = [inv_cell](float v) {
    const float c = std::floor(v * inv_cell);
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::clamp(c, -1048575.0f, 1048575.0f)) + 1048576) &
           0x1fffff;
  };
  return (axis(p.x) << 42) | (axis(p.y) << 21) | axis(p.z);
}

}  // namespace

void findImpacts(const glm::vec3* positions, std::size_t position_stride, const glm::vec3* velocities,
                 std::size_t velocity_stride, const std::uint32_t* ids, std::size_t count, glm::vec3 gravity, float dt,
                 const ImpactParams& params, ImpactTracker& tracker, std::vector<Impact>& out) {
  out.clear();
  tracker.hits.clear();
  const std::uint32_t previous = tracker.calls, now = ++tracker.calls;  // stamps are call numbers
  const float inv_cell = 1.0f / std::max(params.cell_size, 1e-3f);
  const glm::vec3 fall = gravity * dt;
  const float min_speed2 = params.min_speed * params.min_speed;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t id = ids != nullptr ? ids[i] : static_cast<std::uint32_t>(i);
    if (id >= params.max_id) continue;
    if (id >= tracker.velocity.size()) {
      const std::size_t size = std::max<std::size_t>(id + 1, 2 * tracker.velocity.size());
      tracker.velocity.resize(size, glm::vec3(0.0f));
      tracker.seen_in.resize(size, 0);
    }
    const glm::vec3 v = at(velocities, velocity_stride, i);
    // Known: seen by the previous call (an id absent from a call, in the pump, is forgotten).
    if (previous != 0 && tracker.seen_in[id] == previous) {
      const glm::vec3 before = tracker.velocity[id];
      // Most of the water is slow (the pool): one dot product turns it away.
      if (glm::dot(before, before) >= min_speed2) {
        const float speed = glm::length(before);
        // What the step took beyond free flight: |v0 + g dt| - |v1|.
        const float loss = glm::length(before + fall) - glm::length(v);
        if (loss >= params.min_speed_loss && std::isfinite(loss))
          tracker.hits.push_back(
              {cellKey(at(positions, position_stride, i), inv_cell), static_cast<std::uint32_t>(i), speed, loss});
      }
    }
    tracker.velocity[id] = v;
    tracker.seen_in[id] = std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) ? now : 0;
  }
  std::sort(tracker.hits.begin(), tracker.hits.end(), [](const ImpactTracker::Hit& a, const ImpactTracker::Hit& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.index < b.index;
  });
  for (std::size_t begin = 0; begin < tracker.hits.size();) {
    std::size_t end = begin;
    Impact impact;
    while (end < tracker.hits.size() && tracker.hits[end].cell == tracker.hits[begin].cell) {
      const ImpactTracker::Hit& h = tracker.hits[end];
      impact.position += at(positions, position_stride, h.index);
      impact.speed += h.speed;
      impact.speed_loss += h.loss;
      ++end;
    }
    impact.particles = static_cast<std::uint32_t>(end - begin);
    const float inv = 1.0f / static_cast<float>(impact.particles);
    impact.position *= inv;
    impact.speed *= inv;
    impact.speed_loss *= inv;
    out.push_back(impact);
    begin = end;
  }
}

}  // namespace fluid
