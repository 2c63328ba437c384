#include "engine/ui/overlay.hpp"

#include <backends/imgui_impl_opengl3.h>
#include <backends/imgui_impl_sdl.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <cstdio>

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

void drawProfilerWindow(const Profiler& profiler, std::span<const std::string> systems, const std::string& gl_renderer) {
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
  // Oldest to newest, one plot per phase plus the whole frame, sharing one scale.
  std::array<float, Profiler::kHistory> values{};
  const int count = profiler.filled;
  float scale = 1.0f;
  for (int i = 0; i < count; ++i) {
    const int slot = (profiler.head - count + i + Profiler::kHistory) % Profiler::kHistory;
    scale = std::max(scale, profiler.frame_history[slot]);
  }
  for (int i = 0; i < count; ++i) {
    values[i] = profiler.frame_history[(profiler.head - count + i + Profiler::kHistory) % Profiler::kHistory];
  }
  char label[64];
  std::snprintf(label, sizeof label, "frame\n(0..%.0f ms)", scale);
  ImGui::PlotLines(label, values.data(), count, 0, nullptr, 0.0f, scale, ImVec2(0, 60));
  for (int p = 0; p < kPhaseCount; ++p) {
    const auto phase = static_cast<Phase>(p);
    for (int i = 0; i < count; ++i) values[i] = historyAt(profiler, phase, count - 1 - i);
    ImGui::PlotLines(phaseName(phase).data(), values.data(), count, 0, nullptr, 0.0f, scale, ImVec2(0, 28));
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

}  // namespace engine
