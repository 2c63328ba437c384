// The `sph_fluid` effect: the fountain's water as a CPU SPH fluid (fluid/sph), coupled two-way to
// the crates when rigid_bodies is listed. State and setup: game/world/sph_fluid.hpp.
#include "game/world/sph_fluid.hpp"
#include "fluid/sph/blast.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/soak_checks.hpp"
#include "game/world/fountain.hpp"
#include "game/world/rigid_bodies.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace game {
namespace {

constexpr std::string_view kSolverNames[] = {"dfsph", "wcsph"};
constexpr fluid::SphSolverKind kSolverValues[] = {fluid::SphSolverKind::dfsph, fluid::SphSolverKind::wcsph};

const ParamTable<SphFluidParams>& table() {
  using P = SphFluidParams;
  static const ParamTable<P> rows{
      fixed(choice<&P::solver>("solver", kSolverNames, kSolverValues,
                               "dfsph (Bender & Koschier 2015) or wcsph (Becker & Teschner 2007)")),
      fixed(param<&P::max_particles>("max_particles", 1, 50000,
                                     "the water in particles: with the pump the basin starts filled with all of it; "
                                     "without, the jet's budget")),
      fixed(param<&P::particle_radius>("particle_radius", 0.01, 0.2, "r (m); spacing 2r")),
      param<&P::jet_speed>("jet_speed", 0.1, 20.0,
                           "speed of the jet at the nozzle (m/s); the speed cap, sound speed and top sink follow it"),
      fixed(param<&P::nozzle_radius>("nozzle_radius", 0.0, 0.5,
                                     "radius of the nozzle disc (m); particles per layer = lattice points inside")),
      param<&P::rate>("rate", 0.0, 50000.0, "particles emitted per second (capped: layers never overlap)"),
      param<&P::viscosity>("viscosity", 0.0, 1.0, "kinematic viscosity nu (m^2/s)"),
      fixed(param<&P::pump>("pump",
                            "circulate the water: an intake in the basin floor, a gutter round the basin, the nozzle "
                            "gives the same particles back; false = the nozzle makes water")),
      param<&P::pump_delay>("pump_delay", 0.0, 10.0, "seconds a particle spends in the pump's pipe"),
      param<&P::spray_speed>("spray_speed", 0.0, 1000.0,
                             "water faster than this (m/s) with few calm neighbours, or faster than cfl 2r / "
                             "max_time_step, flies ballistic outside the SPH solve, slowed by the water where it is "
                             "in it, until it rejoins slow among water (Ihmsen et al. 2012 spray); 0 = off"),
      param<&P::spray_terminal_speed>("spray_terminal_speed", 0.0, 1000.0,
                                      "the spray's air drag as the speed at which it balances gravity (m/s); 0 = none"),
      param<&P::speculative_contacts>(
          "speculative_contacts",
          "before the push-out, water loses the approach that would take it within half a radius of a collider in "
          "the step (fluid::SphParams::speculative_contacts); false = the push-out alone"),
      param<&P::cfl>("cfl", 0.05, 1.0, "CFL number: a step moves no particle more than cfl * 2r"),
      param<&P::max_time_step>("max_time_step", 0.0005, 0.05, "upper bound of one adaptive SPH step (s)"),
      param<&P::density_error>("density_error", 0.00001, 0.05,
                               "dfsph: mean density error tolerance of the pressure solve (0.0005 = 0.05 %)"),
      param<&P::force_bound>(
          "force_bound", 0.0, 1.0,
          "dfsph: force condition |g| dt^2 <= force_bound * cfl * 2r (keeps resting water still); 0 = off"),
      param<&P::warm_start>("warm_start",
                            "dfsph: start the density solve from warm_start_share x the previous step's stiffness "
                            "(Bender & Koschier 2017 sec. 4.3; fluid::SphParams::warm_start); false = from zero"),
      param<&P::warm_start_share>("warm_start_share", 0.0, 1.0,
                                  "dfsph: the share of the previous step's stiffness a warm start begins from"),
      fixed(param<&P::couple_bodies>(
          "couple_bodies", "crates and water push each other, two-way (only when rigid_bodies is listed too)")),
  };
  return rows;
}

// Where a failing particle is: its signed distance to every collider within a particle radius of
// it, so a soak report tells a particle squeezed between two crates from one that went through a wall.
std::string collidersNear(const fluid::SphWorld& sph, glm::vec3 position, PenetrationScratch& scratch) {
  const float radius = sph.params.particle_radius;
  std::string out;
  for (std::size_t c = 0; c < sph.colliders.size(); ++c) {
    const fluid::SphCollider& collider = sph.colliders[c];
    const Penetration p =
        worstPenetration(std::span(&position, 1), *collider.shape, collider.pose, radius, radius, scratch);
    if (p.depth <= 0.0f) continue;
    char part[96];
    std::snprintf(part, sizeof(part), "%s collider %zu%s %.4f m", out.empty() ? "; within a radius of" : ",", c,
                  fluid::sphColliderMoves(collider) ? " (moving)" : "", static_cast<double>(radius - p.depth));
    out += part;
  }
  return out;
}

class SphFluidEffect final : public EffectOf<SphFluid> {
 public:
  SphFluidEffect(RigidBodies* bodies, const FountainGeometry& level) : bodies_(bodies), level_(level) {}

