// fluiddemo render: a static particle set drawn headless by one of the four water renderers, in
// the fountain scene's lighting (engine::Lighting's sky and sun, the fountain's water colours),
// over a striped wall and floor (shaders/fluid/backdrop.*) so refraction and absorption show.
//   fluiddemo render --in FILE --method mesh|screen_space|raycast|voxel|none --out IMAGE.png
//                    [--width W --height H] [--camera x,y,z --look-at x,y,z] [--radius R]
//                    [--frames N] [--silhouette] [--drop-inner-cells] [--force]
//                    [--kernel isotropic|anisotropic --kr K --ks K --kn N --lambda L] [--ss-filter bilateral|narrow_range]
//                    [--surface-out FILE.csv]
// Prints the milliseconds of each stage (each ended by glFinish) and the renderer's GPU memory.
// --surface-out (screen_space, raycast, voxel): the first surface each pixel shows, as the
// renderer shades it (engine/fluid_render/first_surface.hpp), one CSV row per water pixel.
// The renderers are called directly (engine/fluid_render), not through the game's frame.
// `none` draws the backdrop alone: the reference for water masks (tests/bench/render_sets_docs.sh).
#include "game/commands.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"
#include "game/paths.hpp"

#include "engine/fluid_render/backdrop.hpp"
#include "engine/fluid_render/first_surface.hpp"
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "engine/fluid_render/voxel.hpp"
#include "engine/gl/gl.hpp"
#include "engine/platform/platform.hpp"
#include "engine/render/image_write.hpp"
#include "engine/render/renderer.hpp"
#include "fluid/io/particle_io.hpp"
#include "fluid/sph/anisotropy.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <CLI/CLI.hpp>
#include <sys/resource.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

namespace game {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;
constexpr float kFountainSpacing = 0.08f;  // content/scenes/fountain.json: particle_radius 0.04

double nowMs() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// "x,y,z" → vector; false for anything else (three finite numbers).
bool parseVec3(const std::string& text, glm::vec3& out) {
  std::stringstream in(text);
  std::string part;
  float v[3];
  int n = 0;
  while (std::getline(in, part, ',')) {
    if (n == 3) return false;
    char* end = nullptr;
    v[n] = std::strtof(part.c_str(), &end);
    if (part.empty() || end == part.c_str() || *end != '\0' || !std::isfinite(v[n])) return false;
    ++n;
  }
  if (n != 3) return false;
  out = {v[0], v[1], v[2]};
  return true;
}

// Median distance to the nearest other particle over up to 2000 sampled particles (a hash grid of
// cells about the mean spacing): the set's particle spacing, from which the radius defaults.
float estimateSpacing(const std::vector<glm::vec3>& p, glm::vec3 lo, glm::vec3 hi) {
  if (p.size() < 2) return 0.1f;
  const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-3f));
  const float cell = std::max(std::cbrt(extent.x * extent.y * extent.z / static_cast<float>(p.size())), 1e-4f);
  auto key = [&](glm::vec3 q) {
    const glm::ivec3 c = glm::ivec3(glm::floor((q - lo) / cell));
    return (static_cast<std::int64_t>(c.x) * 73856093) ^ (static_cast<std::int64_t>(c.y) * 19349663) ^
           (static_cast<std::int64_t>(c.z) * 83492791);
  };
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> grid;
  for (std::size_t i = 0; i < p.size(); ++i) grid[key(p[i])].push_back(static_cast<std::uint32_t>(i));
  std::vector<float> nearest;
  const std::size_t step = std::max<std::size_t>(p.size() / 2000, 1);
  for (std::size_t i = 0; i < p.size(); i += step) {
    float best = 1e30f;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto found = grid.find(key(p[i] + cell * glm::vec3(dx, dy, dz)));
          if (found == grid.end()) continue;
          for (std::uint32_t j : found->second)
            if (j != i) best = std::min(best, glm::length(p[j] - p[i]));
        }
    if (best < 1e29f) nearest.push_back(best);
  }
  if (nearest.empty()) return cell;
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return std::max(nearest[nearest.size() / 2], 1e-4f);
}

