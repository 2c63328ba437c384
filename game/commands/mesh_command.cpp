// fluiddemo mesh: particles -> triangle mesh by marching slices (fluid/surface).
//   fluiddemo mesh --in FILE --out FILE [--rc R] [--threshold T] [--cube S] [--threads N]
//                  [--block N] [--stats] [--force]
// Reads .xyz/.csv/.ply particles (fluid/io), writes .obj or .ply with normals (seams welded).
#include "game/commands.hpp"

#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mesh_io.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace game {

int meshCommand(const Args& args) {
  CLI::App app{"Turn a particle file into a closed triangle mesh (marching slices, Rosenberg & Birdwell 2008)",
               "fluiddemo mesh"};
  std::string in, out;
  fluid::SurfaceParams params;
  bool stats = false, force = false;
  app.add_option("--in", in, "particle file: .xyz (x y z per line), .csv or .ply")->required();
  app.add_option("--out", out, "mesh file to write: .obj or .ply (with normals)")->required();
  app.add_option("--rc", params.rc, "cutoff radius Rc of each particle's field (world units)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--threshold", params.threshold, "iso value T (0.2 gives radius 0.975 for Rc = 3)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--cube", params.cube, "cube edge S of the lattice (world units)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--threads", params.threads, "worker threads, 0 = all hardware threads")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  app.add_option("--block", params.blockCubes, "largest block edge in cubes, 0 = auto")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  app.add_flag("--stats", stats, "print extraction statistics");
  app.add_flag("--force", force, "replace --out if it exists");
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them reversed
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  {
    std::string ext = std::filesystem::path(out).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".obj" && ext != ".ply") {
      std::fprintf(stderr, "fluiddemo mesh: --out %s: unknown mesh format '%s' (use .obj or .ply)\n", out.c_str(),
                   ext.c_str());
      return 2;
    }
  }
  if (!force && std::filesystem::exists(out)) {
    std::fprintf(stderr, "fluiddemo mesh: %s exists; not overwriting (use --force to replace it)\n", out.c_str());
    return 1;
  }

  fluid::ParticlePositions particles;
  const fluid::IoStatus read = fluid::readParticleFile(in, particles);
  if (!read.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", read.error.c_str());
    return 1;
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
  const auto t0 = std::chrono::steady_clock::now();
  const fluid::SurfaceStatus st = extractor.extract({particles.x, particles.y, particles.z, {}, {}, {}}, params, mesh);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!st.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s: %s\n", in.c_str(), st.error.c_str());
    return 1;
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
  if (stats) {
    const fluid::SurfaceStats& s = mesh.stats;
    std::printf("particles            %zu\n", particles.size());
    std::printf("triangles            %llu\n", static_cast<unsigned long long>(s.triangles));
    std::printf("vertices             %llu (before welding block seams)\n",
                static_cast<unsigned long long>(s.vertices));
    std::printf("blocks               %u\n", s.blocks);
    std::printf("cubes visited        %llu\n", static_cast<unsigned long long>(s.cubesVisited));
    std::printf("corners evaluated    %llu (+%llu while seeding)\n",
                static_cast<unsigned long long>(s.cornersEvaluated),
                static_cast<unsigned long long>(s.seedEvaluations));
    std::printf("particles looked up  %llu\n", static_cast<unsigned long long>(s.particlesLookedUp));
    std::printf("slices alive (max)   %u, sweep reversals %llu\n", s.maxActiveSlices,
                static_cast<unsigned long long>(s.slabReversals));
    std::printf("corner caches        %.3f MB (largest block)\n", double(s.cornerCacheBytesPeakBlock) / 1e6);
    std::printf("particle cache       %.3f MB (largest block)\n", double(s.particleCacheBytesPeakBlock) / 1e6);
    std::printf("working memory       %.3f MB (all workers)\n", double(s.workingBytesAllWorkers) / 1e6);
    std::printf("time                 %.3f ms\n", ms);
    // The block phases are summed over blocks: on several threads they can add up to more than the time.
    const char* summed = s.blocks > 1 ? ", summed over blocks" : "";
    std::printf("  prepare            %.3f ms (checks, particle sort, block lists)\n", s.prepareMs);
    std::printf("  particle cache     %.3f ms (§6 cache%s)\n", s.cacheBuildMs, summed);
    std::printf("  seeding            %.3f ms (§4 seeding%s)\n", s.seedMs, summed);
    std::printf("  march              %.3f ms (with corner evaluations%s)\n", s.marchMs, summed);
    std::printf("  gather             %.3f ms\n", s.gatherMs);
  }
  return 0;
}

}  // namespace game