  std::string_view name() const override { return "sph_fluid"; }

  // Everything but the construction-time fields, re-derived by initSphFluid's own code.
  void applyLive(const SectionConfig& section, EffectLinks& links) override {
    const SphFluidParams fresh = table().parseLive(section, state.params);
    state.params = fresh;
    deriveSphFluid(fresh, level_, links.gravity, state.world);
  }

  StepOutcome step(const StepContext& ctx) override {
    const PhaseScope phase(ctx.profiler, engine::Phase::fluid);
    // Staggered two-way coupling: the crates as they are after this physics step push the water;
    // the water's push on them acts during the next physics step.
    BodyFluidCoupling* coupling = state.coupling.get();
    if (coupling) collidersFromBodies(*coupling, *bodies_->physics, bodies_->crates, state.world);
    StepOutcome outcome;
    const bool was_running = state.error.empty();
    // This step's explosions push the water before it steps, so the step's CFL bound sees the new
    // speeds (fluid/sph/blast.hpp). The push is capped at the fluid's own speed cap.
    for (const fluid::Blast& blast : ctx.links.blasts) {
      const float cap = state.world.params.max_speed > 0.0f ? state.world.params.max_speed : 30.0f;
      fluid::SphBlastStats blast_stats;
      const fluid::SphStatus pushed = fluid::applyBlast(state.world, blast, cap, &blast_stats);
      if (!pushed.ok() && outcome.failure.empty()) outcome.failure = "sph_fluid: blast refused: " + pushed.error;
      state.blasted_particles += blast_stats.particles;
    }
    step_seconds_ = ctx.step_seconds;
    if (!stepSphFluid(state, ctx.step_seconds) && was_running)
      outcome.failure = "sph_fluid: " + state.error + " (the fluid stops stepping)";
    if (coupling) coupling_error_ = forcesToBodies(*coupling, state.world, *bodies_->physics);
    if (ctx.profiler && sphFluidWarns(state, state.last_totals)) engine::flagFrame(*ctx.profiler);
    return outcome;
  }

