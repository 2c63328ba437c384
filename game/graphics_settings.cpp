#include "game/graphics_settings.hpp"

#include <algorithm>
#include <array>

namespace game {
namespace {

struct Preset {
  std::string_view name;
  float resolution_scale;
  int shadow_size;
  float sprite_rate_scale;
  float min_lattice;
  bool refraction;
};

// The table of the header's comment. low halves each side of the frame (a quarter of the pixels:
// llvmpipe's cost is per pixel) and coarsens the lattice to one spacing (about half the triangles
// of the default 0.75, docs/images/fountain_mesh_lattice.png).
constexpr std::array kPresets = {
    Preset{"low", 0.5f, 512, 0.5f, 1.0f, false},
    Preset{"medium", 0.75f, 1024, 0.75f, 0.75f, true},
    Preset{"high", 1.0f, 0, 1.0f, 0.0f, true},
};

}  // namespace

bool softwareRenderer(std::string_view gl_renderer) {
  for (std::string_view software : {"llvmpipe", "softpipe", "SwiftShader", "Software Rasterizer"})
    if (gl_renderer.find(software) != std::string_view::npos) return true;
  return false;
}

GraphicsSettings resolveGraphics(const SectionConfig& graphics, std::string_view gl_renderer) {
  std::string name = graphics.text("preset");
  if (name == "auto") name = softwareRenderer(gl_renderer) ? "low" : "high";
  const Preset* preset = &kPresets.back();
  for (const Preset& p : kPresets)
    if (p.name == name) preset = &p;
  GraphicsSettings out;
  out.preset = std::string(preset->name);
  const float scale = static_cast<float>(graphics.number("resolution_scale"));
  out.resolution_scale = scale > 0.0f ? std::clamp(scale, 0.1f, 1.0f) : preset->resolution_scale;
  out.shadow_size = preset->shadow_size;
  out.sprite_rate_scale = preset->sprite_rate_scale;
  out.min_lattice = preset->min_lattice;
  out.refraction = preset->refraction;
  return out;
}

void applyGraphics(const GraphicsSettings& settings, const SceneConfig& original, SceneConfig& scene) {
  const auto set = [&](std::string_view section, const char* key, auto&& derive) {
    const SectionConfig* from = original.effect(section);
    if (from == nullptr) return;
    for (SectionConfig& to : scene.effects)
      if (to.name == section) to.params[key].number = derive(from->number(key));
  };
  set("fluid_surface", "cube", [&](double cube) { return std::max(cube, static_cast<double>(settings.min_lattice)); });
  set("fluid_surface", "refraction", [&](double refraction) { return settings.refraction ? refraction : 0.0; });
  set("sprite_particles", "rate", [&](double rate) { return rate * settings.sprite_rate_scale; });
  set("sprite_particles", "spray_rate", [&](double rate) { return rate * settings.sprite_rate_scale; });
  // Foam and bubbles (Ihmsen et al. 2012's diffuse sprites) are sprites born too.
  set("sprite_particles", "foam_trapped_air_rate", [&](double rate) { return rate * settings.sprite_rate_scale; });
  set("sprite_particles", "foam_wave_crest_rate", [&](double rate) { return rate * settings.sprite_rate_scale; });
}

}  // namespace game