struct RenderJob {
  std::string method;
  std::vector<glm::vec3> particles;
  glm::vec3 lo{0.0f}, hi{0.0f};
  float radius = 0.0f, spacing = 0.0f;
  int width = 640, height = 360, frames = 1;
  bool drop_inner = false;
  int tile_width = 0, tile_height = 0;  // voxel: forced tile size (0 = the budget's)
  engine::FluidCamera camera;
  engine::WaterParams water;
  glm::vec3 sky{0.0f};
  engine::Backdrop backdrop;
  engine::ColourTarget target;
  // every method: anisotropic kernels (fluid/sph/anisotropy.hpp, r = 3 spacings);
  // screen_space: the depth filter.
  bool anisotropic = false;
  fluid::AnisotropyParams anisotropy;
  engine::DepthFilter filter = engine::DepthFilter::bilateral;
  // --surface-out: read back after the last frame when asked for
  bool want_surface = false;
  engine::FirstSurface surface;
};

struct Timing {
  std::vector<std::pair<std::string, double>> stages;  // summed over the timed frames
  double gpu_bytes = 0.0;
  std::vector<std::string> notes;
  void add(const std::string& name, double ms) {
    for (auto& [n, v] : stages)
      if (n == name) {
        v += ms;
        return;
      }
    stages.emplace_back(name, ms);
  }
};

// Frames -1 (warm-up, untimed) .. frames-1; `frame(timed)` draws one.
template <class Frame>
void runFrames(const RenderJob& job, Frame&& frame) {
  for (int f = -1; f < job.frames; ++f) frame(f >= 0);
}

void jobKernels(const RenderJob& job, Timing& t, fluid::Anisotropy& kernels);

bool renderMesh(RenderJob& job, const engine::FluidRenderDesc& desc, Timing& t, std::string& error) {
  engine::FluidRenderer r;
  engine::createFluidRenderer(desc, r);
  if (!r.ready) {
    error = r.error;
    return false;
  }
  fluid::SurfaceParams sp;  // the game's field: Rc = 2 spacings, T = 0.2 (iso radius 0.975 Rc / 3), cube = spacing / 2
  sp.rc = 3.0f * job.radius / 0.975f;
  sp.threshold = 0.2f;
  sp.cube = 0.5f * job.spacing;
  sp.order = fluid::SurfaceOrder::backToFront;
  sp.eye = job.camera.eye;
  sp.viewDir = -glm::vec3(glm::transpose(job.camera.view)[2]);
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  // --kernel anisotropic: the field of the ellipsoids at the smoothed centres (SurfaceInput::stretch).
  fluid::Anisotropy kernels;
  jobKernels(job, t, kernels);
  const fluid::SurfaceInput input = job.anisotropic
                                        ? fluid::SurfaceInput{fluid::pointView(kernels.centre), {}, {}, {}, kernels.g}
                                        : fluid::SurfaceInput{fluid::pointView(job.particles)};
  bool ok = true;
  runFrames(job, [&](bool timed) {
    if (!ok) return;
    const double t0 = nowMs();
    const fluid::SurfaceStatus st = extractor.extract(input, sp, mesh);
    if (!st.ok()) {
      error = "meshing failed: " + st.error;
      ok = false;
      return;
    }
    engine::drawBackdrop(job.backdrop, r.scene_fbo, job.camera, job.width, job.height, job.sky);
    engine::finishGpu();
    const double t1 = nowMs();
    engine::uploadFluidMesh(r, mesh.positions, mesh.normals, mesh.indices, error);
    engine::finishGpu();
    const double t2 = nowMs();
    engine::drawFluid(r, job.target.fbo, job.camera, job.water);
    engine::finishGpu();
    if (timed) {
      t.add("extract (CPU marching slices)", t1 - t0);
      t.add("upload mesh", t2 - t1);
      t.add("draw", nowMs() - t2);
    }
  });
  t.gpu_bytes =
      static_cast<double>(job.width) * job.height * (4 + 4 + 8) + static_cast<double>(r.vbo_bytes + r.ibo_bytes);
  t.notes.push_back(std::to_string(mesh.indices.size() / 3) + " triangles, Rc " + std::to_string(sp.rc) + ", cube " +
                    std::to_string(sp.cube));
  engine::destroyFluidRenderer(r);
  return ok;
}

