#pragma once
// SplitMix64 (Steele, Lea & Flood 2014): a counter-based hash, so a particle's random numbers come
// from its id or index and not from the order anything is evaluated in (the same for any thread
// count). Not for cryptography.

#include <cstdint>

namespace fluid {

// The SplitMix64 step with its finaliser: x advanced by the golden-ratio increment, then mixed.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// The top 24 bits of `bits` as a float in [0, 1).
inline float unitFloat(std::uint64_t bits) { return static_cast<float>(bits >> 40) * (1.0f / 16777216.0f); }

}  // namespace fluid
