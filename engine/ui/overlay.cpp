#include "engine/ui/overlay.hpp"

#include <backends/imgui_impl_opengl3.h>
#include <backends/imgui_impl_sdl.h>
#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace engine {

bool createOverlay(Platform& platform, Overlay& out, std::string& error) {
  IMGUI_CHECKVERSION();
  out.context = ImGui::CreateContext();
  ImGui::SetCurrentContext(out.context);
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // never leave imgui.ini files in the user's folder
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.92f;
  if (!ImGui_ImplSDL2_InitForOpenGL(platform.window, platform.context)) {
    error = "ImGui SDL2 backend initialisation failed";
    ImGui::DestroyContext(out.context);
    out.context = nullptr;
    return false;
  }
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
    error = "ImGui OpenGL3 backend initialisation failed";
    ImGui_ImplSDL2_Shutdown();
    ImGui::DestroyContext(out.context);
    out.context = nullptr;
    return false;
  }
  return true;
}

void destroyOverlay(Overlay& overlay) {
  if (overlay.context == nullptr) return;
  ImGui::SetCurrentContext(overlay.context);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplSDL2_Shutdown();
  ImGui::DestroyContext(overlay.context);
  overlay.context = nullptr;
}

bool overlayProcessEvent(const SDL_Event* event) { return ImGui_ImplSDL2_ProcessEvent(event); }

OverlayMode nextOverlayMode(OverlayMode mode) {
  switch (mode) {
    case OverlayMode::compact:
      return OverlayMode::full;
    case OverlayMode::full:
      return OverlayMode::hidden;
    case OverlayMode::hidden:
      break;
  }
  return OverlayMode::compact;
}

// Only the full panels take the mouse and keyboard; the compact strip never does.
bool overlayWantsMouse(const Overlay& overlay) {
  return overlay.context != nullptr && overlay.mode == OverlayMode::full && ImGui::GetIO().WantCaptureMouse;
}

bool overlayWantsKeyboard(const Overlay& overlay) {
  return overlay.context != nullptr && overlay.mode == OverlayMode::full && ImGui::GetIO().WantCaptureKeyboard;
}

namespace {

constexpr float kMargin = 10.0f;
constexpr float kHintReserve = 34.0f;  // the bottom hint line's height, which the panels leave free

float lastFrameMs(const Profiler& profiler) {
  return profiler.filled > 0 ? profiler.frame_history[(profiler.head - 1 + Profiler::kHistory) % Profiler::kHistory]
                             : 0.0f;
}

}  // namespace

OverlayLayout overlayLayout(float width, float height, bool force) {
  // Each panel takes about a third of the width within readable bounds, and never more than half
  // of what the margins leave, so the two never meet.
  const float half = std::max((width - 3.0f * kMargin) * 0.5f, 0.0f);
  const float max_height = std::max(height - 2.0f * kMargin - kHintReserve, 0.0f);
  OverlayLayout layout;
  layout.frame.width = std::min(std::clamp(0.30f * width, 300.0f, 400.0f), half);
  layout.frame.x = kMargin;
  layout.game.width = std::min(std::clamp(0.33f * width, 320.0f, 440.0f), half);
  layout.game.x = width - kMargin - layout.game.width;
  layout.frame.y = layout.game.y = kMargin;
  layout.frame.max_height = layout.game.max_height = max_height;
  layout.frame.force = layout.game.force = force;
  return layout;
}

OverlayLayout currentOverlayLayout(const Overlay& overlay) {
  return overlayLayout(overlay.placed_width, overlay.placed_height, overlay.place_panels);
}

void placeNextPanel(const PanelPlacement& placement) {
  const ImGuiCond cond = placement.force ? ImGuiCond_Always : ImGuiCond_FirstUseEver;
  ImGui::SetNextWindowPos(ImVec2(placement.x, placement.y), cond);
  ImGui::SetNextWindowSize(ImVec2(placement.width, 0.0f), cond);  // height 0: fit the contents
  // The player may widen a panel, never past the display's height.
  ImGui::SetNextWindowSizeConstraints(ImVec2(std::min(placement.width, 200.0f), 0.0f),
                                      ImVec2(std::max(placement.width, 2.0f * placement.width), placement.max_height));
}