template <class Renderer, class Upload, class Draw>
void timeParticleMethod(RenderJob& job, Renderer& r, Timing& t, Upload&& upload, Draw&& draw) {
  runFrames(job, [&](bool timed) {
    engine::drawBackdrop(job.backdrop, r.scene.fbo, job.camera, job.width, job.height, job.sky);
    engine::finishGpu();
    const double t0 = nowMs();
    upload();
    engine::finishGpu();
    const double t1 = nowMs();
    draw(timed);
    engine::finishGpu();
    if (timed) {
      t.add("upload particles", t1 - t0);
      t.add("draw", nowMs() - t1);
    }
  });
}

// --kernel anisotropic: the particles' kernels, computed once outside the timed frames (a warm-up
// pass, then the timed one, reported per frame as the game computes them once per frame).
void jobKernels(const RenderJob& job, Timing& t, fluid::Anisotropy& kernels) {
  if (!job.anisotropic) return;
  fluid::AnisotropyScratch scratch;
  fluid::computeAnisotropy(job.particles, job.anisotropy, scratch, kernels);
  const double a0 = nowMs();
  fluid::computeAnisotropy(job.particles, job.anisotropy, scratch, kernels);
  t.add("anisotropy (CPU)", (nowMs() - a0) * job.frames);
  t.notes.push_back("anisotropic kernels: " + std::to_string(kernels.stretched) + " of " +
                    std::to_string(job.particles.size()) + " stretched");
}

bool renderVoxel(RenderJob& job, const engine::FluidRenderDesc& base, Timing& t, std::string& error) {
  engine::VoxelDesc desc;
  desc.base = base;
  desc.tile_width = job.tile_width;
  desc.tile_height = job.tile_height;
  engine::VoxelRenderer r;
  engine::createVoxelRenderer(desc, r);
  if (!r.ready) {
    error = r.error;
    return false;
  }
  engine::VoxelParams p;
  p.radius = job.radius;
  p.min_gap = job.radius;
  p.filter_radius = 1.5f * job.radius;  // enough rounds to smooth a lattice's bumps (spacing 1.5 R)
  p.time_stages = true;
  const float cell = job.drop_inner ? 3.0f * job.spacing : 0.0f;  // about 27 particles per full cell
  fluid::Anisotropy kernels;
  jobKernels(job, t, kernels);
  bool ok = true;
  double stage_ms[6] = {0, 0, 0, 0, 0, 0};
  timeParticleMethod(
      job, r, t,
      [&] {
        ok = ok && (job.anisotropic
                        ? engine::uploadVoxelEllipsoids(r, kernels.centre, kernels.g, kernels.max_axis, cell, 0, error)
                        : engine::uploadVoxelParticles(r, job.particles, cell, 0, error));
      },
      [&](bool timed) {
        engine::drawVoxelFluid(r, job.target.fbo, job.camera, job.water, p);
        if (!timed) return;
        const engine::VoxelStats& s = r.stats;
        const double ms[6] = {s.splat_ms, s.compress_ms, s.connect_ms, s.filter_ms, s.normals_ms, s.shade_ms};
        for (int i = 0; i < 6; ++i) stage_ms[i] += ms[i];
      });
  if (ok && job.want_surface) engine::readVoxelFirstSurface(r, job.camera, job.surface);
  const engine::VoxelStats& s = r.stats;
  const char* names[6] = {"splat", "compress", "connect", "filter", "normals", "shade"};
  for (int i = 0; i < 6; ++i) t.add(std::string("  ") + names[i], stage_ms[i]);
  t.gpu_bytes = static_cast<double>(s.tile_grid_bytes + s.span_bytes) + 16.0 * s.particles +
                static_cast<double>(job.width) * job.height * 8;
  char line[512];
  std::snprintf(line, sizeof line,
                "voxel grid %dx%dx%d (%d words per column, angle %.1f deg, depth %.3f..%.3f m); tiles %d of %dx%d",
                job.width, job.height, s.layers, s.words, static_cast<double>(s.angle_degrees),
                static_cast<double>(s.nearest), static_cast<double>(s.farthest), s.tiles, s.tile_width, s.tile_height);
  t.notes.push_back(line);
  std::snprintf(line, sizeof line,
                "voxel memory: tile grid %.2f MiB, stored spans %.2f MiB (%d per pixel; %llu spans, %llu columns "
                "overflowing), dense grid at this resolution %.2f MiB",
                s.tile_grid_bytes / kMiB, s.span_bytes / kMiB, desc.max_spans,
                static_cast<unsigned long long>(s.stored_spans), static_cast<unsigned long long>(s.overflow_columns),
                s.dense_grid_bytes / kMiB);
  t.notes.push_back(line);
  std::snprintf(
      line, sizeof line, "particles splatted %u of %u%s", s.splatted, s.particles,
      job.drop_inner
          ? (", and " + std::to_string(s.inner_cells) + " spheres for the full inner cells left out (§4.3)").c_str()
          : "");
  t.notes.push_back(line);
  engine::destroyVoxelRenderer(r);
  return ok;
}

