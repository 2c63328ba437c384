#pragma once
// Checks the smoke test applies to a rendered frame: a scene that draws nothing, or draws
// a single flat colour, fails even when nothing crashed.

#include <cstdint>
#include <span>
#include <string>

namespace game {

struct FrameCheckDesc {
  double max_dominant_colour_fraction = 0.97;  // more pixels than this in one colour bucket = blank
  int changed_channel_threshold = 8;           // a pixel differs when a channel moves by more than this
  double min_changed_fraction = 0.01;          // fewer changed pixels than this = same as nothing drawn
};

struct FrameCheck {
  double dominant_colour_fraction = 0.0;  // share of pixels in the most common 4-bit-per-channel bucket
  double changed_fraction = 0.0;          // share of pixels that differ from the empty frame
  std::string failure;                    // empty when the frame looks drawn
};

// rgba and empty_rgba: width*height RGBA8 pixels. empty_rgba may be empty (check skipped).
FrameCheck checkFrame(std::span<const std::uint8_t> rgba, std::span<const std::uint8_t> empty_rgba, int width,
                      int height, const FrameCheckDesc& desc = {});

}  // namespace game
