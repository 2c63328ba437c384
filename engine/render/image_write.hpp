#pragma once
// PNG output through stb_image_write.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace engine {

// Writes RGBA8 pixels given bottom row first (as glReadPixels returns them) as a PNG with the
// top row first. Creates missing parent folders. Returns false with a message naming the path.
bool writePngBottomUp(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> rgba,
                      std::string& error);

// First "<dir>/<stem>-NNNN.png" that does not exist yet (never overwrites).
std::filesystem::path nextFreeScreenshotPath(const std::filesystem::path& dir, const std::string& stem);

}  // namespace engine
