#pragma once
// FNV-1a, 64-bit (Fowler, Noll, Vo): the content hash of collider files, replay files and the
// replays' simulation-state checkpoints. Fast, byte-order dependent, not cryptographic: it detects
// change, it does not resist tampering.

#include <cstddef>
#include <cstdint>

namespace fluid {

// Incremental: feed bytes in order; `value` is the hash of everything fed so far.
struct Fnv1a64 {
  std::uint64_t value = 14695981039346656037ull;  // the offset basis
  void bytes(const void* data, std::size_t count) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < count; ++k) value = (value ^ p[k]) * 1099511628211ull;  // the 64-bit prime
  }
  // The object representation of a plain value (padding bytes included: hash only types without any).
  template <typename T>
  void add(const T& plain) {
    bytes(&plain, sizeof(T));
  }
};

inline std::uint64_t fnv1a64(const void* data, std::size_t count) {
  Fnv1a64 hash;
  hash.bytes(data, count);
  return hash.value;
}

}  // namespace fluid
