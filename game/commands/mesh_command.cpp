// fluiddemo mesh: particles -> triangle mesh by marching slices (fluid/surface).
//   fluiddemo mesh --in FILE --out FILE [--rc R] [--threshold T] [--cube S] [--threads N]
//                  [--block N] [--field auto|cache|splat|dense|value] [--reps N] [--idle-ms MS] [--stats] [--force]
//                  [--kernel isotropic|anisotropic --kr K --ks K --kn N --lambda L --kernel-radius R]
//   fluiddemo mesh --in 'frames/frame_{}.xyz' --out 'meshes/frame_{}.obj' [--frame-jobs N] [...]
// Reads .xyz/.csv/.ply/.vtk particles (fluid/io), writes .obj, .ply, .vtk or .vtu with normals
// (seams welded). With '{}' in --in, every file matching the pattern ({} = digits) is a frame,
// meshed to --out with the same digits; existing outputs are skipped unless --force (a stopped
// run resumes), a frame that fails is named and the others are finished (exit 1).
// --reps N times N more extractions with the same extractor after the first (warm: scratch and
// output capacity kept, as in a game meshing every frame) and prints their median and min, the first
// (cold) one separately. --idle-ms MS sleeps that long before each of them, as a game's mesher
// waits for the next frame: the threads go idle in between, and waking them is part of the time.
// --kernel anisotropic meshes Yu & Turk 2013's ellipsoids (fluid/sph/anisotropy.hpp, computed once
// per file before the timed extractions) instead of spheres: SurfaceInput::stretch and the smoothed
// centres.
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"

#include "fluid/io/particle_io.hpp"
#include "fluid/sph/anisotropy.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mesh_io.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <unistd.h>