void beginOverlayFrame(Overlay& overlay) {
  ImGui::SetCurrentContext(overlay.context);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplSDL2_NewFrame();
  ImGui::NewFrame();
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  overlay.place_panels = display.x != overlay.placed_width || display.y != overlay.placed_height;
  overlay.placed_width = display.x;
  overlay.placed_height = display.y;
}

void drawCompactStrip(const Profiler& profiler, std::string_view status, std::string_view hint) {
  constexpr ImGuiWindowFlags kPassive = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs |
                                        ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings |
                                        ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav |
                                        ImGuiWindowFlags_NoMove;
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(kMargin, kMargin), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.45f);
  ImGui::SetNextWindowSizeConstraints(ImVec2(0.0f, 0.0f), ImVec2(display.x - 2.0f * kMargin, display.y * 0.2f));
  if (ImGui::Begin("##frame_strip", nullptr, kPassive)) {
    const float last = lastFrameMs(profiler);
    // The two costliest phases of the last frame: what a player would tune first.
    int first = -1, second = -1;
    for (int p = 0; p < kPhaseCount; ++p) {
      const float ms = historyAt(profiler, static_cast<Phase>(p), 0);
      if (first < 0 || ms > historyAt(profiler, static_cast<Phase>(first), 0)) {
        second = first;
        first = p;
      } else if (second < 0 || ms > historyAt(profiler, static_cast<Phase>(second), 0)) {
        second = p;
      }
    }
    ImGui::Text("%5.1f ms  %3.0f fps", last, last > 0.0f ? 1000.0f / last : 0.0f);
    ImGui::SameLine();
    ImGui::TextDisabled("%s %.1f  %s %.1f", phaseName(static_cast<Phase>(first)).data(),
                        historyAt(profiler, static_cast<Phase>(first), 0), phaseName(static_cast<Phase>(second)).data(),
                        historyAt(profiler, static_cast<Phase>(second), 0));
    // A sparkline of the recent frames, a red tick where a frame warned, scaled to the slowest.
    const int count = std::min(profiler.filled, 120);
    const ImVec2 size(160.0f, ImGui::GetTextLineHeight());
    ImGui::SameLine();
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    float scale = 1.0f;
    for (int i = 0; i < count; ++i)
      scale = std::max(scale, profiler.frame_history[(profiler.head - 1 - i + Profiler::kHistory) % Profiler::kHistory]);
    ImDrawList* draw = ImGui::GetWindowDrawList();
    for (int i = 0; i < count; ++i) {
      const int slot = (profiler.head - 1 - i + Profiler::kHistory) % Profiler::kHistory;
      const float x = origin.x + size.x - (static_cast<float>(i) + 1.0f) * size.x / 120.0f;
      const float h = std::max(profiler.frame_history[slot] / scale * size.y, 1.0f);
      const ImU32 colour = profiler.flag_history[slot] != 0 ? IM_COL32(255, 60, 60, 255) : IM_COL32(200, 220, 255, 200);
      draw->AddRectFilled(ImVec2(x, origin.y + size.y - h), ImVec2(x + size.x / 120.0f, origin.y + size.y), colour);
    }
    ImGui::Dummy(size);
    if (!status.empty()) ImGui::TextUnformatted(status.data(), status.data() + status.size());
  }
  ImGui::End();
  if (hint.empty()) return;
  ImGui::SetNextWindowPos(ImVec2(kMargin, display.y - kMargin), ImGuiCond_Always, ImVec2(0.0f, 1.0f));
  ImGui::SetNextWindowBgAlpha(0.35f);
  ImGui::SetNextWindowSizeConstraints(ImVec2(0.0f, 0.0f), ImVec2(display.x - 2.0f * kMargin, kHintReserve * 2.0f));
  if (ImGui::Begin("##key_hint", nullptr, kPassive)) {
    ImGui::PushTextWrapPos(display.x - 3.0f * kMargin);
    ImGui::TextUnformatted(hint.data(), hint.data() + hint.size());
    ImGui::PopTextWrapPos();
  }
  ImGui::End();
}

