#pragma once
// fluid/sph: CPU SPH fluid (no GL, no Bullet). One world = SoA particle store + parameters +
// colliders + emitters + sinks + caller-visible scratch. Everything runs on oneTBB; results are
// bit-identical for any thread count (per-particle work is independent and every floating-point
// reduction uses tbb::parallel_deterministic_reduce with a fixed grain).
//
// Solvers (pick with SphParams::solver):
//  - wcsph: weakly compressible SPH, Becker & Teschner 2007 "Weakly compressible SPH for free
//    surface flows": Tait equation (eq. 7), symmetric pressure force (eq. 6), artificial
//    viscosity (eq. 10-11), time step from the CFL and force conditions (§4, eq. 12-13).
//  - dfsph: Divergence-Free SPH, Bender & Koschier 2015 "Divergence-free smoothed particle
//    hydrodynamics" (and the 2017 TVCG version): constant-density solver (§4.2) and divergence-free
//    solver (§4.1) sharing the stiffness factor alpha_i (eq. 8-9), warm starts (§4.3).
// Boundaries: each collider is a SignedDistanceShape. It acts on the fluid in two ways:
//  - as a continuous boundary in the SPH sums: the collider side of a particle's kernel support
//    is treated as a filled half-space (the density-map idea of Koschier & Bender 2017, "Density
//    maps for improved SPH boundary handling", with the collider locally approximated by its
//    tangent plane); the volume and its gradient enter the density and pressure terms like
//    Akinci et al. 2012 boundary particles;
//  - as a hard constraint after the position update: Kolb et al. 2004 §3.3.2 double check
//    (fluid::resolveCollision), so no particle ends a step inside a collider, except where a moving
//    collider overlaps a still one: there the particle ends outside the still one (sphColliderMoves).
// Two-way coupling: each collider reports the force and torque the fluid exerted on it during the
// last step (pressure from the boundary terms + collision impulses).
//
// Units: SI (m, s, kg). Gravity defaults to -y.

#include "fluid/core/collider.hpp"
#include "fluid/sph/kernels.hpp"
#include "fluid/sph/neighbor_grid.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace fluid {

enum class SphSolverKind { wcsph, dfsph };

// Parses "wcsph" / "dfsph"; returns false for anything else.
bool parseSphSolver(const std::string& name, SphSolverKind& out);
const char* sphSolverName(SphSolverKind kind);