bool renderMethod(RenderJob& job, Timing& t, std::string& error) {
  engine::FluidRenderDesc desc;
  desc.width = job.width;
  desc.height = job.height;
  desc.shader_dir = shadersDir();
  const double px = static_cast<double>(job.width) * job.height;
  if (job.method == "none") {
    runFrames(job, [&](bool timed) {
      const double t0 = nowMs();
      engine::drawBackdrop(job.backdrop, job.target.fbo, job.camera, job.width, job.height, job.sky);
      engine::finishGpu();
      if (timed) t.add("backdrop", nowMs() - t0);
    });
    return true;
  }
  if (job.method == "mesh") return renderMesh(job, desc, t, error);
  if (job.method == "voxel") return renderVoxel(job, desc, t, error);
  bool ok = true;
  if (job.method == "screen_space") {
    engine::ScreenSpaceRenderer r;
    engine::createScreenSpaceRenderer(desc, r);
    if (!r.ready) {
      error = r.error;
      return false;
    }
    engine::ScreenSpaceParams p;
    p.radius = job.radius;
    p.filter_radius = job.radius / 0.65f;  // the game's 0.5 Rc
    // The bilateral range in the game's proportion: its 0.05 m at the fountain's 0.08 m spacing
    // (a fixed metre figure would turn the filter off for a file in other units).
    p.depth_falloff = engine::ScreenSpaceParams{}.depth_falloff * (job.spacing / kFountainSpacing);
    p.filter = job.filter;
    fluid::Anisotropy kernels;
    jobKernels(job, t, kernels);
    timeParticleMethod(
        job, r, t,
        [&] {
          ok = ok && (job.anisotropic
                          ? engine::uploadScreenSpaceEllipsoids(r, kernels.centre, kernels.g, kernels.max_axis, error)
                          : engine::uploadScreenSpaceParticles(r, job.particles, error));
        },
        [&](bool) { engine::drawScreenSpaceFluid(r, job.target.fbo, job.camera, job.water, p); });
    if (ok && job.want_surface) engine::readScreenSpaceFirstSurface(r, job.camera, job.surface);
    t.gpu_bytes = px * (4 + 4 + 4 * 4 + 4) + static_cast<double>(r.particles.capacity_bytes);
    engine::destroyScreenSpaceRenderer(r);
    return ok;
  }
  engine::RaycastDesc rdesc;
  rdesc.base = desc;
  // A still image, not a frame budget: let the pool grow to the bound's top, so that deep water
  // seen at a slant (a pool's four layers: about 50 records per pixel) drops nothing.
  rdesc.max_pool_per_pixel = 64.0f;
  engine::RaycastRenderer r;
  engine::createRaycastRenderer(rdesc, r);
  if (!r.ready) {
    error = r.error;
    return false;
  }
  engine::RaycastParams p;
  p.rc = 3.0f * job.radius / 0.975f;
  p.threshold = 0.2f;
  fluid::Anisotropy kernels;
  jobKernels(job, t, kernels);
  timeParticleMethod(
      job, r, t,
      [&] {
        ok = ok &&
             (job.anisotropic ? engine::uploadRaycastEllipsoids(r, kernels.centre, kernels.g, kernels.max_axis, error)
                              : engine::uploadRaycastParticles(r, job.particles, error));
      },
      [&](bool) { engine::drawRaycastFluid(r, job.target.fbo, job.camera, job.water, p); });
  if (ok && job.want_surface) engine::readRaycastFirstSurface(r, job.camera, job.surface);
  t.gpu_bytes = px * (4 + 4 + 4 + 16 + 4) + 16.0 * r.pool_records + static_cast<double>(r.particles.capacity_bytes);
  t.notes.push_back("raycast pool " + std::to_string(r.pool_records) + " records, asked for " + std::to_string(r.used) +
                    ", dropped " + std::to_string(r.dropped));
  engine::destroyRaycastRenderer(r);
  return ok;
}

