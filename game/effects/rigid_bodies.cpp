// The `rigid_bodies` effect: the Bullet world (ground, basin and statue as static meshes; crates
// stacked at start, more thrown by the player). State and physics: game/world/rigid_bodies.hpp.
#include "game/world/rigid_bodies.hpp"
#include "engine/physics/physics_world.hpp"
#include "engine/render/frame.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/world/level_assets.hpp"

#include <imgui.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace game {
namespace {

const ParamTable<RigidBodyParams>& table() {
  static const ParamTable<RigidBodyParams> rows{
      param<&RigidBodyParams::gravity>("gravity", -100.0, 100.0, "m/s^2"),
      param<&RigidBodyParams::crates>("crates", 0, 200, "crates stacked around the fountain"),
      param<&RigidBodyParams::crate_size>("crate_size", 0.1, 5.0, "crate edge length (m)"),
      param<&RigidBodyParams::density>(
          "density", 10.0, 10000.0,
          "crate density (kg/m^3; fixed at construction): in water (1000) a crate below it floats, above it sinks"),
      param<&RigidBodyParams::throw_speed>("throw_speed", 0.0, 100.0, "speed of a crate thrown with left click (m/s)"),
  };
  return rows;
}

glm::mat4 bodyMatrix(const engine::BodyState& a, const engine::BodyState& b, float alpha, float scale) {
  const glm::vec3 position = glm::mix(a.position, b.position, alpha);
  const glm::quat rotation = glm::slerp(a.rotation, b.rotation, alpha);
  return glm::translate(glm::mat4(1.0f), position) * glm::mat4_cast(rotation) *
         glm::scale(glm::mat4(1.0f), glm::vec3(scale));
}

class RigidBodiesEffect final : public EffectOf<RigidBodies> {
 public:
  std::string_view name() const override { return "rigid_bodies"; }

  // Live: gravity and throw speed. The crates (count, size, density) are placed at construction.
  void applyLive(const SectionConfig& section, EffectLinks& links) override {
    RigidBodyParams fresh = table().parse(section);
    fresh.crates = state.params.crates;
    fresh.crate_size = state.params.crate_size;
    fresh.density = state.params.density;
    if (fresh.gravity != state.params.gravity) engine::setGravity(*state.physics, fresh.gravity);
    state.params = fresh;
    links.gravity = fresh.gravity;
  }

  StepOutcome step(const StepContext& ctx) override {
    const PhaseScope phase(ctx.profiler, engine::Phase::physics);
    stepRigidBodies(state, ctx.step_seconds, ctx.substeps);
    return {};
  }

  std::string findNonFinite() const override { return findNonFiniteBodyState(state); }

  // Every crate, interpolated between the last two steps (slerp for the rotation).
  void submit(engine::FrameBatches& frame, const SubmitContext& ctx) override {
    for (std::size_t i = 0; i < state.crates.size(); ++i) {
      engine::DrawItem crate;
      crate.mesh = &ctx.assets.crate;
      crate.texture = &ctx.assets.wood;
      crate.specular = 0.08f;
      crate.model = bodyMatrix(state.previous[i], state.current[i], ctx.alpha, state.params.crate_size);
      frame.opaque.push_back(crate);
    }
  }

  void drawStatus() const override {
    ImGui::Text("rigid bodies: %d (crates thrown %d)", engine::bodyCount(*state.physics), state.thrown);
  }
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& error) {
  auto effect = std::make_unique<RigidBodiesEffect>();
  RigidBodyParams params = table().parse(section);
  params.level = ctx.scene.scene.text("level");
  if (!buildRigidBodies(params, ctx.content_dir, ctx.seed, effect->state, error)) {
    error = "rigid_bodies: " + error;
    return nullptr;
  }
  // The particles fall with the bodies' gravity; the water pushes the crates.
  ctx.links.gravity = effect->state.params.gravity;
  ctx.links.bodies = &effect->state;
  return effect;
}

}  // namespace

RigidBodyParams rigidParamsFrom(const SectionConfig& section) { return table().parse(section); }

const EffectDesc& rigidBodiesEffect() {
  static const EffectDesc desc{
      "rigid_bodies", "Bullet world: ground, basin, statue, crates", table().specs, {}, &build};
  return desc;
}

}  // namespace game
