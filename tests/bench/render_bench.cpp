// The three fluid renderers side by side on llvmpipe (docs/render.md): ms per frame, picture
// difference against the mesh method (PSNR over RGB, IoU of the water masks) and GPU memory, at
// two viewport sizes and three particle counts grown from tests/data/fountain.xyz (2.5k: its
// first 2500 particles; 13k and 50k: copies of the set tiled on a grid in x/z).
//   usage: bench_fluid_render [--frames N] [--sizes 640x360,1280x720] [--counts 2500,13000,50000]
//                             [--pool RECORDS_PER_PIXEL] [--png DIR]  (PNGs: first size and count)
// Static particle sets (no simulation): each configuration renders 1 warm-up frame and N timed
// frames, each ended by glFinish. "mesh" is timed twice: the extraction on the CPU (2 threads)
// and the GL frame (upload + draw); the particle methods have no extraction.
#include "engine/fluid_render/fluid_render.hpp"
#include "engine/fluid_render/raycast.hpp"
#include "engine/fluid_render/screen_space.hpp"
#include "engine/render/image_write.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace engine;

namespace {

// The game's fountain field: particle radius 0.04 m, spacing 0.08, Rc = 2 spacings, T = 0.2.
constexpr float kSpacing = 0.08f, kRc = 2.0f * kSpacing, kThreshold = 0.2f;
constexpr double kFileRc = 3.0;  // tests/data/README.md: the sets are made for Rc = 3

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

bool readXyz(const std::filesystem::path& path, std::vector<glm::vec3>& out, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path.string() + ": cannot open";
    return false;
  }
  glm::vec3 p;
  while (in >> p.x >> p.y >> p.z) out.push_back(p * static_cast<float>(kRc / kFileRc));
  if (out.empty()) error = path.string() + ": no points";
  return !out.empty();
}

// `count` particles: the base set tiled on a square grid in x/z (cells 1.2 x its extent).
std::vector<glm::vec3> grow(const std::vector<glm::vec3>& base, std::size_t count) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : base) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 cell = (hi - lo) * 1.2f;
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count) / base.size())));
  std::vector<glm::vec3> out;
  for (int t = 0; out.size() < count; ++t) {
    const glm::vec3 offset(static_cast<float>(t % side) * cell.x, 0.0f, static_cast<float>(t / side) * cell.z);
    for (std::size_t i = 0; i < base.size() && out.size() < count; ++i) out.push_back(base[i] + offset - lo);
  }
  return out;
}

struct Backdrop {
  GLuint program = 0, vao = 0, vbo = 0;
};

// Floor under the set and a wall behind it (seen from +z), striped by backdrop.frag.
bool createBackdrop(const std::vector<glm::vec3>& particles, Backdrop& b, std::string& error) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : particles) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  lo -= glm::vec3(2.0f * kRc);
  hi += glm::vec3(2.0f * kRc);
  const float e = std::max(hi.x - lo.x, hi.z - lo.z);
  const float y0 = lo.y, x0 = lo.x - e, x1 = hi.x + e, z0 = lo.z, z1 = hi.z + 3.0f * e, y1 = hi.y + e;
  const float v[] = {x0, y0, z0, x1, y0, z0, x1, y0, z1, x0, y0, z0, x1, y0, z1, x0, y0, z1,
                     x0, y0, z0, x1, y0, z0, x1, y1, z0, x0, y0, z0, x1, y1, z0, x0, y1, z0};
  const std::filesystem::path dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders" / "fluid";
  b.program = buildProgram(std::vector<ShaderStageFiles>{{GL_VERTEX_SHADER, {dir / "backdrop.vert"}},
                                                         {GL_FRAGMENT_SHADER, {dir / "backdrop.frag"}}},
                           "", error);
  glGenVertexArrays(1, &b.vao);
  glGenBuffers(1, &b.vbo);
  glBindVertexArray(b.vao);
  glBindBuffer(GL_ARRAY_BUFFER, b.vbo);
  glBufferData(GL_ARRAY_BUFFER, sizeof(v), v, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, nullptr);
  glBindVertexArray(0);
  return b.program != 0;
}

void destroyBackdrop(Backdrop& b) {
  glDeleteProgram(b.program);
  glDeleteBuffers(1, &b.vbo);
  glDeleteVertexArrays(1, &b.vao);
  b = Backdrop{};
}