struct SphParams {
  SphSolverKind solver = SphSolverKind::dfsph;
  float particle_radius = 0.025f;         // r (m) > 0. Spacing d = 2r, kernel support H = 4r.
  float rest_density = 1000.0f;           // rho_0 (kg/m^3) > 0
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};  // m/s^2
  float viscosity = 0.01f;  // nu of the Laplacian viscosity (Monaghan 2005 form, as in SPlisHSPlasH "standard"), >= 0
  float xsph = 0.0f;        // XSPH velocity smoothing epsilon in [0, 1] (Monaghan 1989), 0 = off
  float cfl = 0.4f;         // in [0.01, 1]: dt <= cfl * d / v_max; DFSPH also |g| dt^2 <= force_bound cfl d
  // DFSPH force condition |g| dt^2 <= force_bound * cfl * d, in [0, 1]; 0 = off (CFL, viscosity and
  // max_time_step only). The CFL bound does not limit a resting fluid (v = 0), whose step then
  // grows to max_time_step; with the default our column-at-rest test (tests/sph) keeps its top
  // layer still, without it surface particles start to slide (0.3 m/s after 2 s).
  float force_bound = 0.0025f;
  float max_time_step = 0.005f;          // s, upper bound of the adaptive step (requested steps above are clamped)
  float min_time_step = 1e-6f;           // s, lower bound (a step never gets shorter, even if CFL asks)
  float max_speed = 0.0f;                // m/s, velocities are clamped to this after each step; 0 = no clamp
  std::size_t max_particles = 1u << 20;  // particle budget: emitters stop at this count; < 2^28

  // Spray (after Ihmsen et al. 2012, "Unified spray, foam and bubbles for particle-based fluids",
  // §4: a particle with fewer than 6 fluid neighbours is spray, advected with gravity and drag
  // and no pressure). Here an SPH particle faster than spray_speed leaves the solve if it had
  // fewer than spray_neighbours calm neighbours (no faster than spray_speed) in the last step, or
  // whatever its neighbours if it is faster than a full step's CFL speed (cfl d / max_time_step),
  // so the SPH's CFL step follows the bulk of the water, never a few fast particles (the jet, a
  // blast's drops, a splash). Outside the water
  // a drop flies ballistic (gravity, quadratic air drag, the colliders' Kolb 2004 §3.3.2
  // reaction); inside it, it is a submerged drop: buoyant, and slowed by the water's drag
  // (spray_water_drag), whose momentum the water takes. A drop no faster than half spray_speed
  // rejoins once it is among spray_neighbours calm SPH particles, or touches a collider, unless it
  // would crowd the water (spray.cpp, gateCrowdedRejoins): bunched drops rejoin one after the
  // other, not in one step that starts at over twice the rest density. Ids and mass are kept; the
  // spray stays in the store (its last ParticleStore::spray_count entries).
  float spray_speed = 0.0f;  // m/s; 0 = off (every particle stays in the SPH solve)
  int spray_neighbours = 6;  // >= 1
  // Drag coefficient C_d of a submerged drop moving at u relative to the water around it:
  // F = 1/2 rho_0 C_d pi r^2 |u| u on a particle of mass rho_0 (2r)^3, scaled by the water's
  // share phi = min(rho_water / rho_0, 1) at the drop. 2 (a bluff body's) stops a 5 m/s drop
  // within a frame. 0 = none (the drop passes through the water).
  float spray_water_drag = 2.0f;
  // Speed at which the drag balances gravity (drag acceleration |g| |v| v / v_t^2, opposite v);
  // 0 = no drag. A blast tears water into drops of millimetres, whose terminal speed is 6-9 m/s.
  float spray_terminal_speed = 0.0f;

  // WCSPH (Becker & Teschner 2007)
  float sound_speed = 20.0f;          // c_s (m/s); accuracy knob: density error ~ (v_max / c_s)^2
  float tait_exponent = 7.0f;         // gamma of eq. 7
  float artificial_viscosity = 0.0f;  // alpha of eq. 10, >= 0 (added to `viscosity`)

  // DFSPH (Bender & Koschier 2015)
  float max_density_error = 0.0005f;    // eta: stop when the mean predicted compression is below this (0.0005 = 0.05 %)
  float max_divergence_error = 0.001f;  // eta_v: mean (Drho/Dt) dt / rho_0 below this
  // Constant-density solver; the divergence solver does at least 1. The 2017 paper's Algorithm 2
  // does at least 2. With 1, most dambreak_box steps save one iteration (two passes over the
  // pairs) while the mean density error stays within the tolerance: docs/sph.md, dambreak_box
  // rows with and without "min 2 iterations" (scene key min_iterations).
  int min_iterations = 1;
  int max_iterations = 100;  // per solve, >= 1
  bool divergence_solver = true;
  // Warm start (2017 §4.3) of the constant-density solve: it starts from warm_start_share x the
  // previous step's summed stiffness (kappa/rho; scaled down when dt grew), applied only to particles that
  // compress now. Off by default: the solve corrects compression only (rho* > rho_0, §4.2; an
  // expansion is left to gravity, or the free surface would be pulled together), so the share of
  // the last step's push that the particle does not need now is never taken back and stays as
  // velocity. On the resting column (fluiddemo simulate --scene column --seconds 2 --fps 1
  // [--set warm_start=1], 2,000 particles, v_rms over the second second) it raises v_rms from
  // 10.5 to 22.4 mm/s (0.05 x: 18.2, 0.1 x: 19.5), above the 1 % of sqrt(g h) = 14 mm/s that the
  // at-rest test of tests/sph allows, for 5.8 instead of 7.4 iterations per step. The divergence
  // solve is never warm-started: the pushes it repeats are never taken back, which adds energy to
  // a jet hitting a collider.
  bool warm_start = false;
  float warm_start_share = 0.2f;  // of the last step's stiffness, in [0, 1] (warm_start on)

  // Neighbour grid extent (the grid clamps stray particles into its border cells).
  glm::vec3 domain_min{-1e30f};
  glm::vec3 domain_max{1e30f};
  float collision_skin = 0.0f;  // m pushed beyond a collider surface; 0 = 0.01 r
  // Speculative contacts (as rigid-body engines use them: a contact is applied before the bodies
  // touch, only to the part of the approach that would close the gap within the step). At a long
  // step water meets a wall at metres per second and travels further than its radius in one step,
  // so the end-of-step push-out (Kolb et al. 2004 §3.3.2) fixes it only after it went that deep.
  // With this on, before the push-out, a particle loses the part of its approach to each collider
  // (along the step-start sample's normal, relative to the collider's velocity there) that would
  // bring it nearer than contact_standoff x particle_radius; the collider takes the reaction.
  bool speculative_contacts = false;
  float contact_standoff = 0.5f;  // x particle_radius, in [0, 4]
};