  // The solver's own health counters for the last game step (fluid::SphStepStats): red lines
  // are the ones that flag the frame-time plot (sphFluidWarns).
  void drawStatus() const override {
    const fluid::SphStepTotals& t = state.last_totals;
    const fluid::SphStepTotals& run = state.run_totals;
    const ImVec4 red(1.0f, 0.35f, 0.35f, 1.0f), plain = ImGui::GetStyleColorVec4(ImGuiCol_Text);
    const auto ull = [](std::size_t v) { return static_cast<unsigned long long>(v); };
    // Each counter's line explains itself when hovered: what it counts and why it matters.
    const auto explain = [](const char* why) {
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", why);
    };
    ImGui::Text("sph fluid: %zu particles, %llu sub-steps this step", state.world.particles.size(), ull(t.steps));
    explain("Sub-steps: the solver's CFL-limited steps inside one 1/60 s game step. More sub-steps\n"
            "cost more time; fast water (a blast, the jet) needs them.");
    const WaterWhereabouts where = waterWhereabouts(state, level_);
    ImGui::Text("  water: pool %zu (level %.0f cm)  jet and air %zu (spray %zu)  ground %zu  pump %zu", where.pool,
                100.0 * where.pool_level, where.jet_and_air, where.spray, where.ground, where.pump);
    explain("Where the constant number of particles is: in the basin's pool, in the jet and the air\n"
            "(spray: drops flying ballistic, outside the SPH solve), on the ground running to the\n"
            "gutter, and inside the pump's pipe on their way back to the nozzle.");
    ImGui::Text("  density error: mean %.3f %%  p99 %.2f %%  max %.2f %%", 100.0 * t.meanDensityError(),
                100.0 * t.p99_density_error, 100.0 * t.max_density_error);
    explain("How far the particles' density is above the rest density after the pressure solve:\n"
            "the fluid's compression. Water should stay within a few per cent.");
    const float deep = sphDeepPush(state);
    ImGui::TextColored(t.max_push_depth > deep ? red : plain,
                       "  pushed out of colliders: %llu (deepest %.1f mm; warns beyond %.1f mm)  run %llu",
                       ull(t.pushed_out), 1000.0 * t.max_push_depth, 1000.0 * deep, ull(run.pushed_out));
    explain("Particles found inside a depth-map collider and moved back to its surface (Kolb & Latta\n"
            "2004). Shallow ones are ordinary contact; a deep one means the water moved faster than\n"
            "the collision could follow, and it warns the frame (red).");
    ImGui::TextColored(t.speed_clamps > 0 ? red : plain, "  speed clamps: %llu  run %llu", ull(t.speed_clamps),
                       ull(run.speed_clamps));
    explain("Particles whose speed was cut to the solver's limit: energy the simulation removed by\n"
            "force rather than by physics. Any clamp warns the frame (red).");
    ImGui::TextColored(t.dt_min_clamps > 0 ? red : plain, "  dt held at min_time_step: %llu  run %llu",
                       ull(t.dt_min_clamps), ull(run.dt_min_clamps));
    explain("Sub-steps where the CFL condition asked for a step below min_time_step and was refused:\n"
            "the solve then runs with a step too long for its fastest particle. Warns the frame (red).");
    ImGui::Text("  dt cut to land on the step's end: %llu  run %llu", ull(t.dt_request_cuts), ull(run.dt_request_cuts));
    explain("Sub-steps shortened so the last one ends exactly on the game step: harmless bookkeeping.");
    ImGui::TextColored(t.nonfinite > 0 ? red : plain, "  NaN/inf particles: %llu  run %llu", ull(t.nonfinite),
                       ull(run.nonfinite));
    explain("Particles with a non-finite position or velocity: the run stops trusting the state.\n"
            "Should always be 0; any warns the frame (red).");
  }

  // The particles in id order (the store is re-sorted by grid cell each step, so the hash says
  // "same particles in the same states" whatever the storage order), the solver's clocks, the
  // pump's water (the ids it will give back, in order, and when), the colliders and their forces.
  bool hashState(Fnv1a64& h, StateHashScratch& scratch) const override {
    const fluid::SphWorld& w = state.world;
    const fluid::ParticleStore& p = w.particles;
    scratch.order.resize(p.size());
    std::iota(scratch.order.begin(), scratch.order.end(), 0u);
    std::sort(scratch.order.begin(), scratch.order.end(),
              [&p](std::uint32_t a, std::uint32_t b) { return p.id[a] < p.id[b]; });
    h.add(static_cast<std::uint64_t>(p.size()));
    for (std::uint32_t i : scratch.order) {
      h.add(p.id[i]);
      hashVec3(h, p.position[i]);
      hashVec3(h, p.velocity[i]);
      h.add(i < p.density.size() ? p.density[i] : 0.0f);
      h.add(i < p.pressure.size() ? p.pressure[i] : 0.0f);
    }
    h.add(w.time);
    h.add(w.step_count);
    h.add(w.next_id);
    h.add(w.last_dt);
    for (const fluid::SphEmitter& e : w.emitters) h.add(e.accumulator);
    if (w.pump.feeds_emitters || w.pump.size() > 0) {
      h.add(static_cast<std::uint64_t>(w.pump.size()));
      for (std::size_t k = w.pump.head; k < w.pump.held.size(); ++k) {
        h.add(w.pump.held[k].id);
        h.add(w.pump.held[k].ready_time);
      }
    }
    for (const fluid::SphCollider& c : w.colliders) {
      hashQuat(h, c.pose.rotation);
      hashVec3(h, c.pose.translation);
      hashVec3(h, c.pose.linear_velocity);
      hashVec3(h, c.pose.angular_velocity);
      hashVec3(h, c.force);
      hashVec3(h, c.torque);
    }
    return true;
  }

