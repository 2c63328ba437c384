// Issue 18 item 4 at more than one resolution: the Archimedes tank of
// tests/game/archimedes_tank.hpp (0.14 m crates of 500, 1000 and 2000 kg/m^3, coupled through
// game/world/body_fluid_coupling) at each particle radius given, one table row per crate. The
// unit test runs the first row set (r = 12.5 mm); finer radii take minutes (8x the particles per
// halving), so they live here.
// --mirrored: the crates' force from the mirrored boundary pressure (BodyFluidCoupling::
// surface_pressure_force off), the "mirrored" columns of docs/engine.md's tank table.
//   bench_archimedes [--radius 0.0125,0.00625] [--mirrored]
#include "tests/game/archimedes_tank.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  std::vector<float> radii{0.0125f, 0.00625f};
  bool mirrored = false;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--mirrored") == 0) {
      mirrored = true;
    } else if (std::strcmp(argv[a], "--radius") == 0 && a + 1 < argc) {
      radii.clear();
      std::string list = argv[++a];
      for (std::size_t b = 0; b < list.size();) {
        const std::size_t e = std::min(list.find(',', b), list.size());
        const float r = std::strtof(list.substr(b, e - b).c_str(), nullptr);
        if (!(r > 0.0f) || r > 0.05f) {
          std::fprintf(stderr, "bench_archimedes: --radius: '%s' is not a radius in (0, 0.05] m\n",
                       list.substr(b, e - b).c_str());
          return 2;
        }
        radii.push_back(r);
        b = e + 1;
      }
    } else {
      std::fprintf(stderr, "usage: bench_archimedes [--radius r1,r2,...] [--mirrored]  (m; default 0.0125,0.00625)\n");
      return 2;
    }
  }
  using namespace archimedes_tank;
  std::printf(
      "| r (mm) | spacings per edge | crate (kg/m^3) | submerged below the volume level | below the visible level | "
      "Archimedes | centre start -> end (m) | lowest corner over the run (m) |\n|---|---|---|---|---|---|---|---|\n");
  for (const float r : radii) {
    const float d = 2.0f * r;
    const int shallow = static_cast<int>(std::lround(0.175f / d)), deep = static_cast<int>(std::lround(0.25f / d));
    struct Case {
      float density;
      int layers;
      float box_y;
      double seconds;
    };
    const Case cases[] = {{500.0f, shallow, shallow * d + kBoxHalf, 2.0},
                          {1000.0f, deep, 0.125f, 2.0},
                          {2000.0f, shallow, shallow * d + kBoxHalf, 1.0}};
    for (const Case& c : cases) {
      const Floating f = floatBox(c.density, c.layers, c.box_y, c.seconds, r, mirrored);
      if (!f.error.empty()) {
        std::fprintf(stderr, "bench_archimedes: r %.4f, crate %.0f: %s\n", r, c.density, f.error.c_str());
        return 1;
      }
      std::printf("| %.2f | %.1f | %.0f | %.3f | %.3f | %.3f | %.3f -> %.3f | %.3f |\n", 1000.0f * r, kBoxHalf / r,
                  c.density, f.fraction, f.visible_fraction, std::min(c.density / 1000.0f, 1.0f), f.start_y, f.end_y,
                  f.lowest);
      std::fflush(stdout);
    }
  }
  return 0;
}
