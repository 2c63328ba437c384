// 16-bit PCM RIFF/WAVE writer (little-endian, as the format requires) for the offline render.
#include "engine/audio/synth.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

namespace engine::audio {
namespace {

void put16(std::vector<unsigned char>& b, std::uint32_t v) {
  b.push_back(static_cast<unsigned char>(v & 0xff));
  b.push_back(static_cast<unsigned char>((v >> 8) & 0xff));
}
void put32(std::vector<unsigned char>& b, std::uint32_t v) {
  put16(b, v & 0xffff);
  put16(b, v >> 16);
}
void putTag(std::vector<unsigned char>& b, const char* tag) { b.insert(b.end(), tag, tag + 4); }

}  // namespace

bool writeWav16(const char* path, std::span<const float> samples, int channels, int sample_rate, std::string* error) {
  if (channels < 1 || channels > 8 || sample_rate < 1 || samples.size() % static_cast<std::size_t>(channels) != 0 ||
      samples.size() * 2 > 0xffffffe0u) {
    if (error) *error = std::string(path) + ": bad WAV layout (channels, rate or length)";
    return false;
  }
  const auto data_bytes = static_cast<std::uint32_t>(samples.size() * 2);
  std::vector<unsigned char> bytes;
  bytes.reserve(44 + data_bytes);
  putTag(bytes, "RIFF");
  put32(bytes, 36 + data_bytes);
  putTag(bytes, "WAVE");
  putTag(bytes, "fmt ");
  put32(bytes, 16);
  put16(bytes, 1);  // PCM
  put16(bytes, static_cast<std::uint32_t>(channels));
  put32(bytes, static_cast<std::uint32_t>(sample_rate));
  put32(bytes, static_cast<std::uint32_t>(sample_rate * channels * 2));
  put16(bytes, static_cast<std::uint32_t>(channels * 2));
  put16(bytes, 16);
  putTag(bytes, "data");
  put32(bytes, data_bytes);
  for (float s : samples) {
    const float clamped = std::isfinite(s) ? std::clamp(s, -1.0f, 1.0f) : 0.0f;
    const auto v = static_cast<std::int16_t>(std::lround(clamped * 32767.0f));
    put16(bytes, static_cast<std::uint16_t>(v));
  }
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path, "wb"), &std::fclose);
  if (!file) {
    if (error) *error = std::string(path) + ": cannot open for writing: " + std::strerror(errno);
    return false;
  }
  if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size()) {
    if (error) *error = std::string(path) + ": write failed: " + std::strerror(errno);
    return false;
  }
  return true;
}

void stereoToMono(std::span<const float> stereo, std::vector<float>& out) {
  out.resize(stereo.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = 0.5f * (stereo[2 * i] + stereo[2 * i + 1]);
}

}  // namespace engine::audio