void drawBanner(std::string_view text) {
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(0.5f * display.x, 0.3f * display.y), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowBgAlpha(0.55f);
  ImGui::SetNextWindowSizeConstraints(ImVec2(0.0f, 0.0f), ImVec2(display.x - 2.0f * kMargin, 0.4f * display.y));
  constexpr ImGuiWindowFlags kPassive = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs |
                                        ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings |
                                        ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav;
  if (ImGui::Begin("##banner", nullptr, kPassive)) {
    ImGui::SetWindowFontScale(2.0f);
    ImGui::PushTextWrapPos(display.x - 4.0f * kMargin);
    ImGui::TextUnformatted(text.data(), text.data() + text.size());
    ImGui::PopTextWrapPos();
  }
  ImGui::End();
}

void drawProfilerWindow(const Profiler& profiler, std::span<const std::string> systems, const std::string& gl_renderer,
                        const PanelPlacement& placement) {
  placeNextPanel(placement);
  if (!ImGui::Begin("Frame (F1: hide panels)")) {
    ImGui::End();
    return;
  }
  ImGui::PushTextWrapPos(0.0f);  // every line wraps at the panel's edge instead of being cut
  ImGui::Text("frame %.2f ms (mean %.2f ms)", lastFrameMs(profiler), frameMeanMs(profiler));
  ImGui::TextDisabled("%s", gl_renderer.c_str());
  ImGui::PushTextWrapPos(-1.0f);  // the table's short cells size their columns; wrapping would split words
  if (ImGui::BeginTable("phases", 4, ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_RowBg)) {
    ImGui::TableSetupColumn("phase");
    ImGui::TableSetupColumn("last ms");
    ImGui::TableSetupColumn("mean ms");
    ImGui::TableSetupColumn("max ms");
    ImGui::TableHeadersRow();
    for (int p = 0; p < kPhaseCount; ++p) {
      const auto phase = static_cast<Phase>(p);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(phaseName(phase).data());
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", historyAt(profiler, phase, 0));
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", phaseMeanMs(profiler, phase));
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", profiler.stats[p].max_ms);
    }
    ImGui::EndTable();
  }
  ImGui::PopTextWrapPos();
  // Stacked per-phase bars for the last kHistory frames (oldest left), the frame total as a
  // line on top; the colours match the legend below.
  static constexpr ImU32 kColours[kPhaseCount] = {IM_COL32(200, 200, 200, 255), IM_COL32(230, 120, 60, 255),
                                                  IM_COL32(70, 150, 240, 255),  IM_COL32(150, 90, 220, 255),
                                                  IM_COL32(90, 200, 110, 255),  IM_COL32(240, 210, 70, 255)};
  const int count = profiler.filled;
  float scale = 1.0f;
  for (int i = 0; i < count; ++i) scale = std::max(scale, profiler.frame_history[i]);
  const ImVec2 size(std::max(ImGui::GetContentRegionAvail().x, 100.0f), 70.0f);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y), IM_COL32(20, 24, 32, 220));
  const float bar = size.x / static_cast<float>(Profiler::kHistory);
  for (int i = 0; i < count; ++i) {
    const int frames_ago = count - 1 - i;
    const float x0 = origin.x + size.x - static_cast<float>(frames_ago + 1) * bar;
    float y = origin.y + size.y;
    for (int p = 0; p < kPhaseCount; ++p) {
      const float h = historyAt(profiler, static_cast<Phase>(p), frames_ago) / scale * size.y;
      if (h <= 0.0f) continue;
      draw->AddRectFilled(ImVec2(x0, y - h), ImVec2(x0 + std::max(bar, 1.0f), y), kColours[p]);
      y -= h;
    }
    const int slot = (profiler.head - 1 - frames_ago + 2 * Profiler::kHistory) % Profiler::kHistory;
    const float total = profiler.frame_history[slot] / scale * size.y;
    draw->AddRectFilled(ImVec2(x0, origin.y + size.y - total - 1.0f),
                        ImVec2(x0 + std::max(bar, 1.0f), origin.y + size.y - total), IM_COL32(255, 255, 255, 200));
  }
  // Red markers over the frames where a system flagged a warning (engine::flagFrame): a tick
  // above the bars and a faint band down the plot, so a spike can be matched with its cause.
  std::vector<int> flagged;  // allocates only while the ring holds flagged frames
  flaggedFramesAgo(profiler, flagged);
  for (const int frames_ago : flagged) {
    const float x0 = origin.x + size.x - static_cast<float>(frames_ago + 1) * bar;
    const float x1 = x0 + std::max(bar, 2.0f);
    draw->AddRectFilled(ImVec2(x0, origin.y), ImVec2(x1, origin.y + size.y), IM_COL32(255, 40, 40, 70));
    draw->AddRectFilled(ImVec2(x0, origin.y), ImVec2(x1, origin.y + 6.0f), IM_COL32(255, 40, 40, 255));
  }
  ImGui::Dummy(size);
  ImGui::Text("0 .. %.1f ms, last %d frames; white = whole frame", scale, count);
  ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.35f, 1.0f), "red: %zu of these frames warned (%llu in the run)",
                     flagged.size(), static_cast<unsigned long long>(profiler.flagged_frames));
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("A frame warns when a system saw something that costs accuracy in it: water pushed deep\n"
                      "out of a collider, a particle's speed clamped, the time step held at its minimum, or\n"
                      "a NaN/inf. The Scene panel's red lines say which; the exit summary counts them.");
  // The legend: a coloured square and the phase's name, wrapped onto a new line when the next
  // entry would not fit the panel.
  const float right = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
  for (int p = 0; p < kPhaseCount; ++p) {
    const char* name = phaseName(static_cast<Phase>(p)).data();
    const float entry = 10.0f + 3.0f + ImGui::CalcTextSize(name).x;
    if (p > 0 && ImGui::GetItemRectMax().x + ImGui::GetStyle().ItemSpacing.x + entry <= right) ImGui::SameLine();
    ImGui::ColorButton(name, ImGui::ColorConvertU32ToFloat4(kColours[p]), ImGuiColorEditFlags_NoTooltip,
                       ImVec2(10, 10));
    ImGui::SameLine(0.0f, 3.0f);
    ImGui::TextUnformatted(name);
  }
  ImGui::Separator();
  std::string running;
  for (const std::string& system : systems) running += (running.empty() ? "" : ", ") + system;
  ImGui::Text("running systems (%zu): %s", systems.size(), systems.empty() ? "none" : running.c_str());
  ImGui::PopTextWrapPos();
  ImGui::End();
}

void endOverlayFrame(Overlay& overlay) {
  ImGui::SetCurrentContext(overlay.context);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void drawProgressWindow(const char* title, float fraction, const char* detail) {
  ImGui::SetNextWindowPos(ImVec2(10, ImGui::GetIO().DisplaySize.y - 80.0f), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(420, 0), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin(title)) {
    ImGui::End();
    return;
  }
  const float clamped = fraction >= 0.0f && fraction <= 1.0f ? fraction : (fraction > 1.0f ? 1.0f : 0.0f);
  ImGui::ProgressBar(clamped, ImVec2(-1.0f, 0.0f));
  ImGui::TextUnformatted(detail);
  ImGui::End();
}

}  // namespace engine
