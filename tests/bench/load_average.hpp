#pragma once
// The 1, 5 and 15 minute load averages from /proc/loadavg ("0.13 0.78 1.59"), or "unknown": the
// benchmark pages print them next to their timings, since the machine is shared.
#include <fstream>
#include <string>

namespace benchplot {

inline std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return f ? a + " " + b + " " + c : std::string("unknown");
}

}  // namespace benchplot
