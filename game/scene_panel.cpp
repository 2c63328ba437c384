#include "game/scene_panel.hpp"

#include "game/world/world.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace game {
namespace {

// A key's label: a fixed key (ParamSpec::live false) is marked, its edit waits for a restart.
std::string knobLabel(const ParamSpec& param) { return std::string(param.key) + (param.live ? "" : " *"); }

// One knob for one key, by its schema row; true when the value changed.
bool editParam(const ParamSpec& param, ParamValue& value) {
  const std::string label = knobLabel(param);
  bool edited = false;
  switch (param.type) {
    case ParamType::number: {
      const double speed = std::max((param.max - param.min) * 1e-3, std::abs(value.number) * 5e-3);
      edited = ImGui::DragScalar(label.c_str(), ImGuiDataType_Double, &value.number, static_cast<float>(speed),
                                 &param.min, &param.max, "%.3f", ImGuiSliderFlags_AlwaysClamp);
      break;
    }
    case ParamType::integer: {
      int v = static_cast<int>(value.number);
      const int lo = static_cast<int>(param.min), hi = static_cast<int>(param.max);
      edited = ImGui::DragInt(label.c_str(), &v, 1.0f, lo, hi, "%d", ImGuiSliderFlags_AlwaysClamp);
      value.number = v;
      break;
    }
    case ParamType::boolean:
      edited = ImGui::Checkbox(label.c_str(), &value.boolean);
      break;
    case ParamType::vec3:
      edited = ImGui::DragFloat3(label.c_str(), &value.vec.x, 0.05f, static_cast<float>(param.min),
                                 static_cast<float>(param.max), "%.2f", ImGuiSliderFlags_AlwaysClamp);
      break;
    case ParamType::text:
      if (param.choices.empty()) {
        ImGui::Text("%s: %s", label.c_str(), value.text.c_str());
      } else if (ImGui::BeginCombo(label.c_str(), value.text.c_str())) {
        for (std::string_view choice : param.choices) {
          const std::string item(choice);
          if (ImGui::Selectable(item.c_str(), value.text == item)) {
            edited = value.text != item;
            value.text = item;
          }
        }
        ImGui::EndCombo();
      }
      break;
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("%.*s%s", static_cast<int>(param.doc.size()), param.doc.data(),
                      param.live ? "" : "\n(* applies on restart: the effect is built with it)");
  return edited;
}

bool editSection(SectionConfig& section, const char* title) {
  const SectionSpec* spec = findSection(section.name);
  if (spec == nullptr || !ImGui::TreeNodeEx(section.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen, "%s", title))
    return false;
  bool changed = false;
  for (const ParamSpec& param : spec->params) {
    auto it = section.params.find(param.key);
    if (it != section.params.end()) changed |= editParam(param, it->second);
  }
  ImGui::TreePop();
  return changed;
}

// The camera as it is now (the camera section's keys are the start pose a new round returns to).
void editLiveCamera(World& world) {
  if (!ImGui::TreeNodeEx("live camera", ImGuiTreeNodeFlags_DefaultOpen)) return;
  engine::FpsCamera& camera = world.camera;
  ImGui::DragFloat3("position##live", &camera.position.x, 0.05f, -1000.0f, 1000.0f, "%.2f");
  ImGui::DragFloat("yaw##live", &camera.yaw_degrees, 0.5f, -720.0f, 720.0f, "%.1f");
  ImGui::DragFloat("pitch##live", &camera.pitch_degrees, 0.5f, -89.0f, 89.0f, "%.1f");
  if (ImGui::Button("make this the start pose")) {
    world.scene.camera.params["position"].vec = camera.position;
    world.scene.camera.params["yaw_degrees"].number = camera.yaw_degrees;
    world.scene.camera.params["pitch_degrees"].number = camera.pitch_degrees;
  }
  ImGui::TreePop();
}

// The widest knob label of the scene, so every knob leaves its label room and none is cut.
float widestLabel(const World& world) {
  float widest = ImGui::CalcTextSize("position").x;
  const auto measure = [&widest](const SectionConfig& section) {
    if (const SectionSpec* spec = findSection(section.name))
      for (const ParamSpec& param : spec->params) {
        const std::string label = knobLabel(param);
        widest = std::max(widest, ImGui::CalcTextSize(label.c_str()).x);
      }
  };
  measure(world.scene.camera);
  for (const SectionConfig& effect : world.scene.effects) measure(effect);
  measure(world.scene.scene);
  measure(world.scene.graphics);
  return widest;
}

std::pair<bool, bool> drawScenePanel(World& world, const engine::PanelPlacement& placement) {
  engine::placeNextPanel(placement);
  // The panel runs down the right edge and scrolls; its height is the layout's.
  ImGui::SetNextWindowSize(ImVec2(placement.width, placement.max_height),
                           placement.force ? ImGuiCond_Always : ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Scene")) {
    ImGui::End();
    return {false, false};
  }
  ImGui::PushTextWrapPos(0.0f);  // status lines wrap at the panel's edge instead of being cut
  ImGui::Text("scene '%s', step %llu", world.scene.name.c_str(), static_cast<unsigned long long>(world.steps));
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->drawStatus();
  if (world.failures.count > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "run-time failures: %llu (frames go on)",
                       static_cast<unsigned long long>(world.failures.count));
    ImGui::Text("last: %s", world.failures.last.c_str());
  }
  ImGui::TextDisabled("%s", keyHint(world).c_str());
  const float indent = ImGui::GetStyle().IndentSpacing * 2.0f;
  const float knob = ImGui::GetContentRegionAvail().x - widestLabel(world) - ImGui::GetStyle().ItemInnerSpacing.x - indent;
  ImGui::PushItemWidth(std::max(knob, 60.0f));
  editLiveCamera(world);
  bool changed = editSection(world.scene.camera, "camera (start pose)");
  for (SectionConfig& effect : world.scene.effects) changed |= editSection(effect, effect.name.c_str());
  changed |= editSection(world.scene.scene, "scene");
  changed |= editSection(world.scene.graphics, "graphics");
  ImGui::TextDisabled("keys marked *, scene.* and graphics.* apply on restart");
  ImGui::PopItemWidth();
  ImGui::PopTextWrapPos();
  const bool restart = ImGui::Button("Restart scene with these values");
  ImGui::End();
  return {changed, restart};
}

}  // namespace

