#pragma once
// The F1 overlay's Scene window: each effect's status lines (Effect::drawStatus), the run-time
// failures, and one knob per scene key, made from the schema (so from the effects' parameter
// tables: ranges, choices and docs as tooltips). It edits world.scene in place.

#include <utility>

namespace game {

struct World;

// Returns {a value changed (apply it live), restart requested (rebuild with the edited scene)}.
std::pair<bool, bool> drawScenePanel(World& world);

}  // namespace game