void drawBackdrop(const Backdrop& b, GLuint fbo, const FluidCamera& camera, int w, int h) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, w, h);
  glClearColor(0.1f, 0.1f, 0.12f, 1.0f);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(b.program);
  const glm::mat4 vp = camera.projection * camera.view;
  glUniformMatrix4fv(glGetUniformLocation(b.program, "u_view_projection"), 1, GL_FALSE, glm::value_ptr(vp));
  glBindVertexArray(b.vao);
  glDrawArrays(GL_TRIANGLES, 0, 12);
  glBindVertexArray(0);
  glDisable(GL_DEPTH_TEST);
}

// Camera on +z and above, framing the set's bounding box.
FluidCamera frame(const std::vector<glm::vec3>& particles, int w, int h) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : particles) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo);
  FluidCamera c;
  c.eye = centre + glm::normalize(glm::vec3(0.35f, 0.45f, 1.0f)) * radius * 2.2f;
  c.near_plane = 0.05f;
  c.far_plane = 200.0f;
  c.view = glm::lookAt(c.eye, centre, glm::vec3(0, 1, 0));
  c.projection =
      glm::perspective(glm::radians(45.0f), static_cast<float>(w) / static_cast<float>(h), c.near_plane, c.far_plane);
  return c;
}

struct Target {
  GLuint fbo = 0, texture = 0;
};

Target makeTarget(int w, int h) {
  Target t;
  t.texture = createTexture2D(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &t.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.texture, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return t;
}

std::vector<std::uint8_t> readTarget(const Target& t, int w, int h) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return px;
}

struct Result {
  double extract_ms = 0.0, frame_ms = 0.0;
  double mib = 0.0;  // GPU memory the renderer allocated (targets, buffers, pool)
  std::uint64_t dropped = 0, records = 0;
  std::vector<std::uint8_t> image;
  std::vector<std::uint8_t> silhouette;  // the same frame with silhouetteWater() (for the mask IoU)
};

// Water that is dark wherever it is at all (opaque, unrefracted, absorbing 1000/m), so the mask
// of pixels that differ from the backdrop is the silhouette, whatever the thickness.
WaterParams silhouetteWater() {
  WaterParams w;
  w.absorption = glm::vec3(1000.0f);
  w.refraction = 0.0f;
  w.opacity = 1.0f;
  return w;
}

constexpr double kMiB = 1024.0 * 1024.0;

