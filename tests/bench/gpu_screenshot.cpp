// Renders the GPU sprite particles for docs/gpu.md: spray, mist, a splash and explosion debris
// raining on a ground plane and a sphere (depth-map colliders), drawn back-to-front after the
// odd-even merge sort, and once more unsorted for comparison.
//   usage: gpu_screenshot OUT_DIR [--force]   (writes gpu_particles_sorted.png, gpu_particles_unsorted.png)
#include "engine/gpu_particles/gpu_particles.hpp"
#include "tests/gpu/cpu_reference.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <stb_image_write.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace engine;

namespace {

constexpr int kW = 480, kH = 360;

bool writePng(const std::filesystem::path& path, bool force, std::string& error) {
  if (std::filesystem::exists(path) && !force) {
    error = path.string() + ": exists (use --force to overwrite)";
    return false;
  }
  std::vector<unsigned char> px(static_cast<std::size_t>(kW) * kH * 4), flipped(px.size());
  glReadPixels(0, 0, kW, kH, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  for (int y = 0; y < kH; ++y) {
    std::copy_n(&px[static_cast<std::size_t>(kH - 1 - y) * kW * 4], kW * 4,
                &flipped[static_cast<std::size_t>(y) * kW * 4]);
  }
  if (stbi_write_png(path.string().c_str(), kW, kH, 4, flipped.data(), kW * 4) == 0) {
    error = path.string() + ": cannot write PNG";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR [--force]\n", argv[0]);
    return 2;
  }
  const std::filesystem::path out_dir = argv[1];
  const bool force = argc > 2 && std::string(argv[2]) == "--force";
  gputest::GlContext ctx;
  gputest::createContext(ctx);
  if (!ctx.ok()) {
    std::fprintf(stderr, "no GL context: %s\n", ctx.error.c_str());
    return 1;
  }
  GpuParticlesDesc d;
  d.width = d.height = 128;
  d.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
  auto type = [](glm::vec4 a, glm::vec4 b, float s0, float s1) {
    ParticleTypeDesc t;
    for (int k = 0; k < kParticleKeyframes; ++k) {
      const float f = static_cast<float>(k) / (kParticleKeyframes - 1);
      t.keys[static_cast<std::size_t>(k)] = {glm::mix(a, b, f), s0 + (s1 - s0) * f};
    }
    return t;
  };
  d.types = {type({0.7f, 0.85f, 1.0f, 0.9f}, {0.4f, 0.6f, 1.0f, 0.3f}, 0.04f, 0.02f),   // spray
             type({0.8f, 0.8f, 0.85f, 0.25f}, {0.8f, 0.8f, 0.85f, 0.0f}, 0.15f, 0.3f),  // mist
             type({0.2f, 0.9f, 0.8f, 0.9f}, {0.1f, 0.5f, 0.9f, 0.4f}, 0.05f, 0.03f),    // splash
             type({1.0f, 0.7f, 0.2f, 1.0f}, {0.6f, 0.1f, 0.05f, 0.6f}, 0.05f, 0.03f)};  // debris
  GpuParticles s;
  createGpuParticles(d, s);
  if (!s.ready) {
    std::fprintf(stderr, "%s\n", s.error.c_str());
    return 1;
  }
  gputest::TestCollider ground = gputest::makeGroundCollider(128);
  gputest::TestCollider sphere =
      gputest::makeSphereCollider({0.0f, 0.45f, 0.0f}, 0.35f, 128, fluid::DepthMapFormat::front_back16);
  GpuColliderDesc cols[2] = {ground.gpu(), sphere.gpu()};
  std::string error;
  if (!setColliders(s, cols, error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  GpuStepParams params;
  params.wind = {0.4f, 0.0f, 0.0f};
  params.material = {0.3f, 0.3f, 0.05f};
  BirthBatch batch;
  for (int frame = 0; frame < 75; ++frame) {
    batch.clear();
    if (frame % 3 == 0) {
      EmitterDesc spray{EmitterKind::spray,
                        {-0.05f, 1.5f, 0.05f},
                        {0.1f, -1.0f, 0.0f},
                        1.5f,
                        0.25f,
                        0.05f,
                        300,
                        2.5f,
                        0,
                        static_cast<std::uint64_t>(frame)};
      emit(spray, batch);
    }
    if (frame == 10) {
      emit({EmitterKind::splash, {0.8f, 0.02f, 0.2f}, {0, 1, 0}, 2.0f, 0.4f, 0.1f, 1500, 1.6f, 2, 77}, batch);
    }
    if (frame == 30) {
      emit({EmitterKind::debris, {-0.8f, 0.6f, -0.2f}, {0, 1, 0}, 2.5f, 0.0f, 0.05f, 2500, 1.5f, 3, 99}, batch);
    }
    if (frame % 10 == 0) {
      emit({EmitterKind::mist,
            {0.0f, 0.1f, 0.4f},
            {1, 0.3f, 0},
            0.5f,
            0.0f,
            0.4f,
            60,
            3.0f,
            1,
            static_cast<std::uint64_t>(frame) + 5},
           batch);
    }
    spawn(s, batch);
    step(s, params);
  }
  const glm::vec3 eye(0.0f, 1.3f, 2.6f);
  const glm::mat4 proj = glm::perspective(glm::radians(50.0f), static_cast<float>(kW) / kH, 0.05f, 20.0f);
  const glm::mat4 view = glm::lookAt(eye, glm::vec3(0.0f, 0.4f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  GLuint tex = 0, fbo = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, kW, kH, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &fbo);
  int status = 0;
  for (const bool sorted : {true, false}) {
    // Sorted: the full network once (a steady camera converges in ceil(passes / per-frame)
    // frames). Unsorted: the identity order, reset by a fresh system would lose the state, so
    // the keys are refreshed and the network skipped: the texture order is the index order.
    if (sorted) {
      sortStep(s, eye, sortPassCount(s.capacity));
    }
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    glViewport(0, 0, kW, kH);
    glClearColor(0.05f, 0.06f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    drawSprites(s, proj * view, proj[1][1], kH);
    const auto path = out_dir / (sorted ? "gpu_particles_sorted.png" : "gpu_particles_unsorted.png");
    if (!writePng(path, force, error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      status = 1;
    } else {
      std::printf("wrote %s (%u live particles)\n", path.string().c_str(), s.allocator.live_count);
    }
    if (sorted) {
      // Back to index order for the unsorted picture.
      s.sort_step = 0;
      std::vector<float> pairs(static_cast<std::size_t>(s.capacity) * 2);
      for (std::uint32_t i = 0; i < s.capacity; ++i) {
        pairs[2 * i] = 0.0f;
        pairs[2 * i + 1] = static_cast<float>(i);
      }
      glBindTexture(GL_TEXTURE_2D, s.sort_tex[s.sort_current]);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, static_cast<GLsizei>(d.width), static_cast<GLsizei>(d.height), GL_RG,
                      GL_FLOAT, pairs.data());
    }
  }
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &tex);
  destroyGpuParticles(s);
  gputest::destroyContext(ctx);
  return status;
}
