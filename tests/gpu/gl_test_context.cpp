#include "tests/gpu/gl_test_context.hpp"

#include <cstdlib>

namespace gputest {

void createContext(GlContext& out) {
  out = GlContext{};
  setenv("SDL_VIDEODRIVER", "offscreen", 1);
  engine::PlatformDesc desc;
  desc.title = "gpu test";
  desc.width = 64;
  desc.height = 64;
  desc.headless = true;
  if (!engine::createPlatform(desc, out.platform, out.error)) return;
  out.version = out.platform.gl_version + " / " + out.platform.gl_renderer;
}

void destroyContext(GlContext& ctx) {
  engine::destroyPlatform(ctx.platform);
  ctx = GlContext{};
}

}  // namespace gputest
