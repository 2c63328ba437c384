// fluiddemo mesh: particles -> triangle mesh by marching slices (fluid/surface).
//   fluiddemo mesh --in FILE --out FILE [--rc R] [--threshold T] [--cube S] [--threads N]
//                  [--block N] [--field auto|cache|splat] [--reps N] [--idle-ms MS] [--stats] [--force]
// Reads .xyz/.csv/.ply particles (fluid/io), writes .obj or .ply with normals (seams welded).
// --reps N times N more extractions with the same extractor after the first (warm: scratch and
// output capacity kept, as in a game meshing every frame) and prints their median and min, the first
// (cold) one separately. --idle-ms MS sleeps that long before each of them, as a game's mesher
// waits for the next frame: the threads go idle in between, and waking them is part of the time.
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"

#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mesh_io.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace game {
namespace {

// An upper bound of the particles' field (Rosenberg & Birdwell 2008 §2): each particle adds
// f(r) = (r/(sqrt2 Rc))^4 - (r/(sqrt2 Rc))^2 + 1/4, at most 1/4 (at r = 0) and 0 from r = Rc
// on, so at any point the field is at most 1/4 x the particles within Rc of it. A ball of
// radius Rc lies inside the 3x3x3 cells of edge Rc around the cell holding its centre, so
// 1/4 x the largest such 27-cell count bounds the field everywhere.
double fieldUpperBound(const fluid::ParticlePositions& particles, double rc) {
  auto cell = [rc](float v) {
    return static_cast<std::int64_t>(std::clamp(std::floor(static_cast<double>(v) / rc), -1e15, 1e15));
  };
  struct CellHash {
    std::size_t operator()(const std::array<std::int64_t, 3>& c) const {
      return static_cast<std::size_t>(c[0] * 73856093 ^ c[1] * 19349663 ^ c[2] * 83492791);
    }
  };
  std::unordered_map<std::array<std::int64_t, 3>, std::size_t, CellHash> counts;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    ++counts[{cell(particles.x[i]), cell(particles.y[i]), cell(particles.z[i])}];
  }
  std::size_t most = 0;
  for (const auto& [c, count] : counts) {
    std::size_t around = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto found = counts.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (found != counts.end()) around += found->second;
        }
    most = std::max(most, around);
  }
  return 0.25 * static_cast<double>(most);
}

}  // namespace

