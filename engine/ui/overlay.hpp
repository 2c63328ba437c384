#pragma once
// Dear ImGui overlay (SDL2 + OpenGL3 backends). Two modes a player cycles with F1:
//  - compact (the default): a thin frame-time strip in the top-left corner and one line of key hints
//    at the bottom, neither taking the mouse, so the view stays the game's;
//  - full: the profiler's per-phase breakdown with a plot of the last Profiler::kHistory frames and
//    the running systems on the left, and the game's own panel on the right (game code adds windows
//    with plain ImGui calls between beginOverlayFrame and endOverlayFrame, placed by overlayLayout).
// The panels are placed for the display size whenever it changes, so a resize never leaves them
// overlapping or outside the window; between resizes the player may move them.

#include "engine/platform/platform.hpp"
#include "engine/profile/profiler.hpp"

#include <span>
#include <string>
#include <string_view>

struct ImGuiContext;

namespace engine {

enum class OverlayMode { hidden, compact, full };

// F1's cycle: compact -> full -> hidden -> compact.
OverlayMode nextOverlayMode(OverlayMode mode);

struct Overlay {
  ImGuiContext* context = nullptr;  // owned
  OverlayMode mode = OverlayMode::compact;
  // The display size the panels were last placed for (beginOverlayFrame compares it).
  float placed_width = 0.0f, placed_height = 0.0f;
  bool place_panels = true;  // this frame's panels take their layout position (the display changed)
};

// Where one panel goes: its top-left corner, its width, the most height it may take (it scrolls
// beyond), and whether this frame forces the position and size (first frame, or after a resize).
struct PanelPlacement {
  float x = 0.0f, y = 0.0f;
  float width = 0.0f;
  float max_height = 0.0f;
  bool force = false;
};

// The full mode's two panels for a display of width x height pixels: the frame panel at the
// top left, the game's panel along the right edge down to the hint line; both inside the display
// and never overlapping (each takes at most half the width when the display is narrow).
struct OverlayLayout {
  PanelPlacement frame;
  PanelPlacement game;
};
OverlayLayout overlayLayout(float width, float height, bool force);
// The layout for this frame's display (between beginOverlayFrame and endOverlayFrame).
OverlayLayout currentOverlayLayout(const Overlay& overlay);
// SetNextWindowPos/Size/SizeConstraints for a panel about to Begin.
void placeNextPanel(const PanelPlacement& placement);

bool createOverlay(Platform& platform, Overlay& out, std::string& error);
void destroyOverlay(Overlay& overlay);

// Feeds one SDL event to ImGui; usable as pollInput's event hook.
bool overlayProcessEvent(const SDL_Event* event);
bool overlayWantsMouse(const Overlay& overlay);
bool overlayWantsKeyboard(const Overlay& overlay);

void beginOverlayFrame(Overlay& overlay);
// Frame-time breakdown per phase (this frame, mean, max), a stacked plot of the history, and
// the running systems, placed at `placement`.
void drawProfilerWindow(const Profiler& profiler, std::span<const std::string> systems, const std::string& gl_renderer,
                        const PanelPlacement& placement);
// The compact mode: a strip with the frame time, the slowest phases, `status` (the game's one-line
// state, may be empty) and a sparkline of recent frames at the top left; `hint` (the keys) along
// the bottom. Neither window takes input.
void drawCompactStrip(const Profiler& profiler, std::string_view status, std::string_view hint);
// A small window with a progress bar (fraction in [0, 1], clamped) and one line of detail, e.g. a
// replay's step and checkpoints.
void drawProgressWindow(const char* title, float fraction, const char* detail);
// A large message centred in the upper half of the display (a game event: "caught"), without input.
void drawBanner(std::string_view text);
// Renders into the currently bound framebuffer (the window's).
void endOverlayFrame(Overlay& overlay);

}  // namespace engine