  // All the water (the store and the pump), where it is, and the solver's health over the frame's
  // one game step (fluid::SphStepTotals of its sub-steps).
  void reportColumns(FrameColumns& row) const override {
    const WaterWhereabouts where = waterWhereabouts(state, level_);
    row.set("particles", static_cast<double>(state.world.particles.size() + where.pump));
    row.set("water_pool", static_cast<double>(where.pool));
    row.set("water_air", static_cast<double>(where.jet_and_air));
    row.set("water_ground", static_cast<double>(where.ground));
    row.set("water_pump", static_cast<double>(where.pump));
    row.set("water_spray", static_cast<double>(where.spray));
    const fluid::SphStepTotals& t = state.last_totals;
    row.set("sph_steps", static_cast<double>(t.steps));
    row.set("sph_fast", static_cast<double>(fastParticles()));
    row.set("sph_iterations", static_cast<double>(t.solver_iterations));
    row.set("density_err_mean", t.meanDensityError());
    row.set("density_err_p99", t.p99_density_error);
    row.set("density_err_max", t.max_density_error);
    row.set("pushed_out", static_cast<double>(t.pushed_out));
    row.set("push_depth_mm", 1000.0 * t.max_push_depth);
    row.set("speed_clamps", static_cast<double>(t.speed_clamps));
    row.set("dt_min_clamps", static_cast<double>(t.dt_min_clamps));
    row.set("dt_request_cuts", static_cast<double>(t.dt_request_cuts));
    row.set("nonfinite", static_cast<double>(t.nonfinite));
    row.set("warned", sphFluidWarns(state, t) ? 1.0 : 0.0);
  }

  // The particles against every collider the solver knows (the fountain and the coupled crates, at
  // the poses the solver ended the step with). The solver ends every step with each centre on or
  // outside every surface (Kolb et al. 2004 §3.3.2 push-out) except where a moving collider (a
  // crate) overlaps another (the fountain, or a crate a blast pressed into it): no position is
  // outside both and the solver leaves a particle between them inside one (still colliders win,
  // else the last resolved), so inside a crate only counts where its way out is free
  // (worstFreePenetration).
  void soakCheck(SoakProbe& probe) const override {
    const fluid::SphWorld& sph = state.world;
    const float radius = sph.params.particle_radius;
    probe.count("sph", sph.particles.size());
    float fastest = 0.0f;
    for (const glm::vec3& v : sph.particles.velocity) fastest = std::max(fastest, glm::dot(v, v));
    probe.particleSpeed(std::sqrt(fastest));
    std::size_t squeezed_now = 0;
    for (std::size_t c = 0; c < sph.colliders.size(); ++c) {
      const fluid::SphCollider& collider = sph.colliders[c];
      const bool moves = fluid::sphColliderMoves(collider);
      std::size_t squeezed = 0;
      Penetration p;
      if (moves) {
        probe.blockers.clear();
        for (std::size_t o = 0; o < sph.colliders.size(); ++o)
          if (o != c) probe.blockers.push_back({sph.colliders[o].shape.get(), sph.colliders[o].pose});
        p = worstFreePenetration(sph.particles.position, *collider.shape, collider.pose, probe.blockers, radius,
                                 probe.scratch, squeezed);
      } else {
        p = worstPenetration(sph.particles.position, *collider.shape, collider.pose, radius, 0.0f, probe.scratch);
      }
      squeezed_now += squeezed;
      if (p.ratio > probe.particle_tolerance && probe.failure.empty()) {
        const std::string what = "sph particle id " + std::to_string(sph.particles.id[p.index]) + " (SPH collider " +
                                 std::to_string(c) + (moves ? ", moving)" : ", still)");
        probe.fail(describePenetration(what, p, probe.particle_tolerance) + collidersNear(sph, p.position, probe.scratch));
      }
      probe.penetration("sph", p, probe.particle_tolerance, {});
    }
    probe.squeezed_frames += squeezed_now > 0 ? 1u : 0u;
    probe.squeezed_max = std::max(probe.squeezed_max, squeezed_now);
    // The water circulates through the pump (issue 33): over a long run the pool holds its level.
    if (sph.pump.feeds_emitters) probe.gauge("pool level", waterWhereabouts(state, level_).pool_level, "m");
  }

