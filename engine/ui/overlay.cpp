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

bool overlayWantsMouse(const Overlay& overlay) {
  return overlay.context != nullptr && overlay.visible && ImGui::GetIO().WantCaptureMouse;
}

bool overlayWantsKeyboard(const Overlay& overlay) {
  return overlay.context != nullptr && overlay.visible && ImGui::GetIO().WantCaptureKeyboard;
}

void beginOverlayFrame(Overlay& overlay) {
  ImGui::SetCurrentContext(overlay.context);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplSDL2_NewFrame();
  ImGui::NewFrame();
}

void drawProfilerWindow(const Profiler& profiler, std::span<const std::string> systems,
                        const std::string& gl_renderer) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Frame (F1 hides)")) {
    ImGui::End();
    return;
  }
  const float last_frame = profiler.filled > 0
                               ? profiler.frame_history[(profiler.head - 1 + Profiler::kHistory) % Profiler::kHistory]
                               : 0.0f;
  ImGui::Text("frame %.2f ms (mean %.2f ms)  %s", last_frame, frameMeanMs(profiler), gl_renderer.c_str());
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
  // Stacked per-phase bars for the last kHistory frames (oldest left), the frame total as a
  // line on top; the colours match the legend below.
  static constexpr ImU32 kColours[kPhaseCount] = {IM_COL32(200, 200, 200, 255), IM_COL32(230, 120, 60, 255),
                                                  IM_COL32(70, 150, 240, 255),  IM_COL32(150, 90, 220, 255),
                                                  IM_COL32(90, 200, 110, 255),  IM_COL32(240, 210, 70, 255)};
  const int count = profiler.filled;
  float scale = 1.0f;
  for (int i = 0; i < count; ++i) scale = std::max(scale, profiler.frame_history[i]);
  const ImVec2 size(std::max(ImGui::GetContentRegionAvail().x, 100.0f), 90.0f);
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
  for (int p = 0; p < kPhaseCount; ++p) {
    if (p > 0) ImGui::SameLine();
    ImGui::ColorButton(phaseName(static_cast<Phase>(p)).data(), ImGui::ColorConvertU32ToFloat4(kColours[p]),
                       ImGuiColorEditFlags_NoTooltip, ImVec2(10, 10));
    ImGui::SameLine(0.0f, 3.0f);
    ImGui::TextUnformatted(phaseName(static_cast<Phase>(p)).data());
  }
  ImGui::Separator();
  ImGui::Text("running systems (%zu):", systems.size());
  for (const std::string& system : systems) ImGui::BulletText("%s", system.c_str());
  if (systems.empty()) ImGui::TextDisabled("none");
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
