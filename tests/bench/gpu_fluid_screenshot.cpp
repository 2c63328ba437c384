// Screenshots of the fluid surface rendering for docs/gpu.md: the test scene (striped wall,
// floor, two particle blobs meshed by marching slices) with the sort-order switch
// (unsorted / sorted / exact per-slab), the opaque goo style and the camera inside the water.
//   usage: gpu_fluid_screenshot OUT_DIR [--force]
#include "engine/fluid_render/fluid_render.hpp"
#include "tests/gpu/fluid_scene.hpp"
#include "tests/gpu/gl_test_context.hpp"

#include <stb_image_write.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

using namespace engine;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR [--force]\n", argv[0]);
    return 2;
  }
  const std::filesystem::path out_dir = argv[1];
  const bool force = argc > 2 && std::string(argv[2]) == "--force";
  constexpr int kW = 400, kH = 300;
  gputest::GlContext ctx;
  gputest::createContext(ctx);
  if (!ctx.ok()) {
    std::fprintf(stderr, "no GL context: %s\n", ctx.error.c_str());
    return 1;
  }
  FluidRenderer r;
  FluidRenderDesc d;
  d.width = kW;
  d.height = kH;
  d.shader_dir = std::filesystem::path(FLUIDDEMO_SOURCE_DIR) / "shaders";
  createFluidRenderer(d, r);
  if (!r.ready) {
    std::fprintf(stderr, "%s\n", r.error.c_str());
    return 1;
  }
  auto target = std::make_unique<gputest::ColourTarget>(kW, kH, GL_RGBA8);  // deleted before the context
  struct Shot {
    const char* name;
    glm::vec3 eye;
    fluid::SurfaceOrder order;
    bool exact;
    FluidStyle style;
  };
  const Shot shots[] = {
      {"fluid_unsorted.png", {2.4f, 0.9f, 0.3f}, fluid::SurfaceOrder::none, false, FluidStyle::water},
      {"fluid_sorted.png", {2.4f, 0.9f, 0.3f}, fluid::SurfaceOrder::backToFront, false, FluidStyle::water},
      {"fluid_exact_slabs.png", {2.4f, 0.9f, 0.3f}, fluid::SurfaceOrder::backToFront, true, FluidStyle::water},
      {"fluid_goo.png", {2.4f, 0.9f, 0.3f}, fluid::SurfaceOrder::backToFront, false, FluidStyle::goo},
      {"fluid_inside.png", {0.05f, 0.5f, 0.0f}, fluid::SurfaceOrder::backToFront, false, FluidStyle::water}};
  int status = 0;
  for (const Shot& shot : shots) {
    gputest::FluidScene scene;
    std::string error;
    if (!gputest::createFluidScene(scene, kW, kH, shot.eye, error) ||
        !gputest::extractMesh(scene, shot.order, shot.exact, error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    WaterParams params;
    params.style = shot.style;
    const std::vector<unsigned char> px = gputest::renderFrame(scene, r, target->fbo, params, true);
    const OutOfOrder ooo = countOutOfOrderPairs(scene.mesh.positions, scene.mesh.indices, scene.camera.eye);
    gputest::destroyFluidScene(scene);
    const std::filesystem::path path = out_dir / shot.name;
    if (std::filesystem::exists(path) && !force) {
      std::fprintf(stderr, "%s: exists (use --force to overwrite)\n", path.string().c_str());
      status = 1;
      continue;
    }
    std::vector<unsigned char> flipped(px.size());
    for (int y = 0; y < kH; ++y) {
      std::copy_n(&px[static_cast<std::size_t>(kH - 1 - y) * kW * 4], kW * 4,
                  &flipped[static_cast<std::size_t>(y) * kW * 4]);
    }
    if (stbi_write_png(path.string().c_str(), kW, kH, 4, flipped.data(), kW * 4) == 0) {
      std::fprintf(stderr, "%s: cannot write PNG\n", path.string().c_str());
      status = 1;
      continue;
    }
    std::printf("wrote %s: %llu triangles, %llu out-of-order pairs\n", path.string().c_str(),
                static_cast<unsigned long long>(ooo.triangles), static_cast<unsigned long long>(ooo.pairs));
  }
  target.reset();
  destroyFluidRenderer(r);
  gputest::destroyContext(ctx);
  return status;
}
