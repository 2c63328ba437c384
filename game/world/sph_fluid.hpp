#pragma once
// The `sph_fluid` effect: the fountain's water as a CPU SPH fluid (fluid/sph: DFSPH by default,
// WCSPH selectable). The basin starts filled with max_particles of water, settled; a pump
// (fluid::SphPump) circulates it as in a real fountain: an intake in the basin floor takes water,
// and the nozzle on the spire gives the same particles back as a jet after the pipe's delay; the
// jet falls into the dish and the basin, colliding with the level's baked depth-map colliders
// (ground, basin and statue from content/colliders, game/world/fountain.hpp). Water thrown out of
// the basin goes down the gutter round it into the pump. The count of water never changes.
// Without the pump (pump = false) the nozzle makes new particles up to max_particles and water
// that leaves the basin is gone. Stepped once per game fixed step (the SPH solver sub-steps
// adaptively inside it, CFL-limited).

#include "fluid/sph/sph.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/body_fluid_coupling.hpp"
#include "game/world/fountain.hpp"

#include <functional>
#include <memory>
#include <string>

namespace game {

struct SphFluidParams {
  fluid::SphSolverKind solver = fluid::SphSolverKind::dfsph;
  std::size_t max_particles = 13000;  // the water (with the pump: all of it, from the start)
  float particle_radius = 0.04f;  // m; spacing 2r
  float jet_speed = 4.5f;         // m/s at the nozzle
  float nozzle_radius = 0.12f;    // m
  float rate = 500.0f;            // particles per second
  float viscosity = 0.02f;        // m^2/s (SphParams::viscosity)
  bool pump = true;         // circulate the water (intake, gutter, nozzle); fixed at construction
  float pump_delay = 0.5f;  // s a particle spends in the pump's pipe
  // Spray (fluid::SphParams::spray_speed): water faster than this with few calm neighbours, or
  // faster than a full step's CFL speed (cfl 2r / max_time_step) whatever its neighbours, flies
  // ballistic outside the SPH solve (slowed by the water where it is in it) until it rejoins, slow,
  // among water; 0 = off. The fountain's scene lowers it under its one-step CFL speed.
  float spray_speed = 6.0f;            // m/s
  float spray_terminal_speed = 8.0f;   // m/s: the drops' air drag (millimetre drops fall at 6-9 m/s)
  // fluid::SphParams::speculative_contacts: at one 1/60 s step water meets the walls at metres per
  // second; without them it goes that deep before the push-out.
  bool speculative_contacts = true;
  // Solver quality knobs (fluid::SphParams): accuracy against time, see docs/sph.md.
  float cfl = 0.4f;
  float max_time_step = 0.005f;   // s
  float density_error = 0.0005f;  // dfsph tolerance (mean predicted compression)
  float force_bound = 0.0025f;    // dfsph force condition; 0 = off
  bool warm_start = true;         // dfsph warm start of the density solve (2017 §4.3)
  float warm_start_share = fluid::SphParams{}.warm_start_share;
  bool couple_bodies = true;      // crates and water push each other (with rigid_bodies; fixed at construction)
};

// Reads a validated "sph_fluid" section through the effect's parameter table
// (game/effects/sph_fluid.cpp; the defaults above are the scene defaults). The schema already
// refused unknown solvers, so it returns true; the signature stays for callers that check.
bool sphParamsFrom(const SectionConfig& section, SphFluidParams& out, std::string& error);

struct SphFluid {
  SphFluidParams params;
  fluid::SphWorld world;
  std::uint64_t steps = 0;         // game steps taken
  std::uint64_t solver_steps = 0;  // adaptive SPH steps taken
  std::uint64_t blasted_particles = 0;  // particle pushes by explosions so far (fluid/sph/blast.hpp)
  std::string error;               // first solver error; the system stops stepping after one
  // The solver's health counters (fluid::SphStepStats) summed over the last stepSphFluid call's
  // sub-steps, and over the whole run: the overlay, the replay CSV and the run summaries read them.
  fluid::SphStepTotals last_totals;
  fluid::SphStepTotals run_totals;
  // Crates <-> water, two-way: only with rigid_bodies listed and couple_bodies on. Shared so a
  // SphFluid stays copyable (the fountain benchmark snapshots one); a copy shares the coupling.
  std::shared_ptr<BodyFluidCoupling> coupling;
};

// Copies the solver knobs that may change while the fluid runs (viscosity, cfl, max_time_step,
// density_error, force_bound, warm_start) into the solver's parameters.
void applySolverKnobs(const SphFluidParams& params, fluid::SphParams& solver);

// Everything that follows from the tunable parameters, the gravity and the level: the solver
// knobs, the speed cap and the WCSPH sound speed (from jet_speed), the nozzle's speed and rate,
// and the pump's intake and gutters (or, without it, the sinks of strays; the top one from the jet's reach). initSphFluid calls it, and
// so does a live edit, so raising jet_speed live moves the cap, the sound speed and the top sink
// exactly as a rebuild would. Fixed-at-construction fields (solver, max_particles,
// particle_radius, nozzle_radius, pump) must be the world's own.
void deriveSphFluid(const SphFluidParams& params, const FountainGeometry& geometry, glm::vec3 gravity,
                    fluid::SphWorld& world);

// Builds the SPH world: parameters, one collider per part of `colliders` (the level's baked
// colliders, shared; ensureFountainColliders), the nozzle emitter at `nozzle`
// (pointing up), the pump and the pool (fillSphPool); reserves every buffer for max_particles.
// False + error (naming the field and value) on invalid parameters.
bool initSphFluid(SphFluid& fluid, const SphFluidParams& params, const FountainGeometry& geometry,
                  const std::shared_ptr<const LevelColliders>& colliders, glm::vec3 gravity, std::string& error);

// Where the water is (the overlay, the replay CSV): in the basin below its wall top (pool), above
// it or over the statue (jet and air: the jet, the dish, spray), outside the basin (ground), and
// in the pump. Their sum is the count of water.
struct WaterWhereabouts {
  std::size_t pool = 0, jet_and_air = 0, ground = 0, pump = 0;
  std::size_t spray = 0;  // of all these, flying ballistic (fluid::SphParams::spray_speed)
  float pool_level = 0.0f;  // m above the basin floor: the pool's volume over the basin's floor area
};
WaterWhereabouts waterWhereabouts(const SphFluid& fluid, const FountainGeometry& geometry);
// The basin's floor area between its wall and the statue's plinth (m^2): pool_level's divisor.
float basinFloorArea(const FountainGeometry& geometry);

// Advances the fluid by exactly `dt` seconds (adaptive SPH sub-steps, each <= params.max_time_step),
// calling `on_step` (when given) with each sub-step's statistics. Returns false and sets
// fluid.error when the solver refuses a step.
bool stepSphFluid(SphFluid& fluid, double dt, const std::function<void(const fluid::SphStepStats&)>& on_step = {});

// The push-out depth (m) beyond which a collision push-out is a warning: one particle radius.
// The boundary pressure (sph.hpp, density-map boundary) holds water about a radius off a wall, so
// the end-of-step collision check normally finds particles only grazing it (a skin deep); a
// centre more than r inside means the whole particle passed the surface within one step: the
// boundary failed to stop it (a blast, a fast crate, a too-long step).
float sphDeepPush(const SphFluid& fluid);
// Whether `totals` (e.g. fluid.last_totals) hold a warning: fluid::sphTotalsWarn at sphDeepPush.
bool sphFluidWarns(const SphFluid& fluid, const fluid::SphStepTotals& totals);

// Empty when every position/velocity/density is finite; otherwise names the first bad value
// (a solver error is not a value: the world records it as a run-time failure).
std::string findNonFiniteSph(const SphFluid& fluid);

}  // namespace game