std::string keyHint(const World& world) {
  std::string hint = "WASD move  Space/E up  Q down  Shift fast  RMB/Tab look  LMB crate";
  if (world.links.explosives != nullptr) hint += "  G charge";
  hint += "  F1 panels  F12 screenshot  Esc quit";
  return hint;
}

std::pair<bool, bool> drawGameOverlay(World& world, const engine::Overlay& overlay, const engine::Profiler& profiler,
                                      const std::string& gl_renderer) {
  if (overlay.mode == engine::OverlayMode::hidden) return {false, false};
  // What the effects tell the player: their lines join the strip, their banners show mid-screen.
  std::string status, banner;
  for (const std::unique_ptr<Effect>& effect : world.effects) {
    const HudText hud = effect->hud();
    if (!hud.line.empty()) status += (status.empty() ? "" : "   ") + hud.line;
    if (!hud.banner.empty()) banner += (banner.empty() ? "" : "\n") + hud.banner;
  }
  if (!banner.empty()) engine::drawBanner(banner);
  if (overlay.mode == engine::OverlayMode::compact) {
    engine::drawCompactStrip(profiler, status, keyHint(world));
    return {false, false};
  }
  const engine::OverlayLayout layout = engine::currentOverlayLayout(overlay);
  engine::drawProfilerWindow(profiler, world.systems, gl_renderer, layout.frame);
  return drawScenePanel(world, layout.game);
}

}  // namespace game
