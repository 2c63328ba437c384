#pragma once
// The game's overlay (engine/ui/overlay.hpp's modes). Compact: the frame strip and the keys this
// scene answers to. Full (F1): the profiler panel and the Scene panel: each effect's status lines
// (Effect::drawStatus), the run-time failures, the live camera, and one knob per scene key, made
// from the schema (so from the effects' parameter tables: ranges, choices and docs as tooltips).
// The Scene panel edits world.scene and world.camera in place.

#include "engine/profile/profiler.hpp"
#include "engine/ui/overlay.hpp"

#include <string>
#include <utility>

namespace game {

struct World;

// The keys the scene answers to, one line (G only where the scene lists explosives).
std::string keyHint(const World& world);

// Draws the overlay's windows for its mode (between beginOverlayFrame and endOverlayFrame).
// Returns {a value changed (apply it live), restart requested (rebuild with the edited scene)}.
std::pair<bool, bool> drawGameOverlay(World& world, const engine::Overlay& overlay, const engine::Profiler& profiler,
                                      const std::string& gl_renderer);

}  // namespace game
