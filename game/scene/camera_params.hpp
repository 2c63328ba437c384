#pragma once
// The scene's `camera` section as a parameter table bound to engine::FpsCamera: each key's default
// is the camera's own member initialiser (engine/camera/camera.hpp), written once there.

#include "engine/camera/camera.hpp"
#include "game/effects/params.hpp"

namespace game {

const ParamTable<engine::FpsCamera>& cameraParamTable();

}  // namespace game