// SoA particle store. Index order may change at every step (particles are re-sorted by grid cell
// for locality); `id` is stable and unique for the lifetime of the world.
struct ParticleStore {
  std::vector<glm::vec3> position;  // m
  std::vector<glm::vec3> velocity;  // m/s
  std::vector<float> density;       // kg/m^3, computed at the start of each step
  std::vector<float>
      pressure;  // Pa. WCSPH: Tait pressure; DFSPH: the effective pressure rho_i^2 * sum of kappa_i/rho_i
                 // over the step's solver iterations (a per-step impulse: average it over steps)
  std::vector<std::uint32_t> id;
  // Spray (SphParams::spray_speed): after a step the last spray_count particles fly ballistic,
  // outside the SPH solve; the first size() - spray_count are the SPH water.
  std::size_t spray_count = 0;

  std::size_t size() const { return position.size(); }
  std::size_t sphCount() const { return position.size() - std::min(spray_count, position.size()); }
};

struct SphCollider {
  std::shared_ptr<const SignedDistanceShape> shape;  // shared, read-only, must be non-null
  ColliderPose pose;                                 // world placement at the start of the next step
  CollisionMaterial material;
  bool boundary_pressure = true;  // also act as SPH boundary (density/pressure), not only as collision
  // The coupling force (below) reads the water's pressure at the collider's surface: each
  // particle's pressure extrapolated hydrostatically to its mirror point behind the surface
  // (Adami, Hu & Adams 2012, "A generalized wall boundary condition for SPH", eq. 27, without the
  // wall's acceleration) instead of mirrored (p_b = p_i), so that the pair's mean is the pressure
  // at the surface, not at the particle about r deeper. A floating body then sinks to its
  // Archimedes draft instead of riding about r above it. The water's own boundary term keeps the
  // mirror (boundary.hpp, addCouplingTerm, says why).
  bool surface_pressure_force = false;
  bool integrate_pose = true;  // advance pose by its velocities during each step
  // Films (a sub-particle closure for a coupled body): water squeezed between this collider and
  // one of the world's first `film_partner_count` colliders (the scene's own, in the game), where
  // the two surfaces face each other (facesAcrossAFilm) and the particle is nearer the two
  // together than `film_gap` (m; 0 = off), is a film no particle resolves: a layer of particles
  // fits only where the gap is at least a spacing. Such a particle's boundary-pressure term and
  // collision reactions (of the end-of-step passes and the speculative contacts; a spray drop's
  // collisions are not films and keep theirs) are left out of force/torque below, while the water
  // itself still feels the wall; the caller gives the body the film's pressure instead
  // (game/world/body_fluid_coupling's filmForce), so the film is counted once.
  float film_gap = 0.0f;
  std::size_t film_partner_count = 0;
  // The shape's signed distance is 1-Lipschitz (|d(a) - d(b)| <= |a - b|: an exact SDF, or min/max
  // of exact ones as in CSG). Only then, and only while the collider does not move during a step
  // (integrate_pose off or zero velocities), the end-of-step collision check skips the query of a
  // particle that moved less than its start distance (minus a margin): its whole step stayed
  // outside, so it neither reached the surface nor tunnelled through a thin part. Without the
  // flag the tunnelling test also runs for such particles and can fire where the outward normal
  // flips across a medial axis without any crossing (a concave corner of a CSG shape).
  bool lipschitz_distance = false;
  // Two-way coupling outputs: force (N) and torque (N m, about pose.translation) the fluid
  // exerted on this collider, averaged over the last stepSph/advanceSph call.
  glm::vec3 force{0.0f};
  glm::vec3 torque{0.0f};
};

// Two surfaces face each other across a film when their outward normals are within 60 degrees of
// opposite: a box's bottom over a floor, or its lower face where it tilts onto an edge; a box's
// side stands beside the floor, not across a film from it.
inline bool facesAcrossAFilm(glm::vec3 normal, glm::vec3 other_normal) {
  return glm::dot(normal, other_normal) < -0.5f;
}

