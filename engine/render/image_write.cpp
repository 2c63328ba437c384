#include "engine/render/image_write.hpp"

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

}  // namespace engine
