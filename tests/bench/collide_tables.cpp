// Generates the tables of docs/collide.md (fluid/collide, Kolb et al. 2004 §4):
//   1. L1 normal index angular error against resolution (§4.2, eq. (3));
//   2. accuracy against time per shape, map set, format and resolution, measured against the
//      exact mesh distance (fluid::MeshDistance) on seeded random points.
// Usage: bench_collide_tables [--points N] [--l1-samples N] [--res 64,128,...] [--csv FILE [--force]]
// --csv also writes the rows of table 2 to FILE, which scripts/plots/collide_accuracy.py draws as
// charts (error against ns per query, log-log; one curve per map set, one point per resolution).
#include "bench_timing.hpp"
#include "collide_meshes.hpp"
#include "fluid/collide/collide.hpp"
#include "load_average.hpp"
#include "bench_csv.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using benchtiming::median;

using Clock = std::chrono::steady_clock;
using collide_test::Mesh;
using fluid::DepthMapFormat;

double angleDeg(glm::vec3 a, glm::vec3 b) {
  const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
  return glm::degrees(std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y)));
}

void l1Table(int samples) {
  std::printf("### L1 normal index: angular error of the stored texel normal\n\n");
  std::printf(
      "%d seeded uniform random unit vectors (std::mt19937 seed 1, normalised Gaussians); error = angle "
      "between the vector and l1TexelNormal(l1Texel(v, R), R).\n\n",
      samples);
  std::printf("| resolution | texels | max error (deg) | mean error (deg) | max·R (deg) |\n|---|---|---|---|---|\n");
  for (int r : {64, 128, 256, 512, 1024}) {
    std::mt19937 rng(1);
    std::normal_distribution<float> g;
    double max_e = 0.0, sum = 0.0;
    for (int k = 0; k < samples; ++k) {
      glm::vec3 v;
      do v = {g(rng), g(rng), g(rng)};
      while (glm::dot(v, v) < 1e-8f);
      v = glm::normalize(v);
      const double e = angleDeg(fluid::l1TexelNormal(fluid::l1Texel(v, r), r), v);
      max_e = std::max(max_e, e);
      sum += e;
    }
    std::printf("| %d² | %d | %.4f | %.4f | %.1f |\n", r, r * r, max_e, sum / samples, max_e * r);
  }
  std::printf("\n");
}

struct Shape {
  std::string name;
  Mesh mesh;
};

struct Config {
  std::string name;
  std::vector<fluid::MapSpec> specs;
};

std::vector<Config> configsFor(const std::string& shape, const Mesh& mesh, int res) {
  const fluid::Bounds b = fluid::meshBounds(mesh.view());
  std::vector<Config> out;
  for (DepthMapFormat f : {DepthMapFormat::float32, DepthMapFormat::fixed8, DepthMapFormat::front_back16}) {
    out.push_back({std::string("axes ") + fluid::formatName(f), fluid::defaultMapSpecs(b, res, f)});
  }
  const auto with_cube = fluid::defaultMapSpecs(b, res, DepthMapFormat::front_back16, true);
  if (shape == "sphere") {
    out.push_back({"1 cube8 (GREATER, centre)", {with_cube.back()}});
    out.push_back({"axes front-back16 + cube8", with_cube});
  } else if (shape == "torus") {
    // Figure 6 of the paper: two depth cubes and two front-back textures (16 depth maps).
    // Both cubes sit in the hole: LESS sees the inner wall, GREATER the outer wall.
    fluid::MapSpec less = with_cube.back(), greater = with_cube.back();
    less.compare = fluid::DepthCompare::less;
    std::vector<fluid::MapSpec> paper = {with_cube[2], with_cube[0], less, greater};  // z and x front-back
    out.push_back({"paper Fig. 6: 2 cube8 + 2 front-back16", paper});
  } else if (shape == "basin") {
    const fluid::MapSpec cavity = collide_test::basinCavityCube(res);
    auto specs = fluid::defaultMapSpecs(b, res, DepthMapFormat::front_back16);
    specs.push_back(cavity);
    out.push_back({"axes front-back16 + cavity cube8", specs});
  }
  return out;
}