// Whether the collider moves during a step (integrate_pose with a non-zero velocity). The
// end-of-step collision passes project particles out of moving colliders first and out of still
// ones last, so where a moving collider overlaps a still one (no position outside both) the
// particle ends outside the still one: still colliders win (collisions.cpp, resolveCollisions).
inline bool sphColliderMoves(const SphCollider& c) {
  return c.integrate_pose && (glm::dot(c.pose.linear_velocity, c.pose.linear_velocity) > 0.0f ||
                              glm::dot(c.pose.angular_velocity, c.pose.angular_velocity) > 0.0f);
}

// A nozzle: emits discs of particles (square lattice of spacing d inside `radius`) along
// `direction` at `speed`, `rate` particles per second, while start_time <= t < end_time.
// A lattice point is skipped (not emitted) where a collider is nearer than the particle radius, an
// existing particle nearer than 0.99 d, or where the new particle would start above the rest density
// or push an existing particle within its support above it (SPH density with the boundary volume, at
// the positions when the layer is placed; 0.1 % slack for rounding): a blocked nozzle emits less
// instead of packing particles into fluid or solid that is already there. A free jet emits every
// lattice point of every layer.
struct SphEmitter {
  glm::vec3 position{0.0f};
  glm::vec3 direction{0.0f, 1.0f, 0.0f};  // normalised when used; zero means +y
  float speed = 2.0f;                     // m/s > 0
  float radius = 0.05f;                   // m >= 0 (0 = one particle per layer)
  float rate =
      1000.0f;  // particles per second >= 0; clamped to speed * (particles per layer) / d so layers never overlap
  float start_time = 0.0f;
  float end_time = 1e30f;
  // Half-angle (radians, in [0, pi/2]) of the cone each particle's direction is scattered in, by
  // a hash of its id (the same for any thread count): a jet that breaks into drops fans out
  // instead of falling back on its own nozzle as one column. 0 = every particle along direction.
  float spread = 0.0f;
  double accumulator = 0.0;  // internal: seconds since the last layer
};

// What a sink does with the particles inside its box at the start of a step.
enum class SphSinkKind {
  remove,  // a drain: they leave the world
  pump,    // a gutter: they go into the world's pump (SphPump), however full it is
  intake,  // the pump's intake: into the pump while it holds less than its capacity
};

// Drain, gutter or intake: the axis-aligned box [min, max], applied at the start of a step. A
// particle inside boxes of several kinds goes to the pump before it is removed.
struct SphSink {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
  SphSinkKind kind = SphSinkKind::remove;
};

// A fountain's pump: the water circulates instead of being made at the nozzle and destroyed in
// the floor. Intakes and gutters (SphSink) take particles out of the store into `held` (each keeps
// its id) and the emitters give them back after `delay` seconds (the pipe), oldest first; while
// `feeds_emitters` is set an emitter creates no particle of its own, so the count of water (the
// store plus the pump) never changes. An intake takes particles while the pump holds fewer than
// `capacity` (what the nozzle returns in `delay` plus a layer, say): it draws what the jet gives
// back, not the pool.
struct SphPumped {
  std::uint32_t id = 0;
  double ready_time = 0.0;  // s: world time from which the nozzle may give it back
};
struct SphPump {
  bool feeds_emitters = false;
  double delay = 0.5;         // s in the pipe
  std::size_t capacity = 0;   // intakes stop taking at this many held
  std::vector<SphPumped> held;  // oldest at `head`; entries before it were given back
  std::size_t head = 0;
  std::size_t size() const { return held.size() - head; }
};

