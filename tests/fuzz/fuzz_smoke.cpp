// Bounded, deterministic mutation run of one fuzz target, for ctest (any compiler, no libFuzzer):
//   fuzz_smoke --target NAME --corpus DIR [--iterations N] [--seed S] [--max-ms T] [--max-mb M]
// Runs every seed file, then N mutants of them (bit flips, byte inserts and deletes,
// truncation, splices, repeated chunks, numbers replaced by huge/NaN/negative values, binary
// words replaced by extreme integers and floats), 1-3 mutations stacked, from a std::mt19937_64
// seeded with S. Fails when the target reports a property violation (fuzz_targets.hpp), when
// one input takes longer than T ms (a hang in the making), or when one input makes the
// process hold more than M MB + 64 x its size beyond what it held before (operator new is
// counted here). A failing input is written to fuzz_failure_<target>.bin in the working directory.
#include "fuzz_targets.hpp"

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <random>
#include <string>
#include <vector>

// ---- allocation accounting (every operator new of the process) -------------------------

namespace {
std::atomic<std::int64_t> g_live{0}, g_peak{0};

void* counted(std::size_t size) {
  void* p = std::malloc(size == 0 ? 1 : size);
  if (p == nullptr) throw std::bad_alloc();
  const std::int64_t live = g_live.fetch_add(static_cast<std::int64_t>(malloc_usable_size(p))) +
                            static_cast<std::int64_t>(malloc_usable_size(p));
  std::int64_t peak = g_peak.load();
  while (live > peak && !g_peak.compare_exchange_weak(peak, live)) {
  }
  return p;
}
void* countedAligned(std::size_t size, std::align_val_t align) {
  void* p = nullptr;
  if (posix_memalign(&p, std::max(sizeof(void*), static_cast<std::size_t>(align)), size == 0 ? 1 : size) != 0)
    throw std::bad_alloc();
  const std::int64_t live = g_live.fetch_add(static_cast<std::int64_t>(malloc_usable_size(p))) +
                            static_cast<std::int64_t>(malloc_usable_size(p));
  std::int64_t peak = g_peak.load();
  while (live > peak && !g_peak.compare_exchange_weak(peak, live)) {
  }
  return p;
}
void release(void* p) {
  if (p == nullptr) return;
  g_live.fetch_sub(static_cast<std::int64_t>(malloc_usable_size(p)));
  std::free(p);
}
}  // namespace

void* operator new(std::size_t size) { return counted(size); }
void* operator new[](std::size_t size) { return counted(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t a) { return countedAligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return countedAligned(size, a); }
void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }

// ---- mutations -------------------------------------------------------------------------

namespace {

using Bytes = std::vector<std::uint8_t>;
using Rng = std::mt19937_64;

std::size_t pick(Rng& rng, std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); }

const char* const kNumbers[] = {"1e308",
                                "-1e308",
                                "1e999",
                                "nan",
                                "-nan",
                                "inf",
                                "-inf",
                                "-1",
                                "0",
                                "-0",
                                "4294967295",
                                "4294967296",
                                "1e30",
                                "-5",
                                "2147483648",
                                "1e-320",
                                "99999999999999999999",
                                "0x7fff",
                                "1.5",
                                "1000000000",
                                "18446744073709551615"};

bool numberChar(std::uint8_t c) { return std::isdigit(c) || c == '.' || c == 'e' || c == 'E' || c == '-' || c == '+'; }

void replaceNumber(Bytes& b, Rng& rng) {
  // Collect number-like runs that start with a digit or a sign.
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < b.size();) {
    if (std::isdigit(b[i]) || ((b[i] == '-' || b[i] == '+') && i + 1 < b.size() && std::isdigit(b[i + 1]))) {
      std::size_t j = i + 1;
      while (j < b.size() && numberChar(b[j])) ++j;
      runs.push_back({i, j});
      i = j;
    } else {
      ++i;
    }
  }
  if (runs.empty()) return;
  const auto [from, to] = runs[pick(rng, runs.size())];
  const char* number = kNumbers[pick(rng, std::size(kNumbers))];
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(from), b.begin() + static_cast<std::ptrdiff_t>(to));
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(from), number, number + std::strlen(number));
}

void replaceWord(Bytes& b, Rng& rng) {
  if (b.size() < 4) return;
  static const std::uint32_t kWords[] = {0xFFFFFFFFu,
                                         0x7FFFFFFFu,
                                         0x80000000u,
                                         0u,
                                         1u,
                                         0x7F800000u /* inf */,
                                         0x7FC00000u /* NaN */,
                                         0xFF800000u,
                                         0x7149F2CAu /* 1e30f */,
                                         4096u,
                                         4097u,
                                         1025u,
                                         256u,
                                         257u,
                                         3u,
                                         0x0000FFFFu};
  const std::size_t at = pick(rng, b.size() / 4) * 4;
  const std::uint32_t w = kWords[pick(rng, std::size(kWords))];
  std::memcpy(b.data() + at, &w, 4);
}

