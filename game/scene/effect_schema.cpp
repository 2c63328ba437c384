// The schema every scene file and --set override is validated against: the fixed sections (scene
// clock, graphics) written here, the camera's bound to engine::FpsCamera (cameraParamTable), then one section per
// effect, generated from each effect's parameter table in registry order (game/effects/). An effect is constructed only
// when a scene lists it.
#include "game/effects/effect.hpp"
#include "game/scene/camera_params.hpp"
#include "game/scene/scene_config.hpp"

#include <array>
#include <vector>

namespace game {
namespace {

ParamValue num(double value) { return {ParamType::number, value, false, {}, {}}; }
ParamValue integer(int value) { return {ParamType::integer, static_cast<double>(value), false, {}, {}}; }

// The levels game/world/level_assets.cpp knows: their models drawn and content/colliders/LEVEL.colliders.
constexpr std::string_view kLevels[] = {"fountain", "blob_monster"};

const std::array kSceneParams = {
    ParamSpec{"step_hz", ParamType::number, 30.0, 240.0, num(60.0), "fixed simulation steps per second"},
    ParamSpec{"substeps", ParamType::integer, 1, 16, integer(1), "physics substeps per simulation step"},
    ParamSpec{"max_steps_per_frame", ParamType::integer, 1, 20, integer(5), "backlog cap after a hitch"},
    ParamSpec{"seed", ParamType::integer, 0, 2147483647, integer(1), "seed of every random choice in the scene"},
    ParamSpec{"level",
              ParamType::text,
              0.0,
              0.0,
              {ParamType::text, 0.0, false, {}, "fountain"},
              "the level: the models drawn (game/world/level_assets.cpp) and the colliders the blob bakes "
              "(content/colliders/LEVEL.colliders)",
              kLevels},
};

constexpr std::string_view kPresets[] = {"auto", "low", "medium", "high"};

const std::array kGraphicsParams = {
    ParamSpec{"preset",
              ParamType::text,
              0.0,
              0.0,
              {ParamType::text, 0.0, false, {}, "auto"},
              "quality: low / medium / high (game/graphics_settings.cpp says what each sets), or auto: low on a "
              "software renderer (llvmpipe), high on a GPU; applies on restart",
              kPresets},
    ParamSpec{"resolution_scale", ParamType::number, 0.0, 1.0, num(0.0),
              "the scene renders at this fraction of the window's size and is scaled up; 0 = the preset's"},
};

}  // namespace

const ParamTable<engine::FpsCamera>& cameraParamTable() {
  using C = engine::FpsCamera;
  static const ParamTable<C> rows{
      param<&C::position>("position", -1000.0, 1000.0, "start position (m), y up"),
      param<&C::yaw_degrees>("yaw_degrees", -360.0, 360.0, "heading; -90 looks along -z"),
      param<&C::pitch_degrees>("pitch_degrees", -89.0, 89.0, "look up (+) or down (-)"),
      param<&C::fov_degrees>("fov_degrees", 20.0, 120.0, "vertical field of view"),
      param<&C::move_speed>("move_speed", 0.1, 100.0, "WASD speed (m/s)"),
      param<&C::bounds_min>("bounds_min", -1000.0, 1000.0,
                            "the player cannot move below these x, y, z (m): the level's edges"),
      param<&C::bounds_max>("bounds_max", -1000.0, 1000.0,
                            "the player cannot move beyond these x, y, z (m): the level's edges"),
  };
  return rows;
}

std::span<const SectionSpec> sceneSchema() {
  static const std::vector<SectionSpec> sections = [] {
    std::vector<SectionSpec> all = {
        SectionSpec{"scene", false, "simulation clock", kSceneParams},
        SectionSpec{"camera", false, "first-person camera", cameraParamTable().specs},
        SectionSpec{"graphics", false, "rendering quality (never changes the simulation)", kGraphicsParams},
    };
    for (const EffectDesc* effect : effectRegistry())
      all.push_back(SectionSpec{effect->name, true, effect->doc, effect->params});
    return all;
  }();
  return sections;
}

}  // namespace game
