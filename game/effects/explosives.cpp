// The `explosives` effect: the player's fused charges (game/explosives). It steps after the
// Bullet world and before everything a blast pushes, and publishes this step's detonations in
// EffectLinks::blasts: the water, the blob and the sprites apply them in their own steps with the
// shared law of fluid/core/blast.hpp; the crates were already pushed by stepExplosives.
#include "game/explosives/explosives.hpp"

#include "engine/render/frame.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/world/level_assets.hpp"
#include "game/world/rigid_bodies.hpp"

#include <imgui.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace game {
namespace {

const ParamTable<ExplosiveParams>& table() {
  static const ParamTable<ExplosiveParams> rows{
      param<&ExplosiveParams::fuse_seconds>("fuse_seconds", 0.05, 60.0, "time from the throw to the detonation (s)"),
      param<&ExplosiveParams::throw_speed>("throw_speed", 0.0, 60.0,
                                           "speed of a thrown charge, G or middle click (m/s)"),
      param<&ExplosiveParams::lob_degrees>("lob_degrees", -80.0, 80.0,
                                           "the throw leaves this far above the aim (deg); 0: along the aim"),
      param<&ExplosiveParams::radius>("radius", 0.02, 1.0, "radius of the charge's Bullet sphere (m)"),
      param<&ExplosiveParams::mass>("mass", 0.05, 100.0, "mass of a charge (kg)"),
      param<&ExplosiveParams::impact_speed_change>(
          "impact_speed_change", 0.0, 100.0,
          "detonate early when one step changes its speed by more (m/s); 0 = fuse only"),
      param<&ExplosiveParams::impulse_at_1m>("impulse_at_1m", 0.0, 10000.0,
                                             "specific impulse 1 m from the blast (Pa s); falls as 1/r^2"),
      param<&ExplosiveParams::core_radius>("core_radius", 0.01, 5.0, "the impulse is capped at its value here (m)"),
      param<&ExplosiveParams::reach>("reach", 0.05, 50.0, "no push beyond this distance (m)"),
      param<&ExplosiveParams::max_live>("max_live", 1, 64, "charges in flight at once; more recycle the oldest"),
  };
  return rows;
}

class ExplosivesEffect final : public EffectOf<Explosives> {
 public:
  ExplosivesEffect(RigidBodies* bodies, std::shared_ptr<const LevelColliders> colliders, glm::vec3 gravity)
      : bodies_(bodies), colliders_(std::move(colliders)), gravity_(gravity) {}
  std::string_view name() const override { return "explosives"; }

  void applyLive(const SectionConfig& section, EffectLinks&) override {
    const ExplosiveParams fresh = table().parse(section);
    if (validateExplosiveParams(fresh).empty()) state.params = fresh;
  }

  StepOutcome step(const StepContext& ctx) override {
    const PhaseScope phase(ctx.profiler, engine::Phase::physics);
    stepExplosives(state, *bodies_->physics, ctx.step_seconds);
    ctx.links.blasts = state.detonations;
    return {};
  }

  std::string findNonFinite() const override {
    for (const Charge& charge : state.charges) {
      if (!charge.live) continue;
      const engine::BodyState body = engine::bodyState(*bodies_->physics, charge.body);
      if (!std::isfinite(body.position.x) || !std::isfinite(body.position.y) || !std::isfinite(body.position.z))
        return "explosives: charge body " + std::to_string(charge.body) + " position is not finite";
    }
    return {};
  }

  // The charges in flight (their Bullet bodies, fuse clocks and the speed the impact test compares
  // against), the effect's clock and counts: a replay whose fuse differs fails at the first
  // checkpoint after the throw, before the blast moves anything else.
  bool hashState(Fnv1a64& h, StateHashScratch&) const override {
    h.add(state.time);
    h.add(state.thrown);
    h.add(state.detonated);
    h.add(state.bodies_pushed);
    h.add(static_cast<std::uint64_t>(state.charges.size()));
    for (const Charge& charge : state.charges) {
      h.add(static_cast<std::uint8_t>(charge.live));
      if (!charge.live) continue;
      h.add(charge.detonates_at);
      hashVec3(h, charge.last_velocity);
      const engine::BodyState body = engine::bodyState(*bodies_->physics, charge.body);
      hashVec3(h, body.position);
      hashQuat(h, body.rotation);
      hashVec3(h, body.linear_velocity);
      hashVec3(h, body.angular_velocity);
    }
    return true;
  }

  void reportColumns(FrameColumns& row) const override {
    row.set("blasts", static_cast<double>(state.detonations.size()));
  }

