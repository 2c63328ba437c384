// The `gulls` effect: a few gulls circle over the fountain and scatter from every blast, climbing
// away from it, then drift back to their circles. Ambient life that shows where a blast went off
// from far away; it costs microseconds. Everything an effect contributes is in this file: its
// parameters (live or fixed), its state and step, what it adds to the replay hash, its CSV column,
// its soak check and what it hands the renderer. It reads the level's shape and this step's blasts
// from EffectLinks and publishes nothing.
//
// Flight: each gull steers toward a desired velocity with a bounded acceleration (Reynolds 1999,
// "Steering behaviors for autonomous characters": seek + separation), the desired velocity being
// the tangent of its own circle around the nozzle plus a spring back to the circle's radius and
// height; a blast within `scare_radius` replaces it by a flight away from the blast and upward for
// `scare_seconds`. Fixed step, seeded: deterministic and independent of the frame rate.
#include "engine/render/frame.hpp"
#include "fluid/core/finite.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/soak_checks.hpp"
#include "game/world/level_assets.hpp"

#include <imgui.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace game {
namespace {

struct GullParams {
  int count = 7;
  float circle_radius = 6.0f;  // m around the nozzle (each gull's own within ±30 %)
  float height = 7.0f;         // m above the ground (each gull's own within ±1.5 m)
  float speed = 4.5f;          // m/s along the circle
  float max_accel = 6.0f;      // m/s^2 of steering
  float scare_radius = 12.0f;  // m: blasts closer than this scatter a gull
  float scare_seconds = 4.0f;  // how long it flees
  float flee_speed = 10.0f;    // m/s while fleeing
  float wing_beats = 2.5f;     // per second (twice as fast while fleeing)
  float size = 1.0f;           // wingspan (m)
};

const ParamTable<GullParams>& table() {
  using P = GullParams;
  static const ParamTable<P> rows{
      fixed(param<&P::count>("count", 0, 64, "gulls (each on its own circle, seeded by scene.seed)")),
      param<&P::circle_radius>("circle_radius", 1.0, 50.0, "radius of their circles around the nozzle (m)"),
      param<&P::height>("height", 2.0, 50.0, "height of their circles above the ground (m)"),
      param<&P::speed>("speed", 0.5, 20.0, "cruising speed (m/s)"),
      param<&P::max_accel>("max_accel", 0.5, 50.0, "steering acceleration (m/s^2)"),
      param<&P::scare_radius>("scare_radius", 0.0, 100.0, "a blast closer than this scatters a gull (m)"),
      param<&P::scare_seconds>("scare_seconds", 0.0, 30.0, "how long a scattered gull flees (s)"),
      param<&P::flee_speed>("flee_speed", 0.5, 40.0, "speed while fleeing (m/s)"),
      param<&P::wing_beats>("wing_beats", 0.0, 10.0, "wing beats per second when cruising"),
      param<&P::size>("size", 0.1, 5.0, "wingspan (m)"),
  };
  return rows;
}

struct Gull {
  glm::vec3 position{0.0f}, velocity{0.0f};
  float radius_scale = 1.0f;  // its circle: circle_radius * radius_scale
  float height_offset = 0.0f;
  float direction = 1.0f;   // +1 counter-clockwise seen from above, -1 clockwise
  float scared = 0.0f;      // s of fleeing left
  glm::vec3 away{0.0f};     // unit direction of the flight while scared
  float wing_phase = 0.0f;  // rad
};

struct Gulls {
  GullParams params;
  glm::vec3 centre{0.0f};  // the nozzle, on the ground
  std::vector<Gull> flock;
  std::uint64_t scatters = 0;  // gulls scattered by blasts so far
};

glm::vec3 clampLength(glm::vec3 v, float most) {
  const float length = glm::length(v);
  return length > most ? v * (most / length) : v;
}

// What the gull wants to fly at: along its circle, sprung back onto it; or away from the blast.
glm::vec3 desiredVelocity(const Gulls& g, const Gull& gull) {
  const GullParams& p = g.params;
  if (gull.scared > 0.0f) return p.flee_speed * gull.away;
  glm::vec3 radial = gull.position - g.centre;
  radial.y = 0.0f;
  const float r = glm::length(radial);
  const glm::vec3 out = r > 1e-4f ? radial / r : glm::vec3(1.0f, 0.0f, 0.0f);
  const glm::vec3 tangent = gull.direction * glm::vec3(-out.z, 0.0f, out.x);
  const float radius_error = p.circle_radius * gull.radius_scale - r;
  const float height_error = g.centre.y + p.height + gull.height_offset - gull.position.y;
  // No faster than the gull flies when fleeing: far from its circle it flies back, not faster.
  return clampLength(p.speed * tangent + 0.8f * radius_error * out + glm::vec3(0.0f, 0.8f * height_error, 0.0f),
                     std::max(p.speed, p.flee_speed));
}

void stepGulls(Gulls& g, std::span<const fluid::Blast> blasts, float dt) {
  const GullParams& p = g.params;
  for (const fluid::Blast& blast : blasts) {
    for (Gull& gull : g.flock) {
      const glm::vec3 from = gull.position - blast.centre;
      const float distance = glm::length(from);
      if (!(distance < p.scare_radius)) continue;
      // Away and upward: a gull right above the blast climbs straight up.
      const glm::vec3 flat = distance > 1e-4f ? from / distance : glm::vec3(0.0f);
      gull.away = glm::normalize(flat + glm::vec3(0.0f, 1.0f, 0.0f));
      gull.scared = p.scare_seconds;
      ++g.scatters;
    }
  }
  for (std::size_t i = 0; i < g.flock.size(); ++i) {
    Gull& gull = g.flock[i];
    glm::vec3 steer = desiredVelocity(g, gull) - gull.velocity;
    // Separation: a gull closer than one wingspan and a half pushes the other away.
    for (std::size_t j = 0; j < g.flock.size(); ++j) {
      const glm::vec3 d = gull.position - g.flock[j].position;
      const float gap = glm::length(d);
      if (j != i && gap > 1e-4f && gap < 1.5f * p.size) steer += (1.5f * p.size - gap) * 4.0f * (d / gap);
    }
    gull.velocity += clampLength(steer, p.max_accel * dt);
    gull.position += gull.velocity * dt;
    gull.position.y = std::max(gull.position.y, g.centre.y + 1.0f);  // never into the ground
    const float beats = p.wing_beats * (gull.scared > 0.0f ? 2.0f : 1.0f);
    gull.wing_phase = std::fmod(gull.wing_phase + 6.2831853f * beats * dt, 6.2831853f);
    gull.scared = std::max(0.0f, gull.scared - dt);
  }
}

// Each gull on its own circle, spread around it, already cruising (seeded: the same flock each run).
void placeFlock(Gulls& g, std::uint32_t seed) {
  std::mt19937 rng(seed ^ 0x6a09e667u);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  g.flock.assign(static_cast<std::size_t>(std::max(g.params.count, 0)), Gull{});
  for (Gull& gull : g.flock) {
    gull.radius_scale = 0.7f + 0.6f * unit(rng);
    gull.height_offset = -1.5f + 3.0f * unit(rng);
    gull.direction = unit(rng) < 0.5f ? -1.0f : 1.0f;
    gull.wing_phase = 6.2831853f * unit(rng);
    const float angle = 6.2831853f * unit(rng);
    const glm::vec3 out(std::cos(angle), 0.0f, std::sin(angle));
    gull.position = g.centre + g.params.circle_radius * gull.radius_scale * out +
                    glm::vec3(0.0f, g.params.height + gull.height_offset, 0.0f);
    gull.velocity = g.params.speed * gull.direction * glm::vec3(-out.z, 0.0f, out.x);
  }
}

std::size_t fleeing(const Gulls& g) {
  std::size_t n = 0;
  for (const Gull& gull : g.flock) n += gull.scared > 0.0f ? 1u : 0u;
  return n;
}

class GullsEffect final : public EffectOf<Gulls> {
 public:
  std::string_view name() const override { return "gulls"; }

