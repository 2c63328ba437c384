#pragma once
// PNG output through stb_image_write.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace engine {

// Writes RGBA8 pixels given bottom row first (as glReadPixels returns them) as a PNG with the
// top row first. Creates missing parent folders. Returns false with a message naming the path.
bool writePngBottomUp(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba,
                      std::string& error);

// Bilinear resampling of RGBA8 pixels (width x height) to out_width x out_height, pixel centres
// aligned: the scene rendered at a resolution scale, written at the window's size.
void resizeRgba(std::span<const std::uint8_t> rgba, int width, int height, int out_width, int out_height,
                std::vector<std::uint8_t>& out);

// First "<dir>/<stem>-NNNN.png" that does not exist yet (never overwrites).
std::filesystem::path nextFreeScreenshotPath(const std::filesystem::path& dir, const std::string& stem);

}  // namespace engine