// Renders `frames` timed frames (after one warm-up) of `method`; the image of the last one.
Result run(FluidMethod method, const std::vector<glm::vec3>& particles, const Backdrop& backdrop, int w, int h,
           int frames, float pool_per_pixel) {
  Result res;
  FluidRenderDesc desc;
  desc.width = w;
  desc.height = h;
  desc.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
  const FluidCamera camera = frame(particles, w, h);
  const WaterParams water;
  Target target = makeTarget(w, h);
  const double px = static_cast<double>(w) * h;
  std::string error;
  if (method == FluidMethod::mesh) {
    FluidRenderer r;
    createFluidRenderer(desc, r);
    fluid::SurfaceExtractor extractor;
    fluid::SurfaceMesh mesh;
    fluid::SurfaceParams sp;
    sp.rc = kRc;
    sp.threshold = kThreshold;
    sp.cube = 0.5f * kSpacing;
    sp.threads = 2;
    sp.order = fluid::SurfaceOrder::backToFront;
    sp.eye = camera.eye;
    sp.viewDir = -glm::vec3(glm::transpose(camera.view)[2]);
    for (int f = -1; f < frames; ++f) {
      const double t0 = now();
      extractor.extract({fluid::pointView(particles)}, sp, mesh);
      const double t1 = now();
      drawBackdrop(backdrop, r.scene_fbo, camera, w, h);
      uploadFluidMesh(r, mesh.positions, mesh.normals, mesh.indices, error);
      drawFluid(r, target.fbo, camera, water);
      glFinish();
      if (f >= 0) {
        res.extract_ms += (t1 - t0) * 1e3 / frames;
        res.frame_ms += (now() - t1) * 1e3 / frames;
      }
    }
    res.image = readTarget(target, w, h);
    drawBackdrop(backdrop, r.scene_fbo, camera, w, h);
    drawFluid(r, target.fbo, camera, silhouetteWater());
    res.silhouette = readTarget(target, w, h);
    res.mib = (px * (4 + 4 + 8) + static_cast<double>(r.vbo_bytes + r.ibo_bytes)) / kMiB;
    destroyFluidRenderer(r);
  } else if (method == FluidMethod::screen_space) {
    ScreenSpaceRenderer r;
    createScreenSpaceRenderer(desc, r);
    ScreenSpaceParams p;
    p.radius = 0.975f * kRc / 3.0f;
    p.filter_radius = 0.5f * kRc;
    for (int f = -1; f < frames; ++f) {
      const double t0 = now();
      drawBackdrop(backdrop, r.scene.fbo, camera, w, h);
      uploadScreenSpaceParticles(r, particles, error);
      drawScreenSpaceFluid(r, target.fbo, camera, water, p);
      glFinish();
      if (f >= 0) res.frame_ms += (now() - t0) * 1e3 / frames;
    }
    res.image = readTarget(target, w, h);
    drawBackdrop(backdrop, r.scene.fbo, camera, w, h);
    drawScreenSpaceFluid(r, target.fbo, camera, silhouetteWater(), p);
    res.silhouette = readTarget(target, w, h);
    // scene RGBA8 + D24, own D24, two R32F depth, R32F thickness; particles
    res.mib = (px * (4 + 4 + 4 + 8 + 4) + static_cast<double>(r.particles.capacity_bytes)) / kMiB;
    destroyScreenSpaceRenderer(r);
  } else {
    RaycastDesc rd;
    rd.base = desc;
    rd.pool_per_pixel = pool_per_pixel;
    RaycastRenderer r;
    createRaycastRenderer(rd, r);
    RaycastParams p;
    p.rc = kRc;
    p.threshold = kThreshold;
    p.grow_pool = false;  // a fixed --pool: the records column is the demand, the memory column that pool
    for (int f = -1; f < frames; ++f) {
      const double t0 = now();
      drawBackdrop(backdrop, r.scene.fbo, camera, w, h);
      uploadRaycastParticles(r, particles, error);
      drawRaycastFluid(r, target.fbo, camera, water, p);
      glFinish();
      if (f >= 0) res.frame_ms += (now() - t0) * 1e3 / frames;
    }
    res.records = r.used;
    res.dropped = r.dropped;
    res.image = readTarget(target, w, h);
    drawBackdrop(backdrop, r.scene.fbo, camera, w, h);
    drawRaycastFluid(r, target.fbo, camera, silhouetteWater(), p);
    res.silhouette = readTarget(target, w, h);
    // scene RGBA8 + D24, heads R32UI, hits RGBA32F, thickness R32F; pool; counters; particles
    res.mib =
        (px * (4 + 4 + 4 + 16 + 4) + 16.0 * r.pool_records + 8 + static_cast<double>(r.particles.capacity_bytes)) /
        kMiB;
    destroyRaycastRenderer(r);
  }
  if (!error.empty()) std::fprintf(stderr, "%s: %s\n", fluidMethodName(method), error.c_str());
  glDeleteFramebuffers(1, &target.fbo);
  glDeleteTextures(1, &target.texture);
  return res;
}

// "records (records per pixel) / dropped" for the table.
std::string perPixel(std::uint64_t records, std::uint64_t dropped, int pixels) {
  char text[96];
  std::snprintf(text, sizeof text, "%llu (%.1f) / %llu", static_cast<unsigned long long>(records),
                static_cast<double>(records) / pixels, static_cast<unsigned long long>(dropped));
  return text;
}

// Backdrop alone through the mesh renderer with no mesh: the "no water" reference for masks.
std::vector<std::uint8_t> background(const std::vector<glm::vec3>& particles, const Backdrop& backdrop, int w, int h) {
  FluidRenderDesc desc;
  desc.width = w;
  desc.height = h;
  desc.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
  FluidRenderer r;
  createFluidRenderer(desc, r);
  Target target = makeTarget(w, h);
  drawBackdrop(backdrop, r.scene_fbo, frame(particles, w, h), w, h);
  std::string error;
  uploadFluidMesh(r, {}, {}, {}, error);
  drawFluid(r, target.fbo, frame(particles, w, h), WaterParams{});
  auto px = readTarget(target, w, h);
  destroyFluidRenderer(r);
  glDeleteFramebuffers(1, &target.fbo);
  glDeleteTextures(1, &target.texture);
  return px;
}

double psnr(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double se = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); i += 4)
    for (std::size_t c = 0; c < 3; ++c, ++n) se += std::pow(double(a[i + c]) - double(b[i + c]), 2.0);
  const double mse = se / static_cast<double>(n);
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

// IoU of the water masks (pixels differing from the background by more than 2/255), taken
// from the silhouette frames.
double maskIou(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
               const std::vector<std::uint8_t>& bg) {
  std::size_t both = 0, either = 0;
  for (std::size_t i = 0; i < a.size(); i += 4) {
    bool wa = false, wb = false;
    for (std::size_t c = 0; c < 3; ++c) {
      wa |= std::abs(int(a[i + c]) - int(bg[i + c])) > 2;
      wb |= std::abs(int(b[i + c]) - int(bg[i + c])) > 2;
    }
    both += wa && wb;
    either += wa || wb;
  }
  return either == 0 ? 0.0 : static_cast<double>(both) / static_cast<double>(either);
}