// Chart data: one CSV row per table row, plus the "map set at res²" rows with an error of 0, which a
// log axis cannot hold.
struct ChartData {
  benchcsv::Table table{{"shape", "maps", "depth_maps", "res", "misclass_pct", "mean_abs_dd", "max_abs_dd",
                         "mean_normal_err_deg", "max_normal_err_deg", "ns_per_query", "bytes", "bake_ms"},
                        {}};
  std::vector<std::string> zeroPoints;
};

void accuracyTable(std::size_t count, const std::vector<int>& resolutions, ChartData* chart) {
  std::vector<Shape> shapes = {{"sphere", collide_test::makeSphere(1.0f, 48, 96)},
                               {"torus", collide_test::makeTorus(1.0f, 0.35f, 96, 32)},
                               {"basin", collide_test::makeBasin(96)}};
  std::printf("### Accuracy against time\n\n");
  std::printf(
      "Per shape: %zu seeded random points (std::mt19937 seed 42) uniform in the mesh bounds padded by 10%% "
      "of the largest extent on every side; reference = exact signed distance to the same mesh "
      "(BVH closest point, crossing-parity sign). *misclass* = inside/outside differs (an invalid sample "
      "counts as outside), over all points. *|Δd|* and *normal error* over the near-surface band "
      "|d_exact| < 5%% of the largest extent, valid samples only (normal reference = direction of the "
      "exact distance gradient). *ns/query* = serial rule-(2) query, median of 3 runs, one thread. "
      "*bytes* = texels of all maps (the 768 KiB normal index texture at 256² is shared and not "
      "counted). Shapes: sphere r=1 (48×96 UV), torus R=1 r=0.35 (96×32), fountain basin (96 segments, "
      "rim overhanging its cavity; tests/collide/collide_meshes.cpp).\n\n",
      count);
  std::printf(
      "| shape | maps | depth maps | res | misclass %% | mean \\|Δd\\| | max \\|Δd\\| | mean normal err (deg) | "
      "max normal err (deg) | ns/query | bytes | bake ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Shape& shape : shapes) {
    const fluid::Bounds b = fluid::meshBounds(shape.mesh.view());
    const glm::vec3 ext = b.hi - b.lo;
    const float size = std::max({ext.x, ext.y, ext.z});
    const glm::vec3 lo = b.lo - glm::vec3(0.1f * size), hi = b.hi + glm::vec3(0.1f * size);
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<glm::vec3> points(count);
    for (glm::vec3& p : points) p = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
    const fluid::MeshDistance exact(shape.mesh.view());
    std::vector<fluid::ColliderSample> reference(count), got(count);
    fluid::queryParallel(exact, points, reference, {0, 256});
    for (int res : resolutions) {
      const std::vector<Config> configs = configsFor(shape.name, shape.mesh, res);
      for (std::size_t ci = 0; ci < configs.size(); ++ci) {
        const Config& config = configs[ci];
        fluid::DepthMapCollider collider;
        const auto t0 = Clock::now();
        const fluid::BakeStatus st = fluid::bakeDepthMaps(shape.mesh.view(), config.specs, {}, collider);
        const double bake_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!st.ok()) {
          std::fprintf(stderr, "bake failed: %s\n", st.error.c_str());
          std::exit(1);
        }
        std::vector<double> times;
        for (int rep = 0; rep < 3; ++rep) {
          const auto q0 = Clock::now();
          fluid::queryParallel(collider, points, got, {1});
          times.push_back(std::chrono::duration<double, std::nano>(Clock::now() - q0).count() / double(count));
        }
        std::size_t wrong = 0, band = 0;
        double sum_d = 0.0, max_d = 0.0, sum_n = 0.0, max_n = 0.0;
        for (std::size_t k = 0; k < count; ++k) {
          const bool in_exact = reference[k].distance < 0.0f;
          const bool in_got = got[k].valid && got[k].distance < 0.0f;
          wrong += in_exact != in_got;
          if (std::fabs(reference[k].distance) < 0.05f * size && got[k].valid) {
            ++band;
            const double dd = std::fabs(double(got[k].distance) - reference[k].distance);
            sum_d += dd;
            max_d = std::max(max_d, dd);
            const double dn = angleDeg(got[k].normal, reference[k].normal);
            sum_n += dn;
            max_n = std::max(max_n, dn);
          }
        }
        std::printf("| %s | %s | %d | %d² | %.3f | %.4f | %.3f | %.2f | %.1f | %.0f | %zu | %.0f |\n",
                    shape.name.c_str(), config.name.c_str(), collider.depthMapCount(), res,
                    100.0 * double(wrong) / double(count), band ? sum_d / double(band) : 0.0, max_d,
                    band ? sum_n / double(band) : 0.0, max_n, median(times), collider.bytes(), bake_ms);
        std::fflush(stdout);
        if (chart == nullptr) continue;
        const double misclassPct = 100.0 * double(wrong) / double(count), meanDd = band ? sum_d / double(band) : 0.0;
        using benchcsv::number;
        chart->table.rows.push_back({shape.name, config.name, std::to_string(collider.depthMapCount()),
                                     std::to_string(res), number(misclassPct), number(meanDd), number(max_d),
                                     number(band ? sum_n / double(band) : 0.0), number(max_n), number(median(times)),
                                     std::to_string(collider.bytes()), number(bake_ms)});
        for (const auto& [value, what] : {std::pair{misclassPct, " (misclassification)"},
                                          std::pair{meanDd, " (distance error)"}})
          if (!benchcsv::drawableOnLogAxes(median(times), value))
            chart->zeroPoints.push_back(shape.name + ", " + config.name + " at " + std::to_string(res) + "²" + what);
      }
    }
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t points = 100000;
  int l1_samples = 1000000;
  std::vector<int> resolutions = {64, 128, 256, 512, 1024};
  std::string csv;
  bool force = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--points" && i + 1 < argc) {
      points = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--l1-samples" && i + 1 < argc) {
      l1_samples = std::atoi(argv[++i]);
    } else if (a == "--res" && i + 1 < argc) {
      resolutions.clear();
      std::stringstream list(argv[++i]);
      std::string item;
      while (std::getline(list, item, ',')) resolutions.push_back(std::atoi(item.c_str()));
    } else if (a == "--csv" && i + 1 < argc) {
      csv = argv[++i];
    } else if (a == "--force") {
      force = true;
    } else {
      std::fprintf(stderr, "usage: %s [--points N] [--l1-samples N] [--res 64,128,...] [--csv FILE [--force]]\n",
                   argv[0]);
      return 2;
    }
  }
  if (points == 0 || l1_samples <= 0 || resolutions.empty()) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  if (!csv.empty() && std::filesystem::exists(csv) && !force) {
    std::fprintf(stderr, "%s: %s exists; pass --force to replace it\n", argv[0], csv.c_str());
    return 1;
  }
  using benchplot::loadAverage;
  const std::string loadBefore = loadAverage();
  l1Table(l1_samples);
  ChartData chart;
  accuracyTable(points, resolutions, csv.empty() ? nullptr : &chart);
  std::printf("Load average (1, 5, 15 min) from /proc/loadavg: %s at the start, %s at the end of the tables.\n",
              loadBefore.c_str(), loadAverage().c_str());
  if (csv.empty()) return 0;
  // The chart's link (named after the CSV: scripts/plots/collide_accuracy.py writes the .png beside
  // it) and what it leaves out, for the page.
  const std::string png = std::filesystem::path(csv).replace_extension(".png").filename().string();
  std::printf("\n![misclassified points and mean distance error against ns per query, per shape and map set, one "
              "point per resolution](%s)\n\n",
              png.c_str());
  std::printf("The chart draws the accuracy table above (log-log; the labels at the points are the resolutions).");
  if (chart.zeroPoints.empty()) {
    std::printf(" Every point has a non-zero error and is drawn.\n");
  } else {
    std::printf(" Points with zero error cannot sit on a log axis and are left out:");
    for (std::size_t i = 0; i < chart.zeroPoints.size(); ++i)
      std::printf("%s %s", i ? ";" : "", chart.zeroPoints[i].c_str());
    std::printf(".\n");
  }
  if (const std::string err = benchcsv::write(csv, chart.table); !err.empty()) {
    std::fprintf(stderr, "%s: %s\n", argv[0], err.c_str());
    return 1;
  }
  std::fprintf(stderr, "%s: wrote %s\n", argv[0], csv.c_str());
  return 0;
}
