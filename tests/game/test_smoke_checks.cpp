#include "game/smoke_checks.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace {

constexpr int kWidth = 32;
constexpr int kHeight = 24;

std::vector<std::uint8_t> flatFrame(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  std::vector<std::uint8_t> rgba(kWidth * kHeight * 4, 255);
  for (int i = 0; i < kWidth * kHeight; ++i) {
    rgba[i * 4 + 0] = r;
    rgba[i * 4 + 1] = g;
    rgba[i * 4 + 2] = b;
  }
  return rgba;
}

// A sky-like vertical gradient: not one colour.
std::vector<std::uint8_t> gradientFrame() {
  std::vector<std::uint8_t> rgba(kWidth * kHeight * 4, 255);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      rgba[(y * kWidth + x) * 4 + 2] = static_cast<std::uint8_t>(y * 10);
    }
  }
  return rgba;
}

TEST(SmokeChecks, FlatFrameIsBlank) {
  const auto frame = flatFrame(40, 80, 120);
  const auto check = game::checkFrame(frame, {}, kWidth, kHeight);
  EXPECT_NE(check.failure.find("nearly one colour"), std::string::npos);
  EXPECT_DOUBLE_EQ(check.dominant_colour_fraction, 1.0);
}

TEST(SmokeChecks, FrameEqualToEmptyFrameFails) {
  const auto frame = gradientFrame();
  const auto check = game::checkFrame(frame, frame, kWidth, kHeight);
  EXPECT_NE(check.failure.find("same as a frame with nothing drawn"), std::string::npos);
  EXPECT_DOUBLE_EQ(check.changed_fraction, 0.0);
}

TEST(SmokeChecks, DrawnFramePasses) {
  const auto empty = gradientFrame();
  auto frame = empty;
  for (int y = 4; y < 20; ++y) {
    for (int x = 8; x < 24; ++x) frame[(y * kWidth + x) * 4 + 0] = 200;  // a red object
  }
  const auto check = game::checkFrame(frame, empty, kWidth, kHeight);
  EXPECT_TRUE(check.failure.empty()) << check.failure;
  EXPECT_NEAR(check.changed_fraction, 16.0 * 16.0 / (kWidth * kHeight), 1e-12);
}

TEST(SmokeChecks, WrongSizeIsReported) {
  const auto frame = gradientFrame();
  EXPECT_FALSE(game::checkFrame(frame, {}, kWidth + 1, kHeight).failure.empty());
  EXPECT_FALSE(game::checkFrame({}, {}, 0, 0).failure.empty());
}

}  // namespace