  std::string findNonFinite() const override {
    std::string bad = findNonFiniteSph(state);
    return bad.empty() ? coupling_error_ : bad;
  }

 private:
  // The SPH particles (spray left out: it flies outside the solve) faster than the speed at which
  // one CFL-bound sub-step spans the whole game step, cfl d / step: each of them alone makes the
  // solver take more than one sub-step per frame.
  std::size_t fastParticles() const {
    const fluid::SphWorld& w = state.world;
    if (!(step_seconds_ > 0.0)) return 0;
    const double one_step = w.params.cfl * fluid::sphSpacing(w.params) / step_seconds_;
    const std::size_t n = std::min(w.particles.sphCount(), w.particles.velocity.size());
    std::size_t fast = 0;
    for (std::size_t i = 0; i < n; ++i)
      fast += static_cast<double>(glm::dot(w.particles.velocity[i], w.particles.velocity[i])) > one_step * one_step;
    return fast;
  }

  RigidBodies* bodies_;
  FountainGeometry level_;
  double step_seconds_ = 0.0;  // the last game step's length (s)
  std::string coupling_error_;  // a non-finite force of the last step's coupling
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& error) {
  auto effect = std::make_unique<SphFluidEffect>(ctx.links.bodies, ctx.links.level);
  const SphFluidParams params = table().parse(section);
  if (!ensureFountainColliders(ctx.content_dir, ctx.links.colliders, error) ||
      !initSphFluid(effect->state, params, ctx.links.level, ctx.links.colliders, ctx.links.gravity, error))
    return nullptr;
  if (ctx.links.bodies != nullptr && params.couple_bodies) {
    // Crates couple while their centre is within a crate's reach of the fluid's grid domain.
    const fluid::SphWorld& sph = effect->state.world;
    const glm::vec3 half(0.5f * ctx.links.bodies->params.crate_size);
    const glm::vec3 reach(glm::length(half));
    effect->state.coupling = std::make_shared<BodyFluidCoupling>();
    initBodyFluidCoupling(*effect->state.coupling, sph, half, sph.params.domain_min - reach,
                          sph.params.domain_max + reach);
  }
  ctx.links.fluid = &effect->state;
  return effect;
}

}  // namespace

bool sphParamsFrom(const SectionConfig& section, SphFluidParams& out, std::string& /*error*/) {
  out = table().parse(section);  // the schema admits only the listed solvers
  return true;
}

namespace {

using enum ColumnFormat;
constexpr ColumnSpec kColumns[] = {
    {"particles", count, "all the water: the SPH store and the pump (constant with a pump)"},
    {"water_pool", count, "of it, in the basin's pool (game::waterWhereabouts)"},
    {"water_air", count, "in the jet and the air"},
    {"water_ground", count, "on the ground, running to the gutter"},
    {"water_pump", count, "inside the pump's pipe"},
    {"water_spray", count, "of the water above, flying ballistic (fluid::SphParams::spray_speed)"},
    {"sph_steps", count, "the solver's sub-steps in the frame's game step"},
    {"sph_fast", count, "SPH particles (not spray) faster than cfl d / game step: each needs a second sub-step"},
    {"sph_iterations", count, "the pressure solver's iterations over the sub-steps (DFSPH: constant density + divergence)"},
    {"density_err_mean", ratio, "mean over the sub-steps of the mean max(0, rho/rho_0 - 1)"},
    {"density_err_p99", ratio, "largest over the sub-steps of the 99th percentile over particles"},
    {"density_err_max", ratio, "largest density error of any particle"},
    {"pushed_out", count, "particles pushed out of colliders"},
    {"push_depth_mm", millimetres, "the deepest of them (mm)"},
    {"speed_clamps", count, "particles whose speed was cut to max_speed"},
    {"dt_min_clamps", count, "sub-steps held at min_time_step against the CFL bound"},
    {"dt_request_cuts", count, "sub-steps shortened to land on the game step's end"},
    {"nonfinite", count, "particles with a NaN/inf position or velocity"},
    {"warned", flag, "1 where the overlay's frame plot draws a red marker (sphFluidWarns)"},
};

}  // namespace

const EffectDesc& sphFluidEffect() {
  static const EffectDesc desc{"sph_fluid",
                               "SPH water (CPU): a filled basin, a pump and its jet, baked fountain colliders",
                               table().specs,
                               {},
                               &build,
                               kColumns};
  return desc;
}

}  // namespace game
