#include "engine/render/image_write.hpp"

#include <algorithm>
#include <cmath>

#include <stb_image_write.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>
#include <vector>

namespace engine {

bool writePngBottomUp(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba,
                      std::string& error) {
  if (width <= 0 || height <= 0 || rgba.size() != static_cast<std::size_t>(width) * height * 4) {
    error = path.string() + ": cannot write PNG, pixel buffer does not match " + std::to_string(width) + "x" +
            std::to_string(height);
    return false;
  }
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  const std::size_t row = static_cast<std::size_t>(width) * 4;
  std::vector<std::uint8_t> flipped(rgba.size());
  for (int y = 0; y < height; ++y) {
    const std::size_t src = static_cast<std::size_t>(height - 1 - y) * row;
    std::copy(rgba.begin() + static_cast<std::ptrdiff_t>(src), rgba.begin() + static_cast<std::ptrdiff_t>(src + row),
              flipped.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * row));
  }
  errno = 0;
  if (stbi_write_png(path.string().c_str(), width, height, 4, flipped.data(), static_cast<int>(row)) == 0) {
    // stb fails without a reason of its own; fopen's (or fwrite's) errno is the one there is.
    error = path.string() + ": cannot write PNG" + (errno != 0 ? std::string(": ") + std::strerror(errno) : "");
    return false;
  }
  return true;
}

std::filesystem::path nextFreeScreenshotPath(const std::filesystem::path& dir, const std::string& stem) {
  std::error_code ec;
  for (int i = 1; i < 100000; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "-%04d.png", i);
    std::filesystem::path candidate = dir / (stem + name);
    if (!std::filesystem::exists(candidate, ec)) return candidate;
  }
  return dir / (stem + "-overflow.png");
}

void resizeRgba(std::span<const std::uint8_t> rgba, int width, int height, int out_width, int out_height,
                std::vector<std::uint8_t>& out) {
  out.assign(static_cast<std::size_t>(std::max(out_width, 0)) * static_cast<std::size_t>(std::max(out_height, 0)) * 4,
             0);
  if (width <= 0 || height <= 0 || rgba.size() < static_cast<std::size_t>(width) * height * 4) return;
  const float sx = static_cast<float>(width) / static_cast<float>(out_width);
  const float sy = static_cast<float>(height) / static_cast<float>(out_height);
  for (int y = 0; y < out_height; ++y) {
    const float fy = std::clamp((static_cast<float>(y) + 0.5f) * sy - 0.5f, 0.0f, static_cast<float>(height - 1));
    const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, height - 1);
    const float wy = fy - static_cast<float>(y0);
    for (int x = 0; x < out_width; ++x) {
      const float fx = std::clamp((static_cast<float>(x) + 0.5f) * sx - 0.5f, 0.0f, static_cast<float>(width - 1));
      const int x0 = static_cast<int>(fx), x1 = std::min(x0 + 1, width - 1);
      const float wx = fx - static_cast<float>(x0);
      for (int c = 0; c < 4; ++c) {
        const auto at = [&](int px, int py) { return static_cast<float>(rgba[(static_cast<std::size_t>(py) * width + px) * 4 + c]); };
        const float top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * wx;
        const float bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * wx;
        out[(static_cast<std::size_t>(y) * out_width + x) * 4 + c] =
            static_cast<std::uint8_t>(std::lround(top + (bottom - top) * wy));
      }
    }
  }
}

}  // namespace engine
