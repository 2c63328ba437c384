#pragma once
// Tiny self-contained PNG plotter for the fluid/sph accuracy benchmark (no new dependencies):
// an RGB canvas, lines, markers, a 3x5 pixel font, and a PNG writer using stored (uncompressed)
// deflate blocks with CRC-32 and Adler-32 as the PNG and zlib specifications require.
#include <cstdint>
#include <string>
#include <vector>

namespace sphbench {

struct Canvas {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  Canvas(int w, int h) : width(w), height(h), rgb(static_cast<std::size_t>(w) * h * 3, 255) {}
  void set(int x, int y, std::uint32_t color);
  void line(int x0, int y0, int x1, int y1, std::uint32_t color);
  void rect(int x0, int y0, int x1, int y1, std::uint32_t color);
  void marker(int x, int y, std::uint32_t color);
  // Text in a 3x5 font scaled by `scale` (upper-case letters, digits, . - % / ( ) space).
  void text(int x, int y, const std::string& s, std::uint32_t color, int scale = 2, bool vertical = false);
};

// Returns an empty string on success, else the error.
std::string writePng(const std::string& path, const Canvas& canvas);

}  // namespace sphbench
