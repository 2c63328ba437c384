// The schema every scene file and --set override is validated against. A section with
// is_effect = true is an effect: its system is constructed only when a scene lists it.
#include "game/scene/scene_config.hpp"

#include <array>

namespace game {
namespace {

ParamValue num(double value) { return {ParamType::number, value, false, {}, {}}; }
ParamValue integer(int value) { return {ParamType::integer, static_cast<double>(value), false, {}, {}}; }
ParamValue vec(float x, float y, float z) { return {ParamType::vec3, 0.0, false, {x, y, z}, {}}; }
ParamValue flag(bool value) { return {ParamType::boolean, 0.0, value, {}, {}}; }
ParamValue word(const char* value) { return {ParamType::text, 0.0, false, {}, value}; }

constexpr std::string_view kSolverChoices[] = {"dfsph", "wcsph"};
constexpr std::string_view kOrderChoices[] = {"sorted", "unsorted", "exact"};
constexpr std::string_view kSurfaceMethodChoices[] = {"mesh", "screen_space", "raycast"};

const std::array kSceneParams = {
    ParamSpec{"step_hz", ParamType::number, 30.0, 240.0, num(60.0), "fixed simulation steps per second"},
    ParamSpec{"substeps", ParamType::integer, 1, 16, integer(1), "physics substeps per simulation step"},
    ParamSpec{"max_steps_per_frame", ParamType::integer, 1, 20, integer(5), "backlog cap after a hitch"},
    ParamSpec{"seed", ParamType::integer, 0, 2147483647, integer(1), "seed of every random choice in the scene"},
};

const std::array kCameraParams = {
    ParamSpec{"position", ParamType::vec3, -1000.0, 1000.0, vec(0.0f, 2.0f, 12.0f), "start position (m), y up"},
    ParamSpec{"yaw_degrees", ParamType::number, -360.0, 360.0, num(-90.0), "heading; -90 looks along -z"},
    ParamSpec{"pitch_degrees", ParamType::number, -89.0, 89.0, num(-8.0), "look up (+) or down (-)"},
    ParamSpec{"fov_degrees", ParamType::number, 20.0, 120.0, num(60.0), "vertical field of view"},
    ParamSpec{"move_speed", ParamType::number, 0.1, 100.0, num(5.0), "WASD speed (m/s)"},
};

const std::array kRigidBodyParams = {
    ParamSpec{"gravity", ParamType::vec3, -100.0, 100.0, vec(0.0f, -9.81f, 0.0f), "m/s^2"},
    ParamSpec{"crates", ParamType::integer, 0, 200, integer(6), "crates stacked around the fountain"},
    ParamSpec{"crate_size", ParamType::number, 0.1, 5.0, num(0.6), "crate edge length (m)"},
    ParamSpec{"throw_speed", ParamType::number, 0.0, 100.0, num(14.0), "speed of a crate thrown with left click (m/s)"},
};

const std::array kSpriteParticleParams = {
    ParamSpec{"rate", ParamType::number, 0.0, 100000.0, num(1500.0), "mist sprites emitted per second at the nozzle"},
    ParamSpec{"speed", ParamType::number, 0.0, 50.0, num(7.0), "mist speed at the nozzle (m/s, +-20%)"},
    ParamSpec{"spread_degrees", ParamType::number, 0.0, 90.0, num(8.0), "half-angle of the mist cone"},
    ParamSpec{"lifetime", ParamType::number, 0.1, 60.0, num(4.0), "mist sprite lifetime (s, +-25%)"},
    ParamSpec{"max_particles", ParamType::integer, 0, 1000000, integer(10000),
              "GPU sprite budget, mist and spray (fixed at construction; 0 = no GPU resources)"},
    ParamSpec{"size", ParamType::number, 0.005, 1.0, num(0.035), "sprite radius (m)"},
    ParamSpec{"restitution", ParamType::number, 0.0, 1.0, num(0.3),
              "Kolb 2004 resilience: bounce off the baked ground/basin/statue depth maps"},
    ParamSpec{"friction", ParamType::number, 0.0, 1.0, num(0.15), "Kolb 2004 friction on the baked colliders"},
    ParamSpec{"spray_rate", ParamType::number, 0.0, 10000.0, num(40.0),
              "Ihmsen 2012 k: spray sprites per second from a surface particle with I_k = 1 (0 = no spray)"},
    ParamSpec{"spray_energy_min", ParamType::number, 0.0, 1000.0, num(8.0),
              "Ihmsen 2012 tau_k,min: specific kinetic energy |v|^2/2 (J/kg) where spray starts"},
    ParamSpec{"spray_energy_max", ParamType::number, 0.0, 1000.0, num(30.0),
              "Ihmsen 2012 tau_k,max: |v|^2/2 (J/kg) of full spray"},
    ParamSpec{"spray_surface_density", ParamType::number, 0.0, 2.0, num(0.9),
              "rho/rho0 at or below which an SPH particle counts as at the free surface"},
    ParamSpec{"spray_lifetime", ParamType::number, 0.1, 60.0, num(1.2), "spray sprite lifetime (s, +-25%)"},
    ParamSpec{"spray_max_per_step", ParamType::integer, 0, 100000, integer(200), "cap on spray births per step"},
};

const std::array kSphFluidParams = {
    ParamSpec{"solver", ParamType::text, 0.0, 0.0, word("dfsph"),
              "dfsph (Bender & Koschier 2015) or wcsph (Becker & Teschner 2007)", kSolverChoices},
    ParamSpec{"max_particles", ParamType::integer, 1, 50000, integer(2500),
              "particle budget (fixed at construction; the jet pauses at it)"},
    ParamSpec{"particle_radius", ParamType::number, 0.01, 0.2, num(0.04), "r (m); spacing 2r (fixed at construction)"},
    ParamSpec{"jet_speed", ParamType::number, 0.1, 20.0, num(4.5), "speed of the jet at the nozzle (m/s)"},
    ParamSpec{"nozzle_radius", ParamType::number, 0.0, 0.5, num(0.12),
              "radius of the nozzle disc (m); particles per layer = lattice points inside"},
    ParamSpec{"rate", ParamType::number, 0.0, 50000.0, num(500.0),
              "particles emitted per second (capped: layers never overlap)"},
    ParamSpec{"viscosity", ParamType::number, 0.0, 1.0, num(0.02), "kinematic viscosity nu (m^2/s)"},
    ParamSpec{"drain", ParamType::boolean, 0.0, 0.0, flag(true), "four drains at the basin wall recycle the water"},
    ParamSpec{"cfl", ParamType::number, 0.05, 1.0, num(0.4), "CFL number: a step moves no particle more than cfl * 2r"},
    ParamSpec{"max_time_step", ParamType::number, 0.0005, 0.05, num(0.005), "upper bound of one adaptive SPH step (s)"},
    ParamSpec{"density_error", ParamType::number, 0.00001, 0.05, num(0.0005),
              "dfsph: mean density error tolerance of the pressure solve (0.0005 = 0.05 %)"},
    ParamSpec{"force_bound", ParamType::number, 0.0, 1.0, num(0.0025),
              "dfsph: force condition |g| dt^2 <= force_bound * cfl * 2r (keeps resting water still); 0 = off"},
    ParamSpec{"warm_start", ParamType::boolean, 0.0, 0.0, flag(true),
              "dfsph: start the density solve from 0.4 x the previous step's stiffness (Bender & Koschier 2017 "
              "sec. 4.3; fluid::SphParams::warm_start); false = from zero"},
    ParamSpec{
        "couple_bodies", ParamType::boolean, 0.0, 0.0, flag(true),
        "crates and water push each other, two-way (only when rigid_bodies is listed too; fixed at construction)"},
};

const std::array kFluidSurfaceParams = {
    ParamSpec{"method", ParamType::text, 0.0, 0.0, word("mesh"),
              "how the water is drawn: mesh (marching slices, CPU), screen_space (splat depth, bilateral smoothing; "
              "Janisz 3.1) or raycast (metaball fragment lists; Szecsi & Illes 2012); live",
              kSurfaceMethodChoices},
    ParamSpec{"order", ParamType::text, 0.0, 0.0, word("sorted"),
              "triangle order: sorted (back-to-front blocks), unsorted, exact (per slab, depth-sorted)", kOrderChoices},
    ParamSpec{"smoothing", ParamType::number, 1.0, 4.0, num(2.0), "field cutoff Rc in particle spacings"},
    ParamSpec{"cube", ParamType::number, 0.2, 2.0, num(0.5), "marching cube edge in particle spacings"},
    ParamSpec{"threshold", ParamType::number, 0.01, 0.24, num(0.2), "iso level T of the particle field"},
    ParamSpec{"refraction", ParamType::number, 0.0, 1.0, num(0.08), "screen offset per metre of water; 0 = off"},
    ParamSpec{"opacity", ParamType::number, 0.0, 1.0, num(0.85), "blend alpha of one water layer"},
    ParamSpec{"absorption", ParamType::vec3, 0.0, 50.0, vec(1.6f, 0.45f, 0.25f), "Beer-Lambert sigma per metre, RGB"},
    ParamSpec{"visible", ParamType::boolean, 0.0, 0.0, flag(true),
              "false: the water is not drawn (the same frame without it; docs/render.md's water masks); live"},
};

const std::array kSections = {
    SectionSpec{"scene", false, "simulation clock", kSceneParams},
    SectionSpec{"camera", false, "first-person camera", kCameraParams},
    SectionSpec{"rigid_bodies", true, "Bullet world: ground, basin, statue, crates", kRigidBodyParams},
    SectionSpec{"sprite_particles", true, "GPU sprites (Kolb 2004): nozzle mist and SPH spray, depth-map collisions",
                kSpriteParticleParams},
    SectionSpec{"sph_fluid", true, "SPH water (CPU): nozzle jet, fountain colliders, drains", kSphFluidParams},
    SectionSpec{"fluid_surface", true, "marching-slices mesh of sph_fluid drawn as refractive water (needs sph_fluid)",
                kFluidSurfaceParams},
};

}  // namespace

std::span<const SectionSpec> sceneSchema() { return kSections; }

}  // namespace game
