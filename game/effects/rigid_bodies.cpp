// The `rigid_bodies` effect: the Bullet world (ground, basin and statue as static meshes; crates
// stacked at start, more thrown by the player). State and physics: game/world/rigid_bodies.hpp.
#include "game/world/rigid_bodies.hpp"
#include "engine/physics/physics_world.hpp"
#include "engine/render/frame.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/paths.hpp"
#include "game/soak_checks.hpp"
#include "game/world/fountain.hpp"
#include "game/world/level_assets.hpp"

#include <imgui.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace game {
namespace {

const ParamTable<RigidBodyParams>& table() {
  static const ParamTable<RigidBodyParams> rows{
      param<&RigidBodyParams::gravity>("gravity", -100.0, 100.0, "m/s^2"),
      fixed(param<&RigidBodyParams::crates>("crates", 0, 200, "crates stacked around the fountain")),
      fixed(param<&RigidBodyParams::crate_size>("crate_size", 0.1, 5.0, "crate edge length (m)")),
      fixed(param<&RigidBodyParams::density>(
          "density", 10.0, 10000.0, "crate density (kg/m^3): in water (1000) a crate below it floats, above it sinks")),
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

  void applyLive(const SectionConfig& section, EffectLinks& links) override {
    const RigidBodyParams fresh = table().parseLive(section, state.params);
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

  // The crates' speeds, and their centres against the fountain's baked parts with the half edge as
  // offset: only the fountain level has a basin for a crate to be inside. Resting contacts stay
  // within Bullet's few-centimetre margin; half an edge means the centre reached the surface (the
  // crate sank or went through a wall). The depth maps answer "beyond reach" farther than their
  // margin from a part: a centre that far is no penetration.
  void soakCheck(SoakProbe& probe) const override {
    for (const engine::BodyState& body : state.current) probe.bodySpeed(glm::length(body.linear_velocity));
    if (probe.level != "fountain") return;
    probe.points.clear();
    for (const engine::BodyState& body : state.current) probe.points.push_back(body.position);
    const float size = state.params.crate_size;
    std::string error;
    if (!ensureFountainColliders(contentDir(), probe.level_colliders, error))
      return probe.fail("level colliders: " + error);
    for (const fluid::CachedCollider& part : probe.level_colliders->parts) {
      const Penetration p =
          worstPenetration(probe.points, part.collider, fluid::ColliderPose{}, size, 0.5f * size, probe.scratch);
      probe.penetration("crates", p, probe.crate_tolerance,
                        "crate " + std::to_string(p.index) + " (edge " + std::to_string(size) + " m, " + part.name + ")");
    }
  }

  // Every crate's transform and velocities as Bullet holds them, the pending external forces (the
  // water's push for the next step) and the crates thrown.
  bool hashState(Fnv1a64& h, StateHashScratch&) const override {
    h.add(static_cast<std::uint64_t>(state.crates.size()));
    h.add(static_cast<std::int64_t>(state.thrown));
    const engine::PhysicsWorld& physics = *state.physics;
    for (engine::BodyId id : state.crates) {
      const engine::BodyState s = engine::bodyState(physics, id);
      hashVec3(h, s.position);
      hashQuat(h, s.rotation);
      hashVec3(h, s.linear_velocity);
      hashVec3(h, s.angular_velocity);
      const auto k = static_cast<std::size_t>(id);
      hashVec3(h, k < physics.external_force.size() ? physics.external_force[k] : glm::vec3(0.0f));
      hashVec3(h, k < physics.external_torque.size() ? physics.external_torque[k] : glm::vec3(0.0f));
    }
    return true;
  }

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