namespace game {
namespace {

std::string lowercaseExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Spheres, or Yu & Turk's anisotropic kernels with their parameters (--kernel).
struct KernelChoice {
  bool anisotropic = false;
  fluid::AnisotropyParams params;  // radius 0 = 1.5 Rc (the game's 3 spacings at Rc = 2 spacings)
};

// The extractor's input for `particles`: the positions as they are, or the kernels' smoothed
// centres and stretch (computed into `kernels`, which must outlive the input).
fluid::SurfaceInput kernelInput(const fluid::ParticlePositions& particles, const KernelChoice& choice,
                                const fluid::SurfaceParams& params, fluid::AnisotropyScratch& scratch,
                                fluid::Anisotropy& kernels) {
  if (!choice.anisotropic) return {fluid::pointView(particles)};
  fluid::AnisotropyParams a = choice.params;
  if (a.radius <= 0.0f) a.radius = 1.5f * params.rc;
  // False only for a non-finite position: every kernel is then a sphere at its particle, and the
  // extractor names the position.
  (void)fluid::computeAnisotropy(particles, a, scratch, kernels);
  return {fluid::pointView(kernels.centre), {}, {}, {}, kernels.g};
}

// One frame: read, check, extract, write. Returns 0, or the exit code of the single-file command
// (1 failure, 2 usage) with the message (without the "fluiddemo mesh: " prefix) in `error`.
int meshFile(const std::string& in, const std::string& out, fluid::SurfaceParams params, const KernelChoice& kernel,
             bool force, fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh, std::string& error) {
  fluid::ParticlePositions particles;
  if (const fluid::IoStatus read = fluid::readParticleFile(in, particles); !read.ok()) {
    error = read.error;
    return 1;
  }
  fluid::AnisotropyScratch scratch;
  fluid::Anisotropy kernels;
  const fluid::SurfaceInput input = kernelInput(particles, kernel, params, scratch, kernels);
  if (error = fluid::unreachableThreshold(input, params, "--threshold", in); !error.empty()) return 2;
  fluid::centreSurfaceOrigin(input, params);
  if (const fluid::SurfaceStatus st = extractor.extract(input, params, mesh); !st.ok()) {
    error = in + ": " + st.error;
    return 1;
  }
  fluid::MeshWriteOptions options;
  options.overwrite = force ? fluid::OverwritePolicy::replace : fluid::OverwritePolicy::refuse;
  options.originX = params.originX, options.originY = params.originY, options.originZ = params.originZ;
  if (const fluid::IoStatus written = fluid::writeSurfaceMesh(out, mesh, options); !written.ok()) {
    error = written.error;
    return 1;
  }
  return 0;
}

// Frames of a '{}' pattern: the files in its folder whose names are the pattern with digits for
// {}, in numeric order (then by name, so frame_7 and frame_007 keep a fixed order).
struct Frame {
  std::string digits, in, out;
};
std::vector<Frame> findFrames(const std::string& in_pattern, const std::string& out_pattern, std::string& error) {
  const std::filesystem::path pattern(in_pattern);
  const std::string name = pattern.filename().string();
  const std::size_t at = name.find("{}");
  if (at == std::string::npos || name.find("{}", at + 2) != std::string::npos ||
      pattern.parent_path().string().find("{}") != std::string::npos) {
    error = "--in " + in_pattern + ": a sequence pattern holds '{}' once, in the file name";
    return {};
  }
  const std::string prefix = name.substr(0, at), suffix = name.substr(at + 2);
  const std::filesystem::path folder = pattern.has_parent_path() ? pattern.parent_path() : ".";
  std::vector<Frame> frames;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string file = it->path().filename().string();
    if (file.size() <= prefix.size() + suffix.size() || file.compare(0, prefix.size(), prefix) != 0 ||
        file.compare(file.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits = file.substr(prefix.size(), file.size() - prefix.size() - suffix.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 18) continue;
    std::string out = out_pattern;
    out.replace(out.find("{}"), 2, digits);
    frames.push_back({digits, (folder / file).string(), out});
  }
  if (ec) {
    error = "--in " + in_pattern + ": cannot list " + folder.string() + ": " + ec.message();
    return {};
  }
  std::sort(frames.begin(), frames.end(), [](const Frame& a, const Frame& b) {
    const unsigned long long x = std::stoull(a.digits), y = std::stoull(b.digits);
    return x != y ? x < y : a.in < b.in;
  });
  if (frames.empty()) error = "--in " + in_pattern + ": no file matches (the pattern's {} stands for digits)";
  return frames;
}

// Meshes every frame on `jobs` workers, each with its own extractor of params.threads threads.
int meshSequence(const std::string& in_pattern, const std::string& out_pattern, const fluid::SurfaceParams& params,
                 const KernelChoice& kernel, bool force, int jobs) {
  std::string error;
  const std::vector<Frame> frames = findFrames(in_pattern, out_pattern, error);
  if (frames.empty()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", error.c_str());
    return 2;
  }
  std::vector<std::size_t> todo;
  std::error_code ec;
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (force || !std::filesystem::exists(frames[i].out, ec)) todo.push_back(i);
  const std::size_t skipped = frames.size() - todo.size();
  std::fprintf(stderr, "fluiddemo mesh: %zu frames (%s ... %s), %zu already meshed (skipped; --force remeshes them)\n",
               frames.size(), frames.front().in.c_str(), frames.back().in.c_str(), skipped);
  for (const std::size_t i : todo) {
    const std::filesystem::path folder = std::filesystem::path(frames[i].out).parent_path();
    if (!folder.empty()) std::filesystem::create_directories(folder, ec);
  }

  const bool terminal = isatty(STDERR_FILENO) != 0;
  const auto start = std::chrono::steady_clock::now();
  auto last_shown = start;
  std::mutex lock;  // guards the counters below and stderr
  std::size_t done = 0;
  std::vector<std::size_t> failed;  // frame indices
  auto progress = [&](bool final) {
    const auto now = std::chrono::steady_clock::now();
    if (!final && !terminal && now - last_shown < std::chrono::seconds(1)) return;
    last_shown = now;
    const double seconds = std::chrono::duration<double>(now - start).count();
    const double rate = seconds > 0.0 ? double(done) / seconds : 0.0;
    const double left = rate > 0.0 ? double(todo.size() - done) / rate : 0.0;
    std::fprintf(stderr, "%smesh: %zu/%zu frames, %.1f frames/s, %.0f s left%s", terminal ? "\r" : "", done,
                 todo.size(), rate, left, terminal && !final ? "" : "\n");
    std::fflush(stderr);
  };
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    fluid::SurfaceExtractor extractor;
    fluid::SurfaceMesh mesh;
    std::string message;
    for (std::size_t k; (k = next.fetch_add(1)) < todo.size();) {
      const Frame& frame = frames[todo[k]];
      const int code = meshFile(frame.in, frame.out, params, kernel, force, extractor, mesh, message);
      std::lock_guard<std::mutex> guard(lock);
      ++done;
      if (code != 0) {
        failed.push_back(todo[k]);
        std::fprintf(stderr, "%sfluiddemo mesh: frame %s failed: %s\n", terminal ? "\r" : "", frame.digits.c_str(),
                     message.c_str());
      }
      progress(false);
    }
  };
  const int workers = std::max(1, std::min<int>(jobs, static_cast<int>(todo.size())));
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  progress(true);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("meshed %zu frames in %.2f s (%zu skipped, %zu failed)\n", todo.size() - failed.size(), seconds, skipped,
              failed.size());
  if (!failed.empty()) {
    std::sort(failed.begin(), failed.end());
    std::fprintf(stderr, "fluiddemo mesh: %zu of %zu frames failed, the first %s\n", failed.size(), frames.size(),
                 frames[failed.front()].in.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

int meshCommand(const Args& args) {
  CLI::App app{"Turn a particle file into a closed triangle mesh (marching slices, Rosenberg & Birdwell 2008)",
               "fluiddemo mesh"};
  std::string in, out;
  fluid::SurfaceParams params;
  bool stats = false, force = false;
  int reps = 0;
  app.add_option("--in", in,
                 "particle file: .xyz (x y z per line), .csv, .ply or legacy .vtk; or a sequence pattern "
                 "'frames/frame_{}.xyz' ({} = the frame's digits)")
      ->required();
  app.add_option("--out", out,
                 "mesh file to write: .obj, .ply, .vtk or .vtu (with normals); with a sequence, a pattern "
                 "'meshes/frame_{}.obj' (existing frames are skipped unless --force)")
      ->required();
  app.add_option("--rc", params.rc, "cutoff radius Rc of each particle's field (world units)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--threshold", params.threshold, "iso value T (0.2 gives radius 0.975 for Rc = 3)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--cube", params.cube, "cube edge S of the lattice (world units)")
      ->capture_default_str()
      ->check(positiveNumber());
  app.add_option("--threads", params.threads, "worker threads, 0 = all the cores this process may run on")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  app.add_option("--block", params.blockCubes, "largest block edge in cubes, 0 = auto")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  std::string field = "auto";
  app.add_option("--field", field, "how corner fields are summed: auto, cache (paper §6 cache), splat (slice splat), dense (slice splat, "
                 "then every interior cube scanned instead of seeded and walked) or value (the dense scan on the field's "
                 "value alone, normals by central differences: faster, not bit-equal to the others)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cache", "splat", "dense", "value"}));
  app.add_option("--reps", reps, "time N warm extractions after the first and print their median and min")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  double idle_ms = 0.0;
  app.add_option("--idle-ms", idle_ms, "with --reps: sleep this long before each timed extraction (a frame's idle)")
      ->capture_default_str()
      ->check(numberIn(0.0, 1000.0));
  int frame_jobs = 0;
  app.add_option("--frame-jobs", frame_jobs,
                 "sequences: frames meshed at once, each on --threads / N threads; 0 = one frame per thread "
                 "(faster than all threads on each frame in turn: docs/use-the-libraries.md)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  std::string kernel_name = "isotropic";
  KernelChoice kernel;
  app.add_option("--kernel", kernel_name,
                 "each particle's kernel: isotropic (spheres) or anisotropic (Yu & Turk 2013 ellipsoids along its "
                 "neighbourhood, centres smoothed)")
      ->capture_default_str()
      ->check(CLI::IsMember({"isotropic", "anisotropic"}));
  app.add_option("--kr", kernel.params.k_r, "anisotropic: largest ratio of a kernel's longest axis to its shortest")
      ->capture_default_str()
      ->check(numberIn(1.0, 16.0));
  app.add_option("--ks", kernel.params.k_s, "anisotropic: scale of a stretched kernel's axes (1: the sphere's volume)")
      ->capture_default_str()
      ->check(numberIn(0.25, 4.0));
  app.add_option("--kn", kernel.params.k_n, "anisotropic: a particle with this many neighbours or fewer stays a sphere")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  app.add_option("--lambda", kernel.params.lambda, "anisotropic: kernel centre smoothing towards the neighbours' mean")
      ->capture_default_str()
      ->check(numberIn(0.0, 1.0));
  app.add_option("--kernel-radius", kernel.params.radius,
                 "anisotropic: neighbourhood radius r of each particle's PCA (world units); default 1.5 x --rc "
                 "(3 particle spacings at the game's Rc = 2 spacings)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--stats", stats, "print extraction statistics");
  app.add_flag("--force", force, "replace --out if it exists (sequences: remesh frames already meshed)");
  if (const int code = parseCommandLine(app, "mesh", args); code >= 0) return code;
  kernel.anisotropic = kernel_name == "anisotropic";
  params.fieldRoute = field == "splat"   ? fluid::SurfaceFieldRoute::sliceSplat
                      : field == "cache" ? fluid::SurfaceFieldRoute::particleCache
                      : field == "dense" ? fluid::SurfaceFieldRoute::denseScan
                      : field == "value" ? fluid::SurfaceFieldRoute::valueScan
                                         : fluid::SurfaceFieldRoute::automatic;
  if (const std::string ext = lowercaseExtension(out); ext != ".obj" && ext != ".ply" && ext != ".vtk" && ext != ".vtu") {
    std::fprintf(stderr, "fluiddemo mesh: --out %s: unknown mesh format '%s' (use .obj, .ply, .vtk or .vtu)\n",
                 out.c_str(), ext.c_str());
    return 2;
  }
  const bool sequence_in = in.find("{}") != std::string::npos, sequence_out = out.find("{}") != std::string::npos;
  if (sequence_in != sequence_out)
    return usageError("mesh", "--in and --out are both sequence patterns (with '{}') or both files");
  if (sequence_in) {
    if (reps > 0 || stats) return usageError("mesh", "--reps and --stats take one file, not a sequence");
    const int threads = fluid::surfaceThreads(params);
    const int jobs = frame_jobs > 0 ? std::min(frame_jobs, threads) : threads;
    params.threads = std::max(1, threads / jobs);
    return meshSequence(in, out, params, kernel, force, jobs);
  }
  if (const int code = checkOutputFile("mesh", "--out", out, force); code >= 0) return code;

  fluid::ParticlePositions particles;
  const fluid::IoStatus read = fluid::readParticleFile(in, particles);
  if (!read.ok()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", read.error.c_str());
    return 1;
  }
  fluid::AnisotropyScratch kernel_scratch;
  fluid::Anisotropy kernels;
  const auto k0 = std::chrono::steady_clock::now();
  const fluid::SurfaceInput input = kernelInput(particles, kernel, params, kernel_scratch, kernels);
  const double kernel_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - k0).count();
  // A threshold the field can never exceed is a usage error, not an empty mesh.
  if (const std::string unreachable = fluid::unreachableThreshold(input, params, "--threshold", in);
      !unreachable.empty()) {
    std::fprintf(stderr, "fluiddemo mesh: %s\n", unreachable.c_str());
    return 2;
  }
  // Keep float vertices precise for data far from the origin: mesh around the particles' centre
  // (a lattice point, so the lattice and the triangles do not change), add it back on writing.
  fluid::centreSurfaceOrigin(input, params);

  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
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
    if (kernel.anisotropic)
      std::printf("anisotropic kernels  %zu of %zu stretched, %.3f ms (one pass, untimed above)\n", kernels.stretched,
                  particles.size(), kernel_ms);
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
