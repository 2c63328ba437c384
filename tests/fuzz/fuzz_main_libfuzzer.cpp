// libFuzzer entry: one executable per target, FLUIDDEMO_FUZZ_TARGET names it (tests/fuzz/CMakeLists.txt).
// A property violation aborts, so libFuzzer keeps the input as a crash.
#include "fuzz_targets.hpp"

#include <cstdio>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const fuzz::Target* target = fuzz::findTarget(FLUIDDEMO_FUZZ_TARGET);
  if (target == nullptr) std::abort();
  const std::string failure = target->check(std::span(data, size));
  if (!failure.empty()) {
    std::fprintf(stderr, "fuzz %s: %s\n", FLUIDDEMO_FUZZ_TARGET, failure.c_str());
    std::abort();
  }
  return 0;
}