template <typename T>
std::vector<T> parseList(const std::string& text, char sep_inner) {
  std::vector<T> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if constexpr (std::is_same_v<T, glm::ivec2>) {
      const auto x = item.find(sep_inner);
      out.push_back({std::stoi(item.substr(0, x)), std::stoi(item.substr(x + 1))});
    } else {
      out.push_back(static_cast<T>(std::stoul(item)));
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 3;
  std::vector<glm::ivec2> sizes{{640, 360}, {1280, 720}};
  std::vector<std::size_t> counts{2500, 13000, 50000};
  std::filesystem::path png_dir;
  float pool = 24.0f;  // raycast pool records per pixel, fixed (the game starts at 2 and grows to the demand)
  try {
    for (int i = 1; i + 1 < argc; i += 2) {
      const std::string key = argv[i], value = argv[i + 1];
      if (key == "--frames") {
        frames = std::clamp(std::stoi(value), 1, 100);
      } else if (key == "--sizes") {
        sizes = parseList<glm::ivec2>(value, 'x');
      } else if (key == "--counts") {
        counts = parseList<std::size_t>(value, 'x');
      } else if (key == "--pool") {
        pool = std::clamp(std::stof(value), 0.01f, 64.0f);
      } else if (key == "--png") {
        png_dir = value;
      } else {
        std::fprintf(stderr, "unknown option %s\n", key.c_str());
        return 2;
      }
    }
  } catch (const std::exception&) {
    std::fprintf(stderr, "bad option value (e.g. --sizes 640x360,1280x720 --counts 2500,13000)\n");
    return 2;
  }
  gputest::GlContext ctx;
  gputest::createContext(ctx);
  if (!ctx.ok()) {
    std::fprintf(stderr, "no GL context: %s\n", ctx.error.c_str());
    return 1;
  }
  std::vector<glm::vec3> base;
  std::string error;
  if (!readXyz(std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "tests/data/fountain.xyz", base, error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf(
      "GL: %s; %d timed frame(s) per row after 1 warm-up, each ended by glFinish; raycast pool %.0f "
      "records per pixel\n\n",
      ctx.version.c_str(), frames, pool);
  std::printf(
      "| particles | size | method | extract ms (CPU) | frame ms (GL) | PSNR vs mesh dB | IoU vs mesh | GPU MiB "
      "| raycast records (per pixel) / dropped |\n|---|---|---|---|---|---|---|---|---|\n");
  bool first = true;
  for (std::size_t count : counts) {
    const std::vector<glm::vec3> particles = grow(std::vector<glm::vec3>(base.begin(), base.end()), count);
    Backdrop backdrop;
    if (!createBackdrop(particles, backdrop, error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    for (const glm::ivec2 size : sizes) {
      const auto bg = background(particles, backdrop, size.x, size.y);
      std::vector<std::uint8_t> mesh_image, mesh_silhouette;
      for (FluidMethod m : {FluidMethod::mesh, FluidMethod::screen_space, FluidMethod::raycast}) {
        const Result r = run(m, particles, backdrop, size.x, size.y, frames, pool);
        if (m == FluidMethod::mesh) {
          mesh_image = r.image;
          mesh_silhouette = r.silhouette;
        }
        const bool is_mesh = m == FluidMethod::mesh;
        std::printf("| %zu | %dx%d | %s | %s | %.1f | %s | %s | %.1f | %s |\n", count, size.x, size.y,
                    fluidMethodName(m), is_mesh ? std::to_string(r.extract_ms).substr(0, 6).c_str() : "-", r.frame_ms,
                    is_mesh ? "-" : std::to_string(psnr(r.image, mesh_image)).substr(0, 5).c_str(),
                    is_mesh ? "-" : std::to_string(maskIou(r.silhouette, mesh_silhouette, bg)).substr(0, 5).c_str(),
                    r.mib, m == FluidMethod::raycast ? perPixel(r.records, r.dropped, size.x * size.y).c_str() : "-");
        std::fflush(stdout);
        if (first && !png_dir.empty()) {
          const auto path = png_dir / (std::string("render_") + fluidMethodName(m) + ".png");
          if (!writePngBottomUp(path, size.x, size.y, r.image, error)) std::fprintf(stderr, "%s\n", error.c_str());
        }
      }
      first = false;
    }
    destroyBackdrop(backdrop);
  }
  gputest::destroyContext(ctx);
  return 0;
}