struct SphStepStats {
  float dt = 0.0f;             // s
  int density_iterations = 0;  // DFSPH constant-density iterations (0 for WCSPH)
  int divergence_iterations = 0;
  float avg_density_error = 0.0f;  // mean over particles of max(0, rho/rho_0 - 1), state at step start
  float max_density_error = 0.0f;  // max over particles of the same
  // 99th percentile over particles of the same: the max is one particle (an impact at a wall
  // within one step, docs/sph.md "Largest compression"), the p99 the water as a whole.
  float p99_density_error = 0.0f;
  float kinetic_energy = 0.0f;     // J, after the step
  float max_acceleration = 0.0f;   // m/s^2, largest |a| used by the time-step bound
  float step_ms = 0.0f;            // wall time
  float neighbor_ms = 0.0f;        // wall time of grid + sort + neighbour lists
  std::size_t particles = 0;       // after the step
  std::size_t emitted = 0;
  std::size_t removed = 0;
  std::size_t pumped = 0;  // particles the intakes and gutters took into the pump this step
  std::size_t spray = 0;         // particles flying ballistic after the step (SphParams::spray_speed)
  std::size_t spray_left = 0;    // particles that left the SPH solve as spray at the step's start
  std::size_t spray_joined = 0;  // spray that rejoined the SPH solve at the step's start
  // Slow drops among water kept out of it at the step's end because they would have crowded it
  // (SphParams::spray_speed): they try again the next step.
  std::size_t rejoins_crowded = 0;
  std::size_t collisions = 0;          // particle-collider reactions (Kolb 2004 §3.3.2) in this step, every pass
  bool dt_limited_by_request = false;  // the caller's max_dt was the binding bound
  // Health counters (they observe the step, never change it). The overlay, the replay CSV and
  // the run summaries show them per frame (docs/replay.md).
  // Particles the end-of-step collision passes moved (each counted once however many passes or
  // colliders pushed it): ended inside a collider, or tunnelled through a thin part, although the
  // boundary pressure should have held them outside.
  std::size_t pushed_out = 0;
  float max_push_depth = 0.0f;   // m, deepest end-of-step penetration among them (0 when none)
  std::size_t speed_clamps = 0;  // particles whose speed was cut to params.max_speed
  // The CFL/force/viscosity bounds asked for a step shorter than params.min_time_step; dt was held
  // at it (the fluid moves further per step than the CFL number allows).
  bool dt_held_at_min = false;
  // Particles with a non-finite position, velocity or density: at the start of a step (the step
  // is refused, stepSph still writes the stats with this count and dt = 0) or after it.
  std::size_t nonfinite = 0;
};

// A run of steps summed for display (the overlay, the replay's frame CSV, run summaries).
struct SphStepTotals {
  std::size_t steps = 0;
  double density_error_sum = 0.0;  // sum over steps of avg_density_error (mean = sum / steps)
  float max_density_error = 0.0f;  // max over steps of max_density_error
  float p99_density_error = 0.0f;  // max over steps of p99_density_error (the worst step's 99th percentile)
  std::size_t pushed_out = 0;
  float max_push_depth = 0.0f;  // m
  std::size_t speed_clamps = 0;
  std::size_t dt_min_clamps = 0;    // steps with dt_held_at_min
  std::size_t dt_request_cuts = 0;  // steps with dt_limited_by_request (informational: landing on a frame's end)
  std::size_t nonfinite = 0;
  // DFSPH's solver iterations (constant-density plus divergence-free, Bender & Koschier 2015 §4)
  // summed over the steps: what a step costs beyond its fixed passes (0 for WCSPH).
  std::size_t solver_iterations = 0;
  float meanDensityError() const { return steps > 0 ? static_cast<float>(density_error_sum / steps) : 0.0f; }
};
void addStepTotals(SphStepTotals& totals, const SphStepStats& step);
void addStepTotals(SphStepTotals& totals, const SphStepTotals& more);
// Whether the totals hold a warning: any speed or min-dt clamp, any non-finite value, or a
// particle pushed out from deeper than `deep_push` metres inside a collider (the boundary
// pressure keeps resting and flowing water about one particle radius off a wall, so a particle
// that ends a step that deep inside got there through a failure of the boundary, not a graze).
bool sphTotalsWarn(const SphStepTotals& totals, float deep_push);

// Empty error == success.
struct SphStatus {
  std::string error;
  bool ok() const { return error.empty(); }
};

