#pragma once
// NaN/inf checks shared by the fluid library, the engine and the game: every input and state
// vector is checked before it can spread through a simulation (DESIGN.md habit 5).

#include <glm/glm.hpp>

#include <cmath>

namespace fluid {

// True when every component is a finite number (no NaN, no ±inf).
inline bool isFinite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace fluid
