// Benchmark of the GPU particle passes (Kolb et al. 2004 §3): particles per millisecond for
// one update pass (forces + integration), the same pass with depth-map collisions (ground
// float32 map + sphere fixed8 front/back pair), one odd-even merge-sort pass (plus its key
// refresh, timed separately) and the sprite draw, for 16k…1M particles.
// Timing: glFinish() around each pass, wall clock, median of --reps repetitions.
//   usage: bench_gpu_particles [--reps N] [--max-side S]   (S: texture side, 128..1024)
#include "engine/gpu_particles/gpu_particles.hpp"
#include "tests/gpu/cpu_reference.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using namespace engine;

namespace {

template <class F>
double medianMs(int reps, F&& pass) {
  std::vector<double> ms;
  pass();  // warm-up (shader compile/JIT, first-touch)
  glFinish();
  for (int r = 0; r < reps; ++r) {
    glFinish();
    const auto t0 = std::chrono::steady_clock::now();
    pass();
    glFinish();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 5;
  std::uint32_t max_side = 1024;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--reps" && k + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++k]));
    } else if (a == "--max-side" && k + 1 < argc) {
      max_side = static_cast<std::uint32_t>(std::atoi(argv[++k]));
    } else {
      std::fprintf(stderr, "bench_gpu_particles: unknown argument '%s'\nusage: %s [--reps N] [--max-side S]\n",
                   a.c_str(), argv[0]);
      return 2;
    }
  }
  gputest::GlContext ctx;
  gputest::createContext(ctx);
  if (!ctx.ok()) {
    std::fprintf(stderr, "bench_gpu_particles: no GL context: %s\n", ctx.error.c_str());
    return 1;
  }
  std::printf("GL: %s\nmedian of %d repetitions; particles per ms (ms per pass)\n\n", ctx.version.c_str(), reps);
  std::printf(
      "| particles | update | update + collide (ground 1 map + sphere 3 front-back16 maps) | same, push-out 0 | sort "
      "key refresh | sort pass | draw (512², points) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
  gputest::TestCollider ground = gputest::makeGroundCollider(256);
  gputest::TestCollider sphere =
      gputest::makeSphereCollider({0.0f, 0.6f, 0.0f}, 0.35f, 256, fluid::DepthMapFormat::front_back16);
  // FBO for the draw.
  GLuint tex = 0, fbo = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, 512, 512, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  for (std::uint32_t side = 128; side <= std::min<std::uint32_t>(max_side, 1024); side *= 2) {
    GpuParticlesDesc d;
    d.width = d.height = side;
    d.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
    GpuParticles s;
    createGpuParticles(d, s);
    if (!s.ready) {
      std::fprintf(stderr, "%s\n", s.error.c_str());
      return 1;
    }
    EmitterDesc e;
    e.kind = EmitterKind::debris;
    e.position = {0.0f, 1.0f, 0.0f};
    e.radius = 0.8f;
    e.count = side * side;
    e.lifetime = 1000.0f;
    BirthBatch batch;
    emit(e, batch);
    spawn(s, batch);
    GpuStepParams params;
    const double update = medianMs(reps, [&] { step(s, params); });
    GpuColliderDesc cols[2] = {ground.gpu(), sphere.gpu()};
    std::string error;
    if (!setColliders(s, cols, error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    const double collide = medianMs(reps, [&] { step(s, params); });
    GpuStepParams single = params;
    single.push_out_iterations = 0;  // exactly the single §3.3.2 projection
    const double collide0 = medianMs(reps, [&] { step(s, single); });
    const glm::vec3 eye(0.0f, 1.0f, 4.0f);
    const double refresh = medianMs(reps, [&] { refreshSortKeys(s, eye); });
    const double pass = medianMs(reps, [&] { sortPasses(s, 1); });
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, 512, 512);
    const glm::mat4 proj = glm::mat4(1.0f);
    const double draw = medianMs(reps, [&] {
      glClear(GL_COLOR_BUFFER_BIT);
      drawSprites(s, proj, 1.0f, 512);
    });
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const double n = static_cast<double>(side) * side;
    std::printf(
        "| %u (%u²) | %.0f (%.2f ms) | %.0f (%.2f ms) | %.0f (%.2f ms) | %.0f (%.2f ms) | %.0f (%.2f ms) | %.0f (%.2f "
        "ms) "
        "|\n",
        side * side, side, n / update, update, n / collide, collide, n / collide0, collide0, n / refresh, refresh,
        n / pass, pass, n / draw, draw);
    std::fflush(stdout);
    destroyGpuParticles(s);
  }
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &tex);
  gputest::destroyContext(ctx);
  return 0;
}
