#include "game/smoke_checks.hpp"

#include <algorithm>
#include <cstdlib>
#include <vector>

namespace game {

FrameCheck checkFrame(std::span<const std::uint8_t> rgba, std::span<const std::uint8_t> empty_rgba, int width,
                      int height, const FrameCheckDesc& desc) {
  FrameCheck check;
  const std::size_t pixels =
      width > 0 && height > 0 ? static_cast<std::size_t>(width) * static_cast<std::size_t>(height) : 0;
  if (pixels == 0 || rgba.size() != pixels * 4) {
    check.failure = "frame has no pixels or the wrong size";
    return check;
  }
  std::vector<std::uint32_t> buckets(1u << 12, 0);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint8_t* p = &rgba[i * 4];
    ++buckets[(static_cast<unsigned>(p[0] >> 4) << 8) | (static_cast<unsigned>(p[1] >> 4) << 4) | (p[2] >> 4)];
  }
  check.dominant_colour_fraction =
      static_cast<double>(*std::max_element(buckets.begin(), buckets.end())) / static_cast<double>(pixels);
  if (check.dominant_colour_fraction > desc.max_dominant_colour_fraction) {
    check.failure = "frame is nearly one colour (" +
                    std::to_string(static_cast<int>(check.dominant_colour_fraction * 100.0)) + "% of pixels)";
    return check;
  }
  if (empty_rgba.size() == rgba.size()) {
    std::size_t changed = 0;
    for (std::size_t i = 0; i < pixels; ++i) {
      for (int c = 0; c < 3; ++c) {
        if (std::abs(int{rgba[i * 4 + static_cast<std::size_t>(c)]} -
                     int{empty_rgba[i * 4 + static_cast<std::size_t>(c)]}) > desc.changed_channel_threshold) {
          ++changed;
          break;
        }
      }
    }
    check.changed_fraction = static_cast<double>(changed) / static_cast<double>(pixels);
    if (check.changed_fraction < desc.min_changed_fraction) {
      check.failure = "frame is the same as a frame with nothing drawn (" + std::to_string(changed) + " pixels differ)";
    }
  }
  return check;
}

}  // namespace game
