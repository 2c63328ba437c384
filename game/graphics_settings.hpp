#pragma once
// Graphics quality (issue 35 item 5): the scene's `graphics` section picks a preset, and the
// preset sets what the renderer costs: the resolution the scene renders at (scaled up to the
// window), the sun's shadow map, how many sprites are born, the water's lattice and refraction.
// Rendering only: no preset touches a simulated value, so replays gate the same at any preset.
//
//            resolution  shadow map  sprites born   water lattice      refraction
//   low         0.5        512        half        >= 1.0 spacings      off
//   medium      0.75      1024        3/4         >= 0.75 spacings     the scene's
//   high        1.0       the run's   the scene's  the scene's         the scene's
// auto is low on a software renderer (llvmpipe, softpipe, SwiftShader) and high on a GPU.

#include "game/scene/scene_config.hpp"

#include <string>
#include <string_view>

namespace game {

struct GraphicsSettings {
  std::string preset;             // low, medium or high (auto resolved)
  float resolution_scale = 1.0f;  // of the window's size, (0, 1]
  int shadow_size = 0;            // texels per side; 0 = the run's own choice
  float sprite_rate_scale = 1.0f; // of the scene's sprite birth rates
  float min_lattice = 0.0f;       // fluid_surface.cube at least this (particle spacings)
  bool refraction = true;         // false: fluid_surface.refraction = 0
};

// True for the renderers that rasterise on the CPU (GL_RENDERER strings).
bool softwareRenderer(std::string_view gl_renderer);

// The settings of `graphics` (the scene's section) on the renderer named `gl_renderer`.
GraphicsSettings resolveGraphics(const SectionConfig& graphics, std::string_view gl_renderer);

// Sets the preset's values into the scene's render-only keys (fluid_surface.cube and refraction,
// sprite_particles.rate, spray_rate and the two foam rates) of the sections it lists. Idempotent: applying it twice
// (a restart) changes nothing more.
void applyGraphics(const GraphicsSettings& settings, const SceneConfig& original, SceneConfig& scene);

}  // namespace game