int meshCommand(const Args& args) {
  CLI::App app{"Turn a particle file into a closed triangle mesh (marching slices, Rosenberg & Birdwell 2008)",
               "fluiddemo mesh"};
  std::string in, out;
  fluid::SurfaceParams params;
  bool stats = false, force = false;
  int reps = 0;
  app.add_option("--in", in, "particle file: .xyz (x y z per line), .csv or .ply")->required();
  app.add_option("--out", out, "mesh file to write: .obj or .ply (with normals)")->required();
  app.add_option("--rc", params.rc, "cutoff radius Rc of each particle's field (world units)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--threshold", params.threshold, "iso value T (0.2 gives radius 0.975 for Rc = 3)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--cube", params.cube, "cube edge S of the lattice (world units)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--threads", params.threads, "worker threads, 0 = all hardware threads")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  app.add_option("--block", params.blockCubes, "largest block edge in cubes, 0 = auto")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  std::string field = "auto";
  app.add_option("--field", field, "how corner fields are summed: auto, cache (paper §6 cache) or splat (slice splat)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cache", "splat"}));
  app.add_option("--reps", reps, "time N warm extractions after the first and print their median and min")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  double idle_ms = 0.0;
  app.add_option("--idle-ms", idle_ms, "with --reps: sleep this long before each timed extraction (a frame's idle)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("--stats", stats, "print extraction statistics");
  app.add_flag("--force", force, "replace --out if it exists");
  if (const int code = parseCommandLine(app, "mesh", args); code >= 0) return code;
  params.fieldRoute = field == "splat"   ? fluid::SurfaceFieldRoute::sliceSplat
                      : field == "cache" ? fluid::SurfaceFieldRoute::particleCache
                                         : fluid::SurfaceFieldRoute::automatic;
  {
    std::string ext = std::filesystem::path(out).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".obj" && ext != ".ply") {
      std::fprintf(stderr, "fluiddemo mesh: --out %s: unknown mesh format '%s' (use .obj or .ply)\n", out.c_str(),
                   ext.c_str());
      return 2;
    }
  }
  if (const int code = checkOutputFile("mesh", "--out", out, force); code >= 0) return code;

  fluid::ParticlePositions particles;
  const fluid::IoStatus read = fluid::readParticleFile(in, particles);
  if (!read.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", read.error.c_str());
    return 1;
  }
  // A threshold the field can never exceed is a usage error, not an empty mesh. (Any T < 1/4 is
  // reached at a lone particle's centre, so only larger ones need the count.)
  if (!particles.empty() && params.threshold >= 0.25f && params.rc > 0.0f) {
    const double bound = fieldUpperBound(particles, params.rc);
    if (params.threshold >= bound) {
      std::fprintf(stderr,
                   "fluiddemo mesh: --threshold %g is at or above the largest value the field of %s can reach "
                   "(%g: at most 0.25 per particle within Rc of a point), so the mesh would be empty\n",
                   static_cast<double>(params.threshold), in.c_str(), bound);
      return 2;
    }
  }
  // Keep float vertices precise for data far from the origin: mesh around the particles' centre
  // (a lattice point, so the lattice and the triangles do not change), add it back on writing.
  if (!particles.empty()) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const double p[3] = {particles.x[i], particles.y[i], particles.z[i]};
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    }
    const double s = params.cube;
    params.originX = std::round(0.5 * (lo[0] + hi[0]) / s) * s;
    params.originY = std::round(0.5 * (lo[1] + hi[1]) / s) * s;
    params.originZ = std::round(0.5 * (lo[2] + hi[2]) / s) * s;
  }

  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  const fluid::SurfaceInput input{particles.x, particles.y, particles.z, {}, {}, {}};
  auto timedExtract = [&](double& ms) {
    const auto t0 = std::chrono::steady_clock::now();
    const fluid::SurfaceStatus st = extractor.extract(input, params, mesh);
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return st;
  };
  double ms = 0;
  if (const fluid::SurfaceStatus st = timedExtract(ms); !st.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s: %s\n", in.c_str(), st.error.c_str());
    return 1;
  }
  if (reps > 0) {
    std::vector<double> warm(static_cast<std::size_t>(reps));
    for (double& w : warm) {
      if (idle_ms > 0.0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(idle_ms));
      (void)timedExtract(w);  // same input and params: cannot fail where the first did not
    }
    std::sort(warm.begin(), warm.end());
    const std::size_t n = warm.size();
    const double med = n % 2 ? warm[n / 2] : 0.5 * (warm[n / 2 - 1] + warm[n / 2]);
    std::printf("first (cold)         %.3f ms\n", ms);
    std::printf("warm, %d reps         median %.3f ms, min %.3f ms", reps, med, warm.front());
    if (idle_ms > 0.0) std::printf(", each after %g ms idle", idle_ms);
    std::printf("\n");
  }
  fluid::MeshWriteOptions options;
  options.overwrite = force ? fluid::OverwritePolicy::replace : fluid::OverwritePolicy::refuse;
  options.originX = params.originX;
  options.originY = params.originY;
  options.originZ = params.originZ;
  const fluid::IoStatus written = fluid::writeSurfaceMesh(out, mesh, options);
  if (!written.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", written.error.c_str());
    return 1;
  }
  if (mesh.indices.empty()) {
    std::fprintf(stderr, "fluiddemo mesh: warning: %s: the mesh is empty (the field exceeds --threshold %g nowhere)\n",
                 in.c_str(), static_cast<double>(params.threshold));
  }
  if (stats) {
    const fluid::SurfaceStats& s = mesh.stats;
    std::printf("particles            %zu\n", particles.size());
    std::printf("triangles            %llu\n", static_cast<unsigned long long>(s.triangles));
    std::printf("vertices             %llu (before welding block seams)\n",
                static_cast<unsigned long long>(s.vertices));
    std::printf("blocks               %u (%u with the slice-splat field route)\n", s.blocks, s.splatBlocks);
    std::printf("cubes visited        %llu\n", static_cast<unsigned long long>(s.cubesVisited));
    std::printf("corners evaluated    %llu (+%llu while seeding)\n",
                static_cast<unsigned long long>(s.cornersEvaluated),
                static_cast<unsigned long long>(s.seedEvaluations));
    std::printf("particles looked up  %llu\n", static_cast<unsigned long long>(s.particlesLookedUp));
    std::printf("slices alive (max)   %u, sweep reversals %llu\n", s.maxActiveSlices,
                static_cast<unsigned long long>(s.slabReversals));
    std::printf("corner caches        %.3f MB (largest block)\n", double(s.cornerCacheBytesPeakBlock) / 1e6);
    std::printf("particle cache       %.3f MB (largest block%s)\n", double(s.particleCacheBytesPeakBlock) / 1e6,
                s.splatBlocks ? "; slice splat: its field planes" : "");
    std::printf("working memory       %.3f MB (all workers)\n", double(s.workingBytesAllWorkers) / 1e6);
    std::printf("time                 %.3f ms\n", ms);
    // The block phases are summed over blocks: on several threads they can add up to more than the time.
    const char* summed = s.blocks > 1 ? ", summed over blocks" : "";
    std::printf("  prepare            %.3f ms (checks, particle sort, block lists)\n", s.prepareMs);
    // With the slice-splat route the block setup phase sums the fields instead of building §6 caches.
    std::printf("  particle cache     %.3f ms (%s%s)\n", s.cacheBuildMs,
                s.splatBlocks ? "§6 caches, or slice splat's up-front block fields" : "§6 cache", summed);
    std::printf("  seeding            %.3f ms (§4 seeding%s)\n", s.seedMs, summed);
    std::printf("  march              %.3f ms (with corner evaluations%s)\n", s.marchMs, summed);
    std::printf("  gather             %.3f ms\n", s.gatherMs);
  }
  return 0;
}

}  // namespace game
