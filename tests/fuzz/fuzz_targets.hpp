#pragma once
// The parsers that read user files, each wrapped as a fuzz target: feed it any bytes, and it
// returns "" when the parser behaved (accepted the input and produced only valid values, or
// rejected it with a message naming the file and the place), else what went wrong. Crashes,
// hangs and unbounded allocations are caught around it: by libFuzzer with ASan/UBSan
// (fuzz_main_libfuzzer.cpp, clang, -DFLUIDDEMO_FUZZ=ON) or by the seeded mutation run under
// ctest (fuzz_smoke.cpp, any compiler). docs/fuzz.md says how to run both.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace fuzz {

struct Target {
  std::string_view name;    // also the seed corpus folder: tests/fuzz/corpus/<name>/
  std::string_view parser;  // what it reaches, for messages
  std::string (*check)(std::span<const std::uint8_t> input);
};

// particles_xyz, particles_csv, particles_ply (ASCII and binary), scene_json, scene_set,
// collider_file, model_obj.
std::span<const Target> targets();
const Target* findTarget(std::string_view name);

}  // namespace fuzz