void mutate(Bytes& b, const std::vector<Bytes>& corpus, Rng& rng) {
  switch (pick(rng, 9)) {
    case 0:  // bit flip
      if (!b.empty()) b[pick(rng, b.size())] ^= static_cast<std::uint8_t>(1u << pick(rng, 8));
      break;
    case 1: {  // insert bytes (random, or structural characters)
      static const char kSpecial[] = " \n\t,.-+e[]{}\":0\xff";
      const std::size_t at = pick(rng, b.size() + 1), n = 1 + pick(rng, 8);
      for (std::size_t k = 0; k < n; ++k)
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(at),
                 rng() % 2 ? static_cast<std::uint8_t>(rng()) : static_cast<std::uint8_t>(kSpecial[pick(rng, 16)]));
      break;
    }
    case 2: {  // delete a span
      if (b.empty()) break;
      const std::size_t at = pick(rng, b.size()), n = std::min(b.size() - at, 1 + pick(rng, 16));
      b.erase(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n));
      break;
    }
    case 3:  // truncate
      b.resize(pick(rng, b.size() + 1));
      break;
    case 4: {  // splice: our prefix + another seed's suffix
      const Bytes& other = corpus[pick(rng, corpus.size())];
      const std::size_t cut = pick(rng, b.size() + 1), from = pick(rng, other.size() + 1);
      b.resize(cut);
      b.insert(b.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
      break;
    }
    case 5:
    case 6:
      replaceNumber(b, rng);
      break;
    case 7:
      replaceWord(b, rng);
      break;
    case 8: {  // repeat a chunk (many lines, many items)
      if (b.empty()) break;
      const std::size_t at = pick(rng, b.size()), n = std::min(b.size() - at, 1 + pick(rng, 64));
      const Bytes chunk(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + n));
      const std::size_t times = 1 + pick(rng, 64);
      for (std::size_t k = 0; k < times && b.size() < (1u << 20); ++k)
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), chunk.begin(), chunk.end());
      break;
    }
  }
}

Bytes readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

int main(int argc, char** argv) {
  std::string target_name, corpus_dir;
  long iterations = 2000;
  unsigned long long seed = 1;
  double max_ms = 2000.0, max_mb = 48.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--target")
      target_name = value;
    else if (key == "--corpus")
      corpus_dir = value;
    else if (key == "--iterations")
      iterations = std::stol(value);
    else if (key == "--seed")
      seed = std::stoull(value);
    else if (key == "--max-ms")
      max_ms = std::stod(value);
    else if (key == "--max-mb")
      max_mb = std::stod(value);
    else {
      std::fprintf(stderr, "fuzz_smoke: unknown option %s\n", key.c_str());
      return 2;
    }
  }
  const fuzz::Target* target = fuzz::findTarget(target_name);
  if (target == nullptr || corpus_dir.empty()) {
    std::fprintf(stderr, "usage: fuzz_smoke --target NAME --corpus DIR [--iterations N] [--seed S]\n");
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(corpus_dir)) files.push_back(entry.path());
  std::sort(files.begin(), files.end());  // directory order is not deterministic
  std::vector<Bytes> corpus;
  for (const auto& file : files) corpus.push_back(readFile(file));
  if (corpus.empty()) {
    std::fprintf(stderr, "fuzz_smoke: no seed files in %s\n", corpus_dir.c_str());
    return 1;
  }

  Rng rng(seed ^ std::hash<std::string_view>{}(target->name));
  double slowest_ms = 0.0, most_mb = 0.0;
  auto run = [&](const Bytes& input, long index) {
    const std::int64_t before = g_live.load();
    g_peak.store(before);
    const auto t0 = std::chrono::steady_clock::now();
    const std::string failure = target->check(input);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const double mb = static_cast<double>(g_peak.load() - before) / 1e6;
    slowest_ms = std::max(slowest_ms, ms);
    most_mb = std::max(most_mb, mb);
    std::string problem = failure;
    if (problem.empty() && ms > max_ms) problem = "took " + std::to_string(ms) + " ms";
    if (problem.empty() && mb > max_mb + 64.0 * static_cast<double>(input.size()) / 1e6)
      problem = "held " + std::to_string(mb) + " MB for a " + std::to_string(input.size()) + "-byte input";
    if (problem.empty()) return true;
    const std::string dump = "fuzz_failure_" + std::string(target->name) + ".bin";
    std::ofstream(dump, std::ios::binary)
        .write(reinterpret_cast<const char*>(input.data()), static_cast<std::streamsize>(input.size()));
    std::fprintf(stderr, "fuzz_smoke %s: input %ld (%zu bytes, saved as %s): %s\n", std::string(target->name).c_str(),
                 index, input.size(), dump.c_str(), problem.c_str());
    return false;
  };

  const auto start = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < corpus.size(); ++k) {
    if (!run(corpus[k], -1 - static_cast<long>(k))) return 1;
  }
  for (long i = 0; i < iterations; ++i) {
    Bytes input = corpus[pick(rng, corpus.size())];
    const std::size_t stacked = 1 + pick(rng, 3);
    for (std::size_t m = 0; m < stacked; ++m) mutate(input, corpus, rng);
    if (!run(input, i)) return 1;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "fuzz_smoke %s: %zu seeds + %ld mutants of %s, seed %llu: no failure; slowest input %.1f ms, "
      "most memory held %.1f MB; %.2f s\n",
      std::string(target->name).c_str(), corpus.size(), iterations, std::string(target->parser).c_str(), seed,
      slowest_ms, most_mb, seconds);
  return 0;
}
