#include "game/scene_panel.hpp"

#include "game/world/world.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace game {
namespace {

// One knob for one key, by its schema row; true when the value changed.
bool editParam(const ParamSpec& param, ParamValue& value) {
  const std::string label(param.key);
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
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%.*s", static_cast<int>(param.doc.size()), param.doc.data());
  return edited;
}

bool editSection(SectionConfig& section) {
  const SectionSpec* spec = findSection(section.name);
  if (spec == nullptr || !ImGui::TreeNodeEx(section.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return false;
  bool changed = false;
  for (const ParamSpec& param : spec->params) {
    auto it = section.params.find(param.key);
    if (it != section.params.end()) changed |= editParam(param, it->second);
  }
  ImGui::TreePop();
  return changed;
}

}  // namespace

std::pair<bool, bool> drawScenePanel(World& world) {
  ImGui::SetNextWindowPos(ImVec2(std::max(ImGui::GetIO().DisplaySize.x - 390.0f, 400.0f), 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Scene")) {
    ImGui::End();
    return {false, false};
  }
  ImGui::Text("scene '%s', step %llu", world.scene.name.c_str(), static_cast<unsigned long long>(world.steps));
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->drawStatus();
  if (world.failures.count > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "run-time failures: %llu (frames go on)",
                       static_cast<unsigned long long>(world.failures.count));
    ImGui::TextWrapped("last: %s", world.failures.last.c_str());
  }
  ImGui::TextDisabled("LMB throw crate, RMB/Tab look, WASD move, F12 screenshot");
  ImGui::PushItemWidth(ImGui::GetWindowWidth() * 0.5f);
  bool changed = editSection(world.scene.camera);
  for (SectionConfig& effect : world.scene.effects) changed |= editSection(effect);
  changed |= editSection(world.scene.scene);
  ImGui::TextDisabled("counts, sizes and scene.* apply on restart");
  ImGui::PopItemWidth();
  const bool restart = ImGui::Button("Restart scene with these values");
  ImGui::End();
  return {changed, restart};
}

}  // namespace game