  void applyLive(const SectionConfig& section, EffectLinks&) override {
    state.params = table().parseLive(section, state.params);
  }

  StepOutcome step(const StepContext& ctx) override {
    stepGulls(state, ctx.links.blasts, static_cast<float>(ctx.step_seconds));
    return {};
  }

  std::string findNonFinite() const override {
    for (std::size_t i = 0; i < state.flock.size(); ++i) {
      const Gull& gull = state.flock[i];
      if (!fluid::isFinite(gull.position) || !fluid::isFinite(gull.velocity))
        return "gulls: gull " + std::to_string(i) + " is not finite";
    }
    return {};
  }

  bool hashState(Fnv1a64& h, StateHashScratch&) const override {
    h.add(static_cast<std::uint64_t>(state.flock.size()));
    for (const Gull& gull : state.flock) {
      hashVec3(h, gull.position);
      hashVec3(h, gull.velocity);
      h.add(gull.scared);
    }
    h.add(state.scatters);
    return true;
  }

  void reportColumns(FrameColumns& row) const override {
    row.set("gulls_fleeing", static_cast<double>(fleeing(state)));
  }

  // A gull stays in the sky near the fountain: above the ground, within its circle plus one
  // flight from a blast (and the way back), and no faster than it can fly.
  void soakCheck(SoakProbe& probe) const override {
    probe.count("gulls", state.flock.size());
    const GullParams& p = state.params;
    const float reach = 1.5f * (p.circle_radius + p.height) + 1.5f * p.flee_speed * p.scare_seconds + 10.0f;
    const float fastest = 1.5f * std::max(p.flee_speed, p.speed) + 2.0f * p.size;
    for (std::size_t i = 0; i < state.flock.size(); ++i) {
      const Gull& gull = state.flock[i];
      if (glm::length(gull.position - state.centre) > reach || gull.position.y < state.centre.y ||
          glm::length(gull.velocity) > fastest)
        probe.fail("gull " + std::to_string(i) + " left the sky over the fountain (at " +
                   std::to_string(gull.position.x) + ", " + std::to_string(gull.position.y) + ", " +
                   std::to_string(gull.position.z) + " m, " + std::to_string(glm::length(gull.velocity)) + " m/s)");
    }
  }