// Caller-visible scratch: every per-step buffer, reused (vectors only grow) so that a warmed-up
// world does not allocate in stepSph.
struct SphScratch {
  CubicSplineKernel kernel;
  float particle_mass = 0.0f;      // m = rho_0 / (lattice sum of W at spacing d): a resting lattice has rho = rho_0
  std::vector<float> wall_volume;  // tabulated boundary volume V(s), s in [-H, H]
  std::vector<float> wall_area;    // tabulated A(s) = -dV/ds
  float wall_shift = 0.0f;         // calibration offset of s (see ensureInit)
  float wall_beta = 1.0f;          // calibration scale of V and A (see ensureInit)
  float wall_neighbours = 0.0f;    // lattice neighbours per unit boundary volume
  // Exact boundary volume of solid boxes (boundary.cpp, boxBoundaryVolume): the kernel's integral
  // over the octant z > a and its slope along a.x, tabulated on (kOctantCells + 1)^3 nodes over
  // a in [-H, H]^3; built when a solid box collider first appears (empty otherwise).
  std::vector<float> octant_volume, octant_slope;
  std::vector<glm::vec4> collider_box;  // per collider, this step: xyz calibrated half extents, w = 1 for a solid box
  NeighborGrid grid;
  // The step's exact lists: the neighbours of i are neighbors.indices[offsets[i] .. offsets[i] +
  // counts[i]) (DFSPH: a fresh search, so that is up to offsets[i + 1]; WCSPH: the front of i's
  // Verlet range, filtered by the density pass).
  NeighborLists neighbors;
  // WCSPH Verlet list (radius H + skin) and the positions it was built at (neighbor_step.cpp).
  NeighborLists verlet;
  std::vector<glm::vec3> verlet_position;
  float verlet_radius = 0.0f;
  bool verlet_valid = false;
  // Per neighbour pair: m_j grad W_ij, one array per component (SoA: the solver's pair loops read
  // them eight pairs at a time). WCSPH: pair k as in neighbors.indices. DFSPH: i's pairs from
  // pair_start[i], zero-padded to a multiple of 8 and read through 32-byte aligned views
  // (pair_loops.hpp), so the arrays are a few entries longer than the pairs.
  std::vector<float> grad_x, grad_y, grad_z;
  std::vector<std::uint32_t> pair_start;  // DFSPH: n + 1 entries, multiples of 8 (pair_loops.hpp PairBlocks)
  // per particle
  std::vector<glm::vec3> vec_a, vec_b, boundary_gradient, old_position, accel;
  // Step-start positions and the velocities padded to 16 bytes, so the eight-lane pair loops load
  // a neighbour's x, y, z with one 16-byte load (DFSPH density, viscosity and solver passes);
  // vel4[i].w carries the viscosity coefficient 10 nu / rho_i from the density pass to the
  // viscosity pass (the density pass reads pos4 of the neighbours, so it cannot write there).
  std::vector<glm::vec4> vel4, pos4;
  std::vector<glm::vec4> kappa4;           // DFSPH: .x = kappa_i / rho_i of the current iteration (16-byte records)
  std::vector<std::uint32_t> pair_offset;  // DFSPH: per neighbour pair (as grad_x), 16 j (byte offset of j's record)
  std::vector<float> factor, kappa, kappa_v, warm_kappa, density_adv, kappa_scale, boundary_volume, boundary_flux,
      boundary_product, float_tmp;
  std::vector<float> density_error;  // per particle max(0, rho/rho_0 - 1) at the step start (the p99's selection)
  std::vector<std::uint32_t> u32_tmp;
  std::vector<std::uint32_t> sorted_keys;     // the grid's cell keys in re-sorted order (swapped into the grid)
  std::vector<std::uint32_t> keep;            // per particle: 0 when inside a sink at the start of the step
  // Per particle, from the end of the last step (SphParams::spray_speed): kJoinNeighbours for a
  // drop that rejoins the water at the next step's start, kUnknownNeighbours for SPH particles and
  // those added since, a count below spray_neighbours for a drop that stays spray. The spray
  // transitions read it.
  static constexpr std::uint32_t kUnknownNeighbours = ~0u, kJoinNeighbours = ~0u - 1u;
  std::vector<std::uint32_t> last_neighbours;
  std::vector<float> spray_water_density;     // advanceSpray: per drop, the SPH water's density at its end (kg/m^3)
  std::vector<glm::vec3> rejoined;            // advanceSpray: the drops let back in this step, in order
  std::vector<float> spray_water_share;       // advanceSpray: per drop, the water's share phi around it
  std::vector<std::uint32_t> spray_near;      // advanceSpray: one drop's SPH neighbours
  std::vector<float> spray_near_weight;       // advanceSpray: their kernel weights
  std::vector<std::uint32_t> spray_order;     // the spray transitions' permutation (new index -> old)
  std::vector<glm::vec3> emitter_crowd;       // applyEmitters: the particles near the layer being placed
  std::vector<float> emitter_crowd_density;   // applyEmitters: their SPH density (kg/m^3) with the layer so far
  std::vector<std::uint8_t> collider_moving;  // per collider: 1 when its pose has a velocity this step
  std::vector<std::vector<ColliderSample>> start_samples;  // per collider, at the step-start positions
  // Per collider with boundary pressure (empty for the others): collider c's share of grad V at
  // each particle's step-start position (sampleBoundary), which the coupling force reuses.
  std::vector<std::vector<glm::vec3>> boundary_share;
  std::vector<std::vector<ColliderSample>> end_samples;  // per collider, at the end-of-step positions
  // Collision passes: bit c set while particle i's end_samples[c][i] is out of date (it moved after
  // collider c's last query).
  std::vector<std::uint32_t> collide_stale;
  std::vector<std::uint32_t> collide_order;  // collision passes: moving colliders first, still ones last
  // The end-of-step samples carried to the next step's boundary sampling (sampleBoundary): the last
  // collision pass queried each collider at the particles' final positions, which are the next
  // step's start positions. A sample is a pure function of the shape, its pose and the point, so
  // it is reused where all three are bit-for-bit the same (the results are bit-identical).
  struct SampleCarry {
    static constexpr std::uint32_t kNone = ~0u;
    // Per particle, indexed as at the end of the last step: the position end_samples were taken at
    // (collide_stale says which colliders' samples are current there).
    std::vector<glm::vec3> position;
    std::size_t count = 0;  // particles at the end of the last step (0: nothing carried)
    // This step: particle -> its index at the end of the last step (kNone: none, e.g. emitted);
    // the sinks' compaction and the re-sort keep it in step with the store.
    std::vector<std::uint32_t> index, index_tmp;
    // Per collider: the shape queried (held, so a new shape never takes its address), the pose of
    // the query, and whether end_samples[c] holds real queries where collide_stale bit c is clear.
    std::vector<std::shared_ptr<const SignedDistanceShape>> shape;
    std::vector<ColliderPose> pose;
    std::vector<std::uint8_t> usable;
  } carry;
  std::vector<glm::vec4> push_plane;  // per particle: the moving face that pushed it this step (xyz normal, w offset)
  std::vector<std::uint8_t> pushed;   // per particle: 1 once a collision pass moved it this step (stats.pushed_out)
  std::vector<glm::vec3> reduce_force, reduce_torque;
  bool initialised = false;
  // Testing aid: run the pair loops' portable code even where the CPU has AVX2. Both give
  // bit-identical results (the same IEEE operations in the same order); tests/sph compares them.
  bool portable_pair_loops = false;
};