// The fountain's look: the scene lighting's sky and sun (engine::Lighting, the fountain scene
// sets none of its own) and the water's colours of fluid_surface (game/world/fluid_surface.hpp).
// `silhouette`: as bench_fluid_render, water dark wherever there is any (the image is its mask).
void setFountainLook(bool silhouette, RenderJob& job) {
  const engine::Lighting lighting;
  job.sky = lighting.sky_horizon;
  job.water.sky_zenith = lighting.sky_zenith;
  job.water.sky_horizon = lighting.sky_horizon;
  job.water.light_direction = lighting.sun_direction;
  // the water's absorption: WaterParams' default, the game's
  if (silhouette) {
    job.water.absorption = glm::vec3(1000.0f);
    job.water.refraction = 0.0f;
    job.water.opacity = 1.0f;
  }
}

// Writes the target's pixels as a PNG; false + error.
bool writeTarget(const RenderJob& job, const std::string& out, std::string& error) {
  std::vector<std::uint8_t> pixels;
  engine::readColourTarget(job.target, pixels);
  return engine::writePngBottomUp(out, job.width, job.height, pixels, error);
}

// --surface-out: one row per pixel that shows water (bottom-up pixel rows, as GL reads them).
bool writeSurfaceCsv(const engine::FirstSurface& surface, const std::string& path, std::string& error) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) {
    error = "--surface-out " + path + ": cannot write: " + std::strerror(errno);
    return false;
  }
  std::fprintf(file, "x,y,px,py,pz,nx,ny,nz\n");
  for (int y = 0; y < surface.height; ++y)
    for (int x = 0; x < surface.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(surface.width) +
                            static_cast<std::size_t>(x);
      if (!surface.hit[i]) continue;
      const glm::vec3 p = surface.point[i], n = surface.normal[i];
      std::fprintf(file, "%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", x, y, static_cast<double>(p.x),
                   static_cast<double>(p.y), static_cast<double>(p.z), static_cast<double>(n.x),
                   static_cast<double>(n.y), static_cast<double>(n.z));
    }
  const bool written = std::ferror(file) == 0;
  if (std::fclose(file) != 0 || !written) {
    error = "--surface-out " + path + ": write failed: " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace

int renderCommand(const Args& args) {
  CLI::App app{"Draw a static particle set with one water renderer, headless, and time its stages", "fluiddemo render"};
  std::string in, out, method = "voxel", camera_text, look_text, surface_out;
  int width = 640, height = 360, frames = 1;
  float radius = 0.0f;
  bool force = false, silhouette = false, drop_inner = false;
  app.add_option("--in", in, "particle file: .xyz (x y z per line), .csv or .ply")->required();
  app.add_option("--method", method, "mesh, screen_space, raycast, voxel, or none (the backdrop alone)")
      ->capture_default_str()
      ->check(CLI::IsMember({"mesh", "screen_space", "raycast", "voxel", "none"}));
  app.add_option("--out", out, "PNG image to write")->required();
  app.add_option("--width", width, "image width, px")->capture_default_str()->check(CLI::Range(16, 8192));
  app.add_option("--height", height, "image height, px")->capture_default_str()->check(CLI::Range(16, 8192));
  app.add_option("--camera", camera_text,
                 "eye position x,y,z (default: framing the set from +x, above; the striped wall behind)");
  app.add_option("--look-at", look_text, "point looked at x,y,z (default: the set's centre)");
  app.add_option("--radius", radius,
                 "a lone particle's iso radius, metres (spheres of screen_space/voxel; Rc = 3R/0.975 of "
                 "mesh/raycast); default 0.65 x the median nearest-neighbour spacing (the game's ratio)")
      ->check(positiveNumber());
  app.add_option("--frames", frames, "timed frames after one warm-up (stage times are their mean)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_flag("--silhouette", silhouette, "opaque, dark water: the image is the water's mask (for IoU)");
  std::string tile_text;
  app.add_option("--tile-size", tile_text, "voxel: tile WxH instead of the 64 MiB budget's (paper Table 1)");
  app.add_flag("--drop-inner-cells", drop_inner, "voxel: leave full inner cells out of the splat (paper §4.3)");
  app.add_option("--surface-out", surface_out,
                 "screen_space, raycast, voxel: CSV of the first surface each water pixel shows (x,y,px,py,pz,nx,ny,nz: "
                 "pixel from the bottom-left, world point, world normal facing the eye)");
  app.add_flag("--force", force, "replace --out (and --surface-out) if it exists");
  std::string kernel = "isotropic", ss_filter = "bilateral";
  fluid::AnisotropyParams aniso;
  app.add_option("--kernel", kernel,
                 "mesh, screen_space, raycast, voxel: isotropic (spheres) or anisotropic (ellipsoids, Yu & Turk 2013; "
                 "neighbourhood radius 3 particle spacings)")
      ->capture_default_str()
      ->check(CLI::IsMember({"isotropic", "anisotropic"}));
  app.add_option("--kr", aniso.k_r, "anisotropic: largest axis ratio")
      ->capture_default_str()
      ->check(numberIn(1.0, 16.0));
  app.add_option("--ks", aniso.k_s, "anisotropic: axis scale (1: the sphere's volume)")
      ->capture_default_str()
      ->check(numberIn(0.25, 4.0));
  app.add_option("--kn", aniso.k_n, "anisotropic: neighbours needed to stretch (more than this)")
      ->capture_default_str()
      ->check(CLI::Range(0, 200));
  app.add_option("--lambda", aniso.lambda, "anisotropic: kernel centre smoothing")
      ->capture_default_str()
      ->check(numberIn(0.0, 1.0));
  app.add_option("--ss-filter", ss_filter,
                 "screen_space depth filter: bilateral or narrow_range (Truong & Yuksel 2018)")
      ->capture_default_str()
      ->check(CLI::IsMember({"bilateral", "narrow_range"}));
  if (const int code = parseCommandLine(app, "render", args); code >= 0) return code;
  glm::vec3 eye{0.0f}, target{0.0f};
  if (!camera_text.empty() && !parseVec3(camera_text, eye))
    return usageError("render", "--camera " + camera_text + ": expected three numbers x,y,z");
  if (!look_text.empty() && !parseVec3(look_text, target))
    return usageError("render", "--look-at " + look_text + ": expected three numbers x,y,z");
  int tile_w = 0, tile_h = 0;
  if (!tile_text.empty()) {
    char x = 0, extra = 0;
    if (std::sscanf(tile_text.c_str(), "%d%c%d%c", &tile_w, &x, &tile_h, &extra) != 3 || x != 'x' || tile_w < 1 ||
        tile_h < 1 || tile_w > 8192 || tile_h > 8192)
      return usageError("render", "--tile-size " + tile_text + ": expected WxH, each 1..8192");
  }
  if (const int code = checkPngOutput("render", "--out", out, force); code >= 0) return code;
  if (!surface_out.empty()) {
    if (method != "screen_space" && method != "raycast" && method != "voxel")
      return usageError("render", "--surface-out: only for --method screen_space, raycast or voxel (not " + method + ")");
    if (const int code = checkOutputFile("render", "--surface-out", surface_out, force); code >= 0) return code;
  }

  fluid::ParticlePositions read;
  if (const fluid::IoStatus st = fluid::readParticleFile(in, read); !st.ok()) {
    std::fprintf(stderr, "fluiddemo render: %s\n", st.error.c_str());
    return 1;
  }
  if (read.size() == 0) {
    std::fprintf(stderr, "fluiddemo render: --in %s: no particles in the file\n", in.c_str());
    return 1;
  }
  RenderJob job;
  job.method = method;
  job.width = width;
  job.height = height;
  job.frames = frames;
  job.drop_inner = drop_inner;
  job.want_surface = !surface_out.empty();
  job.tile_width = tile_w;
  job.tile_height = tile_h;
  job.particles.resize(read.size());
  job.lo = glm::vec3(1e30f);
  job.hi = glm::vec3(-1e30f);
  for (std::size_t i = 0; i < read.size(); ++i) {
    job.particles[i] = read[i];
    job.lo = glm::min(job.lo, job.particles[i]);
    job.hi = glm::max(job.hi, job.particles[i]);
  }
  const double t_spacing = nowMs();
  job.spacing = estimateSpacing(job.particles, job.lo, job.hi);
  job.radius = radius > 0.0f ? radius : 0.65f * job.spacing;
  if (radius > 0.0f) job.spacing = radius / 0.65f;
  const double spacing_ms = nowMs() - t_spacing;
  job.anisotropic = kernel == "anisotropic";
  job.anisotropy = aniso;
  job.anisotropy.radius = 3.0f * job.spacing;
  engine::parseDepthFilter(ss_filter, job.filter);
  const glm::vec3 centre = 0.5f * (job.lo + job.hi);
  const float extent = std::max(0.5f * glm::length(job.hi - job.lo), 4.0f * job.radius);
  if (look_text.empty()) target = centre;
  if (camera_text.empty()) eye = centre + glm::normalize(glm::vec3(1.0f, 0.45f, 0.35f)) * extent * 2.2f;
  if (glm::length(eye - target) < 1e-4f)
    return usageError("render", "--camera and --look-at are the same point: no view direction");
  job.camera.eye = eye;
  job.camera.near_plane = std::max(0.01f, 1e-3f * glm::length(eye - target));
  job.camera.far_plane = std::max(200.0f, 4.0f * (glm::length(eye - centre) + extent));
  const glm::vec3 forward = glm::normalize(target - eye);
  const glm::vec3 up = std::abs(forward.y) > 0.99f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
  job.camera.view = glm::lookAt(eye, target, up);
  job.camera.projection = glm::perspective(glm::radians(45.0f), static_cast<float>(width) / static_cast<float>(height),
                                           job.camera.near_plane, job.camera.far_plane);
  setFountainLook(silhouette, job);

  engine::PlatformDesc platform_desc;
  platform_desc.title = "fluiddemo render";
  platform_desc.width = 64;
  platform_desc.height = 64;
  platform_desc.headless = true;
  engine::Platform platform;
  std::string error;
  if (!engine::createPlatform(platform_desc, platform, error)) {
    std::fprintf(stderr, "fluiddemo render: no GL context: %s\n", error.c_str());
    return 1;
  }
  int code = 0;
  if (!engine::createBackdrop(shadersDir(), job.lo, job.hi, job.radius, eye, job.backdrop, error)) {
    std::fprintf(stderr, "fluiddemo render: backdrop shaders: %s\n", error.c_str());
    code = 1;
  }
  engine::createColourTarget(width, height, job.target);
  Timing timing;
  const double t0 = nowMs();
  if (code == 0 && !renderMethod(job, timing, error)) {
    std::fprintf(stderr, "fluiddemo render: --method %s: %s\n", method.c_str(), error.c_str());
    code = 1;
  }
  const double total_ms = nowMs() - t0;
  if (code == 0 && !writeTarget(job, out, error)) {
    std::fprintf(stderr, "fluiddemo render: %s\n", error.c_str());
    code = 1;
  }
  if (code == 0 && job.want_surface && !writeSurfaceCsv(job.surface, surface_out, error)) {
    std::fprintf(stderr, "fluiddemo render: %s\n", error.c_str());
    code = 1;
  }
  if (code == 0) {
    std::printf("render %s: %zu particles from %s, %dx%d, radius %.4g m (spacing %.4g m%s), GL %s / %s\n",
                method.c_str(), job.particles.size(), in.c_str(), width, height, static_cast<double>(job.radius),
                static_cast<double>(job.spacing), radius > 0.0f ? ", from --radius" : ", estimated",
                platform.gl_version.c_str(), platform.gl_renderer.c_str());
    std::printf("  spacing estimate      %9.2f ms (CPU)\n", spacing_ms);
    for (const auto& [name, ms] : timing.stages) std::printf("  %-22s%9.2f ms\n", name.c_str(), ms / frames);
    std::printf("  all frames (%d + 1 warm-up) %.2f ms\n", frames, total_ms);
    std::printf("  GPU memory            %9.2f MiB (the renderer's targets and buffers)\n", timing.gpu_bytes / kMiB);
    for (const std::string& note : timing.notes) std::printf("  %s\n", note.c_str());
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf("  peak memory (process) %.0f MiB (resident: particles, mesh, driver)\n",
                static_cast<double>(usage.ru_maxrss) / 1024.0);
    std::printf("wrote %s\n", out.c_str());
    if (job.want_surface) std::printf("wrote %s\n", surface_out.c_str());
  }
  engine::destroyColourTarget(job.target);
  engine::destroyBackdrop(job.backdrop);
  engine::destroyPlatform(platform);
  return code;
}

}  // namespace game