  // While the throw key is held: where a charge thrown now would fly and land (from the eye, along
  // the view, as playerThrowExplosive throws it).
  bool prepareFrame(const FrameContext& ctx, std::string&) override {
    aiming_ = ctx.aiming;
    if (aiming_)
      predictThrow(state.params, throwOrigin(ctx.eye, ctx.view_dir), ctx.view_dir, gravity_, colliders_->parts, arc_);
    return true;
  }

  // A live charge is drawn as a dark stone sphere of its collision sphere's diameter
  // (content/models/charge.obj); it turns as Bullet rolls it.
  void submit(engine::FrameBatches& frame, const SubmitContext& ctx) override {
    for (const Charge& charge : state.charges) {
      if (!charge.live) continue;
      const engine::BodyState body = engine::bodyState(*bodies_->physics, charge.body);
      engine::DrawItem item;
      item.mesh = &ctx.assets.charge;
      item.texture = &ctx.assets.stone;
      item.tint = glm::vec3(0.35f);  // dark, so it reads as a charge against the paving
      item.specular = 0.3f;
      item.model = glm::translate(glm::mat4(1.0f), body.position) * glm::mat4_cast(body.rotation) *
                   glm::scale(glm::mat4(1.0f), glm::vec3(2.0f * state.params.radius));
      frame.opaque.push_back(item);
    }
    if (aiming_) submitAim(frame, ctx);
  }

  void drawStatus() const override {
    ImGui::Text("explosives: %d live, %llu thrown, %llu detonated (G or middle click throws)", liveCharges(state),
                static_cast<unsigned long long>(state.thrown), static_cast<unsigned long long>(state.detonated));
  }

 private:
  // The arc as a dotted line of glowing beads (one per 1/24 s of flight, from 0.05 s after the
  // throw so they start in front of the hand) and the landing point as a disc of the blast's core on the
  // surface it hits: orange where it lands, grey where the fuse would run out in the air.
  void submitAim(engine::FrameBatches& frame, const SubmitContext& ctx) const {
    engine::DrawItem bead;
    bead.mesh = &ctx.assets.charge;
    bead.tint = glm::vec3(2.4f, 1.3f, 0.35f);
    bead.specular = 0.0f;
    bead.casts_shadow = false;
    constexpr std::size_t kStride = 5;  // samples of 1/120 s between beads
    for (std::size_t k = 6; k < arc_.path.size(); k += kStride) {
      bead.model = glm::translate(glm::mat4(1.0f), arc_.path[k]) * glm::scale(glm::mat4(1.0f), glm::vec3(0.045f));
      frame.opaque.push_back(bead);
    }
    engine::DrawItem disc = bead;
    disc.tint = arc_.lands ? glm::vec3(2.6f, 0.8f, 0.15f) : glm::vec3(0.6f);
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    const glm::vec3 n = glm::length(arc_.end_normal) > 0.5f ? glm::normalize(arc_.end_normal) : up;
    const glm::quat tilt(up, n);  // the shortest rotation taking up onto the normal
    const float diameter = 2.0f * state.params.core_radius;
    disc.model = glm::translate(glm::mat4(1.0f), arc_.end - n * state.params.radius + n * 0.01f) *
                 glm::mat4_cast(tilt) * glm::scale(glm::mat4(1.0f), glm::vec3(diameter, 0.02f, diameter));
    frame.opaque.push_back(disc);
  }

  RigidBodies* bodies_;
  std::shared_ptr<const LevelColliders> colliders_;  // the level's depth-map colliders (the aim arc's ground)
  glm::vec3 gravity_;
  bool aiming_ = false;
  AimArc arc_;
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& error) {
  if (!ensureLevelColliders(ctx.content_dir, ctx.scene.scene.text("level"), ctx.links.colliders, error)) {
    error = "explosives: " + error;
    return nullptr;
  }
  auto effect = std::make_unique<ExplosivesEffect>(ctx.links.bodies, ctx.links.colliders, ctx.links.gravity);
  effect->state.params = table().parse(section);
  if (std::string bad = validateExplosiveParams(effect->state.params); !bad.empty()) {
    error = bad;
    return nullptr;
  }
  ctx.links.explosives = &effect->state;
  return effect;
}

constexpr std::string_view kNeeds[] = {"rigid_bodies"};
constexpr ColumnSpec kColumns[] = {{"blasts", ColumnFormat::count, "explosives that went off in the frame's step"}};

}  // namespace

const EffectDesc& explosivesEffect() {
  static const EffectDesc desc{"explosives",
                               "fused charges the player throws; their blasts push water, crates, sprites",
                               table().specs, kNeeds, &build, kColumns};
  return desc;
}

}  // namespace game