  // A white body (the charge's sphere stretched along the flight) and two grey wings (the crate
  // stretched thin) beating about the body's axis.
  void submit(engine::FrameBatches& frame, const SubmitContext& ctx) override {
    const float s = state.params.size;
    for (const Gull& gull : state.flock) {
      const float speed = glm::length(gull.velocity);
      const glm::vec3 forward = speed > 1e-4f ? gull.velocity / speed : glm::vec3(0.0f, 0.0f, 1.0f);
      glm::vec3 side = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), forward);
      side = glm::length(side) > 1e-4f ? glm::normalize(side) : glm::vec3(1.0f, 0.0f, 0.0f);
      const glm::vec3 up = glm::cross(forward, side);
      const glm::mat4 frame_of_gull(glm::vec4(side, 0.0f), glm::vec4(up, 0.0f), glm::vec4(forward, 0.0f),
                                    glm::vec4(gull.position, 1.0f));
      engine::DrawItem body;
      body.mesh = &ctx.assets.charge;
      body.tint = glm::vec3(0.92f, 0.92f, 0.88f);
      body.model = frame_of_gull * glm::scale(glm::mat4(1.0f), glm::vec3(0.14f, 0.12f, 0.42f) * s);
      frame.opaque.push_back(body);
      const float flap = 0.6f * std::sin(gull.wing_phase);
      for (const float hand : {-1.0f, 1.0f}) {
        engine::DrawItem wing;
        wing.mesh = &ctx.assets.crate;
        wing.tint = glm::vec3(0.55f, 0.57f, 0.6f);
        wing.model = frame_of_gull * glm::rotate(glm::mat4(1.0f), hand * flap, glm::vec3(0.0f, 0.0f, 1.0f)) *
                     glm::translate(glm::mat4(1.0f), glm::vec3(hand * 0.27f * s, 0.0f, 0.0f)) *
                     glm::scale(glm::mat4(1.0f), glm::vec3(0.45f * s, 0.015f * s, 0.16f * s));
        frame.opaque.push_back(wing);
      }
    }
  }

  void drawStatus() const override {
    ImGui::Text("gulls: %zu, %zu fleeing, %llu scattered by blasts", state.flock.size(), fleeing(state),
                static_cast<unsigned long long>(state.scatters));
  }
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string&) {
  auto effect = std::make_unique<GullsEffect>();
  Gulls& g = effect->state;
  g.params = table().parse(section);
  g.centre = glm::vec3(ctx.links.level.nozzle.x, 0.0f, ctx.links.level.nozzle.z);
  placeFlock(g, ctx.seed);
  return effect;
}

using enum ColumnFormat;
constexpr ColumnSpec kColumns[] = {
    {"gulls_fleeing", count, "gulls fleeing a blast"},
};

}  // namespace

const EffectDesc& gullsEffect() {
  static const EffectDesc desc{
      "gulls",       "gulls circling over the fountain that scatter from blasts (steering behaviours)",
      table().specs, {},
      &build,        kColumns};
  return desc;
}

}  // namespace game
