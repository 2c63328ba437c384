// The `sprite_particles` effect: mist from the nozzle and spray from the SPH water as GPU
// state-preserving particles (Kolb et al. 2004). State and GPU code: game/world/sprite_particles.hpp.
#include "game/world/sprite_particles.hpp"
#include "engine/render/frame.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/soak_checks.hpp"
#include "game/world/fountain.hpp"

#include <imgui.h>

#include <cstdio>

namespace game {
namespace {

const ParamTable<SpriteParticleParams>& table() {
  using P = SpriteParticleParams;
  static const ParamTable<P> rows{
      param<&P::rate>("rate", 0.0, 100000.0, "mist sprites emitted per second at the nozzle"),
      param<&P::speed>("speed", 0.0, 50.0, "mist speed at the nozzle (m/s, +-20%)"),
      param<&P::spread_degrees>("spread_degrees", 0.0, 90.0, "half-angle of the mist cone"),
      param<&P::lifetime>("lifetime", 0.1, 60.0, "mist sprite lifetime (s, +-25%)"),
      fixed(param<&P::max_particles>("max_particles", 0, 1000000,
                                     "GPU sprite budget, mist and spray (0 = no GPU resources)")),
      param<&P::size>("size", 0.005, 1.0, "sprite radius (m)"),
      param<&P::restitution>("restitution", 0.0, 1.0,
                             "Kolb 2004 resilience: bounce off the baked ground/basin/statue depth maps"),
      param<&P::friction>("friction", 0.0, 1.0, "Kolb 2004 friction on the baked colliders"),
      param<&P::spray_rate>("spray_rate", 0.0, 10000.0,
                            "Ihmsen 2012 k: spray sprites per second from a surface particle with I_k = 1 (0 = no "
                            "spray)"),
      param<&P::spray_energy_min>("spray_energy_min", 0.0, 1000.0,
                                  "Ihmsen 2012 tau_k,min: specific kinetic energy |v|^2/2 (J/kg) where spray starts"),
      param<&P::spray_energy_max>("spray_energy_max", 0.0, 1000.0,
                                  "Ihmsen 2012 tau_k,max: |v|^2/2 (J/kg) of full spray"),
      param<&P::spray_surface_density>("spray_surface_density", 0.0, 2.0,
                                       "rho/rho0 at or below which an SPH particle counts as at the free surface"),
      param<&P::spray_lifetime>("spray_lifetime", 0.1, 60.0, "spray sprite lifetime (s, +-25%)"),
      param<&P::spray_max_per_step>("spray_max_per_step", 0, 100000, "cap on spray births per step"),
      param<&P::foam_trapped_air_rate>(
          "foam_trapped_air_rate", 0.0, 100000.0,
          "Ihmsen 2012 k_ta: foam/bubble/spray sprites per second from an SPH particle with I_ta = I_k = 1 (0 with "
          "foam_wave_crest_rate 0 = no foam)"),
      param<&P::foam_wave_crest_rate>("foam_wave_crest_rate", 0.0, 100000.0,
                                      "Ihmsen 2012 k_wc: the same for the wave-crest potential I_wc"),
      param<&P::foam_ta_min>("foam_ta_min", 0.0, 1000.0,
                             "Ihmsen 2012 tau_ta,min: trapped-air potential (sum |v_ij|(1 - v^.x^)W, m/s) where foam starts"),
      param<&P::foam_ta_max>("foam_ta_max", 0.0, 1000.0, "Ihmsen 2012 tau_ta,max: trapped-air potential of full foam"),
      param<&P::foam_wc_min>("foam_wc_min", 0.0, 1000.0,
                             "Ihmsen 2012 tau_wc,min: wave-crest curvature sum (1 - n_i.n_j)W where foam starts"),
      param<&P::foam_wc_max>("foam_wc_max", 0.0, 1000.0, "Ihmsen 2012 tau_wc,max: wave-crest curvature of full foam"),
      param<&P::foam_energy_min>("foam_energy_min", 0.0, 1000.0,
                                 "Ihmsen 2012 tau_k,min for foam: |v|^2/2 (J/kg) where diffuse births start"),
      param<&P::foam_energy_max>("foam_energy_max", 0.0, 1000.0, "Ihmsen 2012 tau_k,max for foam: |v|^2/2 (J/kg)"),
      param<&P::foam_lifetime>("foam_lifetime", 0.1, 60.0, "foam/bubble sprite lifetime (s, +-25%); foam fades over it"),
      param<&P::bubble_buoyancy>("bubble_buoyancy", 0.0, 100.0, "Ihmsen 2012 eq. 8 k_b: bubble buoyancy (times -g)"),
      param<&P::bubble_drag>("bubble_drag", 0.0, 1.0,
                             "Ihmsen 2012 eq. 8 k_d: fraction of the bubble's slip against the water removed per step"),
      param<&P::foam_spray_below>("foam_spray_below", 0, 1000,
                                  "Ihmsen 2012 4.2: a diffuse sprite with fewer fluid neighbours is spray"),
      param<&P::foam_bubble_above>("foam_bubble_above", 0, 1000,
                                   "Ihmsen 2012 4.2: a diffuse sprite with more fluid neighbours is a bubble"),
      param<&P::foam_max_per_step>("foam_max_per_step", 0, 100000, "cap on foam/bubble/spray births per step"),
      param<&P::blast_debris>("blast_debris",
                              "a blast throws dark grit besides its fireball and smoke (the blob's street: off, its "
                              "sewer's rim lets fast grit through)"),
  };
  return rows;
}

class SpriteParticlesEffect final : public EffectOf<SpriteParticles> {
 public:
  explicit SpriteParticlesEffect(const SphFluid* fluid) : fluid_(fluid) {}