struct SphWorld {
  SphParams params;
  ParticleStore particles;
  std::vector<SphCollider> colliders;
  std::vector<SphEmitter> emitters;
  std::vector<SphSink> sinks;
  SphPump pump;
  double time = 0.0;  // s
  std::uint64_t step_count = 0;
  std::uint32_t next_id = 0;
  float last_dt = 0.0f;
  SphScratch scratch;
};

// Derived quantities of a world's parameters.
inline float sphSpacing(const SphParams& p) { return 2.0f * p.particle_radius; }
inline float sphSupport(const SphParams& p) { return 4.0f * p.particle_radius; }
float sphParticleMass(const SphParams& params);

// Appends a particle (id = world.next_id++). Returns false (and adds nothing) over budget.
bool addSphParticle(SphWorld& world, glm::vec3 position, glm::vec3 velocity = glm::vec3(0.0f));
// Appends a particle with a given id (the pump's return: its id is one the world made, so the
// budget does not apply and next_id stays). The caller keeps ids unique.
bool addSphParticleWithId(SphWorld& world, std::uint32_t id, glm::vec3 position, glm::vec3 velocity);
// Fills the box [lo, hi] with a cubic lattice of spacing d starting at lo + r; returns the count added.
std::size_t addSphBlock(SphWorld& world, glm::vec3 lo, glm::vec3 hi, glm::vec3 velocity = glm::vec3(0.0f));
// Fills a basin from the bottom up: the cubic lattice of spacing d over the box [lo, hi] (first
// point lo + r), layer by layer in y, keeping the points where `inside` is true and no collider
// is nearer than the particle radius (each collider's own distance query), until `count`
// particles are added. Returns the count added. At rest this lattice is at the solvers' rest density (sphParticleMass) and a radius
// off every wall (the boundary's calibration), so it needs little settling.
template <typename Inside>
std::size_t addSphPool(SphWorld& world, glm::vec3 lo, glm::vec3 hi, std::size_t count, Inside&& inside);
// Whether a particle at `p` would be within `radius` of a collider (queried at the colliders'
// current poses). Out-of-reach answers count as far.
bool sphNearCollider(const SphWorld& world, glm::vec3 p, float radius);

// Reserves every per-particle buffer for `capacity` particles (call once to avoid growth later).
void reserveSph(SphWorld& world, std::size_t capacity);

// Checks parameters (finite, in range); the message names the field and value.
SphStatus validateSphParams(const SphParams& params);

