#pragma once
// Dear ImGui overlay (SDL2 + OpenGL3 backends): the profiler's per-phase breakdown with a plot
// of the last Profiler::kHistory frames, and the list of running systems. Game code may add
// its own windows with plain ImGui calls between beginOverlayFrame and endOverlayFrame.

#include "engine/platform/platform.hpp"
#include "engine/profile/profiler.hpp"

#include <span>
#include <string>

struct ImGuiContext;

namespace engine {

struct Overlay {
  ImGuiContext* context = nullptr;  // owned
  bool visible = true;              // toggled by the game (F1)
};

bool createOverlay(Platform& platform, Overlay& out, std::string& error);
void destroyOverlay(Overlay& overlay);

// Feeds one SDL event to ImGui; usable as pollInput's event hook.
bool overlayProcessEvent(const SDL_Event* event);
bool overlayWantsMouse(const Overlay& overlay);
bool overlayWantsKeyboard(const Overlay& overlay);

void beginOverlayFrame(Overlay& overlay);
// Frame-time breakdown per phase (this frame, mean, max), a stacked plot of the history, and
// the running systems.
void drawProfilerWindow(const Profiler& profiler, std::span<const std::string> systems, const std::string& gl_renderer);
// A small window with a progress bar (fraction in [0, 1], clamped) and one line of detail, e.g. a
// replay's step and checkpoints.
void drawProgressWindow(const char* title, float fraction, const char* detail);
// Renders into the currently bound framebuffer (the window's).
void endOverlayFrame(Overlay& overlay);

}  // namespace engine