  std::string_view name() const override { return "sprite_particles"; }

  void applyLive(const SectionConfig& section, EffectLinks& links) override {
    state.params = spriteParamsFrom(section, links.gravity, links.level.nozzle);
  }

  // After the water (registry order): spray is born from this step's SPH state. GPU work; a
  // no-op without a GL context (attachGpu), so it only enters the phase when attached.
  StepOutcome step(const StepContext& ctx) override {
    if (!state.attached) return {};
    const PhaseScope phase(ctx.profiler, engine::Phase::fluid);
    return {stepSpriteParticles(state, fluid_, static_cast<float>(ctx.step_seconds), ctx.links.blasts)};
  }

  std::string findNonFinite() const override { return findNonFiniteSprite(state); }

  void reportColumns(FrameColumns& row) const override { row.set("sprites", liveSprites(state)); }

  // The sprites live on the GPU: read them back after every step so the NaN and penetration
  // checks see every live sprite.
  void soakBeforeStep(SoakProbe&) override { state.readback_every = 1; }

  // The read-back against the depth maps the sprites collide with on the GPU (baked from the same
  // models; the CPU lookup of fluid/collide is the reference the shader decodes).
  void soakCheck(SoakProbe& probe) const override {
    probe.count("sprites", liveSprites(state));
    const engine::GpuReadback& sample = state.gpu.readback;
    for (const glm::vec4& v : sample.velocities) probe.particleSpeed(glm::length(glm::vec3(v)));
    // The read-back must be fresh (the frame just drawn ran it): a check of stale data would pass
    // whatever the GPU did.
    if (state.attached && state.readback_every > 0 && sample.step != state.steps)
      probe.fail("sprite read-back is stale (step " + std::to_string(sample.step) + " of " +
                 std::to_string(state.steps) + ")");
    // Nothing read back (no GL context: soak --no-render simulates no sprite) leaves nothing to check.
    if (sample.positions.empty()) return;
    probe.points.clear();
    for (const glm::vec4& p : sample.positions) probe.points.emplace_back(p);
    const std::size_t parts = state.level_colliders ? state.level_colliders->parts.size() : 0;
    for (std::size_t c = 0; c < parts; ++c) {
      const Penetration p = worstPenetration(probe.points, state.level_colliders->parts[c].collider,
                                             fluid::ColliderPose{}, state.params.size, 0.0f, probe.scratch);
      probe.penetration("sprites", p, probe.particle_tolerance,
                        "live sprite " + std::to_string(p.index) + " (" + state.collider_names[c] + ")");
    }
  }