// One adaptive step of at most max_dt seconds (max_dt <= 0: params.max_time_step). Order:
// validate input (a non-finite position/velocity is reported with particle id/index and step,
// and the world is left untouched; stats->nonfinite counts them), sinks, emitters, neighbour grid + re-sort, solver,
// collisions.
SphStatus stepSph(SphWorld& world, float max_dt, SphStepStats* stats = nullptr);

// One step of an even split of `remaining` seconds (> 0): with t the step stepSph would take
// (CFL, force, viscosity bounds, max_time_step), the step is remaining / ceil(remaining / t), so
// steps that land on a caller's time are equal and none is a sliver (see the solver).
SphStatus stepSphWithin(SphWorld& world, double remaining, SphStepStats* stats = nullptr);

// Steps until `duration` seconds have passed, with stepSphWithin (the remaining time is spread
// evenly over the last steps; none is cut to land exactly). Collider force/torque become the time
// average over the substeps. `per_step` (optional) is called with the stats of every step;
// max_steps bounds the work (error if exceeded). A step refused for non-finite input is passed
// to `per_step` too (dt = 0, nonfinite > 0) before the error returns.
template <typename F>
SphStatus advanceSph(SphWorld& world, double duration, F&& per_step, std::size_t max_steps = 1000000);

// Total kinetic energy (J) and the potential energy m g.h relative to height 0 along -gravity (J).
double sphKineticEnergy(const SphWorld& world);
double sphPotentialEnergy(const SphWorld& world);
// Mean and max over particles of max(0, rho/rho_0 - 1) for the densities stored in the world.
void sphDensityError(const SphWorld& world, float& mean, float& max);
// Volume estimate sum_i m / max(rho_i, rho_0): shrinks when the fluid is compressed (m^3).
double sphCompressedVolume(const SphWorld& world);

// Steps with the solver's own step (stepSph with no request) until world.time >= until; the last
// step may end past it (none is cut). The steps, and the state after each, do not depend on the
// times asked for, so a caller that samples at its own rate (fluiddemo simulate --fps) gets the
// same physics at every rate; sphPositionsAt gives the positions at the asked time. Unlike
// advanceSph the world runs ahead of the caller's clock, so it is for callers that only read it.
template <typename F>
SphStatus advanceSphUntil(SphWorld& world, double until, F&& per_step, std::size_t max_steps = 1000000) {
  for (std::size_t steps = 0; world.time < until - 1e-7; ++steps) {
    if (steps >= max_steps) return {"advanceSphUntil: more than max_steps steps needed"};
    SphStepStats stats;
    if (SphStatus status = stepSph(world, 0.0f, &stats); !status.ok()) return status;
    per_step(stats);
  }
  return {};
}

// Particle positions at time t in storage order: linear between the start and the end of the last
// step, the path the advection x += dt v takes (collision projections aside). t is clamped to
// [world.time - world.last_dt, world.time]; before the first step `out` is the current positions.
void sphPositionsAt(const SphWorld& world, double t, std::vector<glm::vec3>& out);

// --- implementation of the templates ---
template <typename Inside>
std::size_t addSphPool(SphWorld& world, glm::vec3 lo, glm::vec3 hi, std::size_t count, Inside&& inside) {
  const float d = sphSpacing(world.params), r = world.params.particle_radius;
  const glm::ivec3 n = glm::max(glm::ivec3(glm::floor((hi - lo) / d + 1e-4f)), glm::ivec3(0));
  std::size_t added = 0;
  for (int y = 0; y < n.y && added < count; ++y) {
    for (int z = 0; z < n.z && added < count; ++z)
      for (int x = 0; x < n.x && added < count; ++x) {
        const glm::vec3 p = lo + glm::vec3(r) + d * glm::vec3(x, y, z);
        if (!inside(p) || sphNearCollider(world, p, r)) continue;
        if (!addSphParticle(world, p)) return added;
        ++added;
      }
  }
  return added;
}

SphStatus advanceSphImpl(SphWorld& world, double duration, void (*cb)(void*, const SphStepStats&), void* ctx,
                         std::size_t max_steps);

template <typename F>
SphStatus advanceSph(SphWorld& world, double duration, F&& per_step, std::size_t max_steps) {
  return advanceSphImpl(
      world, duration, [](void* c, const SphStepStats& s) { (*static_cast<std::remove_reference_t<F>*>(c))(s); },
      &per_step, max_steps);
}

}  // namespace fluid