  void attachGpu(const GpuContext& gpu) override {
    if (!attachSpriteGpu(state, gpu.shader_dir, gpu.content_dir, static_cast<float>(gpu.step_seconds)))
      std::fprintf(stderr, "fluiddemo: sprite_particles off: %s\n", state.gpu_error.c_str());
  }
  void detachGpu() override { detachSpriteGpu(state); }

  void submit(engine::FrameBatches& frame, const SubmitContext&) override {
    if (state.attached && state.gpu.ready) frame.sprites.push_back(&state.gpu);
  }

  // The CPU index allocator (Kolb §3.3.1) knows every live sprite without a read-back.
  void drawStatus() const override {
    const SpriteParticles& s = state;
    if (!s.gpu_error.empty()) {
      ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "sprites off: %s", s.gpu_error.c_str());
      return;
    }
    if (!s.attached) {
      ImGui::Text("sprites: no GL context (not simulated)");
      return;
    }
    const engine::IndexAllocator& a = s.gpu.allocator;
    ImGui::Text("sprites: %u live / %u budget (%ux%u texels), active range %u, free %zu", a.live_count, s.capacity,
                s.gpu.desc.width, s.gpu.desc.height, a.active_range, a.free_heap.size());
    ImGui::Text(
        "  born: mist %llu, spray %llu (%u this step), blasts %llu (%llu shock rings on the water, %llu not born "
        "inside a collider), dropped (budget full) %llu",
        static_cast<unsigned long long>(s.born_mist), static_cast<unsigned long long>(s.born_spray), s.spray_last_step,
        static_cast<unsigned long long>(s.born_blast), static_cast<unsigned long long>(s.shock_rings),
        static_cast<unsigned long long>(s.buried_blast), static_cast<unsigned long long>(s.dropped));
    ImGui::Text("  foam/bubbles (Ihmsen 2012): %llu born, last step %u spray / %u foam / %u bubbles at birth",
                static_cast<unsigned long long>(s.born_diffuse), s.diffuse_last_step[0], s.diffuse_last_step[1],
                s.diffuse_last_step[2]);
    ImGui::Text("  sort pass %u of %u, colliders loaded in %.0f ms", s.gpu.sort_step,
                engine::sortPassCount(s.gpu.capacity), s.bake_ms);
  }

 private:
  const SphFluid* fluid_;  // spray source (null without sph_fluid)
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& /*error*/) {
  auto effect = std::make_unique<SpriteParticlesEffect>(ctx.links.fluid);
  const SpriteParticleParams params = spriteParamsFrom(section, ctx.links.gravity, ctx.links.level.nozzle);
  initSpriteParticles(effect->state, params, params.max_particles, ctx.seed ^ 0x9e3779b9u);
  effect->state.level = ctx.scene.scene.text("level");
  // The level's colliders when an effect built before loaded them (sph_fluid, explosives); else at attach.
  if (ctx.links.colliders && ctx.links.colliders->level == effect->state.level)
    effect->state.level_colliders = ctx.links.colliders;
  return effect;
}

}  // namespace

SpriteParticleParams spriteParamsFrom(const SectionConfig& section, glm::vec3 gravity, glm::vec3 nozzle) {
  SpriteParticleParams p = table().parse(section);
  p.gravity = gravity;
  p.nozzle = nozzle;
  return p;
}

constexpr ColumnSpec kColumns[] = {
    {"sprites", ColumnFormat::count, "live GPU sprite particles (the allocator's count; 0 without GL)"}};

const EffectDesc& spriteParticlesEffect() {
  static const EffectDesc desc{"sprite_particles",
                               "GPU sprites (Kolb 2004): nozzle mist, SPH spray, foam and bubbles (Ihmsen 2012), depth-map collisions",
                               table().specs,
                               {},
                               &build,
                               kColumns};
  return desc;
}

}  // namespace game
