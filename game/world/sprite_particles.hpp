#pragma once
// The `sprite_particles` effect: the fountain's mist and spray as GPU state-preserving particles
// (engine/gpu_particles, Kolb, Latta & Rezk-Salama 2004 §3). The CPU decides births (§3.3.1:
// "initial particle data is determined on the CPU"): the jet's mist from the nozzle, and spray
// born from the SPH fluid after Ihmsen et al. 2012 (see emitSprayFromSph). Simulation,
// collisions with depth maps baked from the level's models (Kolb §4), the odd-even merge sort
// and the point-sprite draw all run on the GPU; nothing the GPU computes flows back into the
// game (no feedback into SPH or Bullet), so the sprites are not part of the replay state hash.
//
// Two stages, so a world can exist without a GL context:
//   initSpriteParticles   no GL: parameters, seed, budget. buildWorld calls it.
//   attachSpriteGpu       needs the GL context current: loads the colliders (once), creates the
//                         textures/FBOs/shaders. runScene calls it; `replay --no-render` and
//                         the unit tests without GL never do, and then stepping is a no-op (no
//                         births, no cost: the effect simply is not simulated there).
//   detachSpriteGpu       frees the GL objects; must run while the same context is current
//                         (the destructor does not touch GL: the context may be gone).
// A system whose shaders failed (`gpu.ready == false`, `gpu_error` set) keeps the game running
// without the effect.

#include "engine/gpu_particles/gpu_particles.hpp"
#include "fluid/collide/collide.hpp"
#include "fluid/sph/diffuse.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace game {

struct SphFluid;

// The effect's parameters; their defaults are the scene defaults (game/effects/sprite_particles.cpp
// binds each to its scene key). Mist and spray are live-tunable; max_particles is the budget,
// fixed at construction.
struct SpriteParticleParams {
  // Mist: a cone of sprites from the nozzle.
  float rate = 1500.0f;                 // sprites per second
  float speed = 7.0f;                   // m/s at the nozzle (±20 %)
  float spread_degrees = 8.0f;          // half-angle of the cone
  float lifetime = 4.0f;                // s (±25 %)
  std::uint32_t max_particles = 10000;  // GPU budget, mist and spray
  float size = 0.035f;                  // sprite radius, m
  float restitution = 0.3f;             // Kolb §3.3.2 resilience ε
  float friction = 0.15f;               // Kolb §3.3.2 friction ν
  // Spray from the SPH fluid (Ihmsen et al. 2012 §4, a subset; see emitSprayFromSph).
  float spray_rate = 40.0f;            // k: sprites per second from a particle with I_k = I_s = 1
  float spray_energy_min = 8.0f;       // τ_k,min: specific kinetic energy ½|v|² (J/kg) where I_k starts
  float spray_energy_max = 30.0f;      // τ_k,max: where I_k reaches 1
  float spray_surface_density = 0.9f;  // ρ/ρ0 at or below which a particle counts as at the free surface
  float spray_lifetime = 1.2f;         // s (±25 %)
  int spray_max_per_step = 200;        // cap on spray births per step
  bool blast_debris = true;            // a blast throws grit too (off where it would fall into a level's holes)
  // Foam and bubbles (Ihmsen et al. 2012, the rest of the paper; fluid/sph/diffuse.hpp): diffuse
  // sprites born from the trapped-air and wave-crest potentials scaled by the kinetic energy
  // (eq. 2), classed on the GPU each step by the fluid-neighbour count at the sprite (§4.2).
  float foam_trapped_air_rate = 60.0f;  // k_ta: diffuse sprites per second at I_ta = I_k = 1 (0 = none)
  float foam_wave_crest_rate = 20.0f;   // k_wc: the same for I_wc
  float foam_ta_min = 2.0f;             // τ_ta,min (m/s)
  float foam_ta_max = 10.0f;            // τ_ta,max
  float foam_wc_min = 0.1f;             // τ_wc,min (dimensionless curvature)
  float foam_wc_max = 1.0f;             // τ_wc,max
  float foam_energy_min = 1.0f;         // τ_k,min on |v|^2/2 (J/kg)
  float foam_energy_max = 10.0f;        // τ_k,max
  float foam_lifetime = 3.0f;           // s (±25 %); foam fades over it
  float bubble_buoyancy = 2.0f;         // k_b of eq. 8
  float bubble_drag = 0.5f;             // k_d of eq. 8
  int foam_spray_below = 6;             // §4.2: spray below this many fluid neighbours
  int foam_bubble_above = 20;           // §4.2: bubble above
  int foam_max_per_step = 300;          // cap on diffuse births per step
  // From the world, not the scene section: the particles' gravity and the level's nozzle.
  glm::vec3 gravity{0.0f};
  glm::vec3 nozzle{0.0f};
};

// Reads a validated "sprite_particles" section (the effect's parameter table) and sets the
// world-given fields.
SpriteParticleParams spriteParamsFrom(const SectionConfig& section, glm::vec3 gravity, glm::vec3 nozzle);

// Particle types in the GPU system's key-frame table.
inline constexpr std::uint32_t kMistType = 0;
inline constexpr std::uint32_t kSprayType = 1;
inline constexpr std::uint32_t kDebrisType = 2;  // explosion debris: dark grit thrown out, falls
inline constexpr std::uint32_t kSmokeType = 3;   // explosion smoke: grows, rises slowly, fades
inline constexpr std::uint32_t kFireType =
    4;  // explosion fireball: a bright burst that rises and dies within half a second
inline constexpr std::uint32_t kRingType = 5;  // a blast's shock ring on the water: white foam rushing out, slowing
// Diffuse sprites (engine ParticleTypeDesc::diffuse): classed on the GPU every step, drawn as their class.
inline constexpr std::uint32_t kDiffuseSprayType = 6;
inline constexpr std::uint32_t kFoamType = 7;
inline constexpr std::uint32_t kBubbleType = 8;

struct SpriteParticles {
  SpriteParticleParams params;
  std::uint32_t capacity = 0;  // max_particles, fixed at construction
  std::uint64_t seed = 0;
  std::uint64_t steps = 0;    // steps simulated on the GPU
  double emit_debt = 0.0;     // fractional mist sprites owed to the next step
  double spray_debt = 0.0;    // fractional spray sprites owed to the next step
  engine::BirthBatch births;  // scratch, reused every step
  // Foam and bubbles: the potentials' scratch and the fluid grid, reused every step.
  fluid::DiffuseScratch diffuse_scratch;
  fluid::DiffusePotentials potentials;
  std::vector<fluid::DiffuseBirth> diffuse_births;
  fluid::FluidCellGrid fluid_grid;
  // GPU side (attachSpriteGpu).
  bool attached = false;
  engine::GpuParticles gpu;
  std::string gpu_error;  // why the effect is off (shader or collider failure); empty while fine
  // The level's baked colliders (content/colliders: ground, basin, statue; collider space =
  // world), shared with the SPH fluid (EffectLinks::colliders) or loaded at attach.
  std::shared_ptr<const LevelColliders> level_colliders;
  std::string level = "fountain";  // the scene's level, whose colliders the sprites bounce on
  std::vector<std::string> collider_names;
  double bake_ms = 0.0;  // loading them (a stale file is re-baked)
  // Counters for the overlay and tests.
  std::uint64_t born_mist = 0, born_spray = 0, born_blast = 0;
  std::uint64_t born_diffuse = 0;                    // foam/bubble/spray births from the potentials
  std::array<std::uint32_t, 3> diffuse_last_step{};  // births of the last step by class at birth
  std::uint64_t shock_rings = 0;                     // blasts that met the water and threw a ring of foam
  std::uint64_t dropped = 0;                         // births refused because the budget was full
  std::uint64_t buried_blast = 0;                    // blast sprites not born: inside a level collider
  std::uint32_t spray_last_step = 0;
  // Read-back for checks (soak, tests): every `readback_every` GPU steps (0 = never) the step asks
  // for the live sprites' positions and velocities after it (engine::requestReadback); the frame's
  // sprite pass reads them into gpu.readback (xyz, w = 1), with the step they belong to.
  int readback_every = 0;
};

// CPU only (no GL): parameters, budget and seed.
void initSpriteParticles(SpriteParticles& s, const SpriteParticleParams& params, std::uint32_t capacity,
                         std::uint64_t seed);

// The baked colliders of s.level (ensureLevelColliders) into s.level_colliders unless set;
// no GL. False + error naming the file on failure.
bool loadSpriteColliders(SpriteParticles& s, const std::filesystem::path& content_dir, std::string& error);

// Needs the GL context current. Loads the colliders if not done yet, creates the GPU system for
// `capacity` sprites and uploads the colliders. A failure leaves the effect off (gpu_error says
// why) and returns false; the game goes on. A zero budget creates nothing and returns true.
bool attachSpriteGpu(SpriteParticles& s, const std::filesystem::path& shader_dir,
                     const std::filesystem::path& content_dir, float dt);
void detachSpriteGpu(SpriteParticles& s);

// One fixed step (no-op when not attached): retire, emit mist and spray (from `sph` when given),
// integrate and collide (Kolb §3.3.1–3.3.2), read back when due. No GL: the engine records the GPU
// work and the frame runs it.
// `blasts`: this step's explosions (EffectLinks::blasts): each throws debris and smoke sprites at
// its centre, and every live sprite is pushed by it (fluid/core/blast.hpp, in the update shader).
// Returns what the engine refused (the foam's fluid grid), for the world's run-time failures; empty when
// all went through.
std::string stepSpriteParticles(SpriteParticles& s, const SphFluid* sph, float dt,
                                std::span<const fluid::Blast> blasts = {});

// The GPU half of each step (births, the update pass, read-backs) is recorded by the engine and run
// by the frame: the effect submits `gpu` to the frame (engine::FrameBatches::sprites), whose sprite
// pass runs the steps recorded since the last frame, sorts for the eye (Kolb §3.3.3) and draws.

// Live sprites as the CPU allocator counts them (0 when not attached).
std::uint32_t liveSprites(const SpriteParticles& s);

// Spray births (Ihmsen et al. 2012): appends to `batch`, returns the number appended. Pure
// function of its inputs (seeded), no GL.
std::size_t emitSprayFromSph(const SphFluid& sph, const SpriteParticleParams& params, float dt, std::uint64_t seed,
                             double& debt, engine::BirthBatch& batch);

// Foam and bubbles (Ihmsen et al. 2012): the potentials of every SPH particle, then eq. 2's
// births, typed by their parent's neighbour count (kDiffuseSprayType / kFoamType / kBubbleType).
// Appends to `batch`, returns the number appended. Pure function of its inputs (seeded), no GL.
// `per_class` counts the births by class at birth (spray, foam, bubble).
struct DiffuseScratchSet {
  fluid::DiffuseScratch& scratch;
  fluid::DiffusePotentials& potentials;
  std::vector<fluid::DiffuseBirth>& births;
};
std::size_t emitDiffuseFromSph(const SphFluid& sph, const SpriteParticleParams& params, float dt, std::uint64_t seed,
                               DiffuseScratchSet scratch, engine::BirthBatch& batch,
                               std::array<std::uint32_t, 3>& per_class);
// The diffuse parameters of fluid/sph/diffuse.hpp for neighbourhood radius h (the SPH support).
fluid::DiffuseParams diffuseParams(const SpriteParticleParams& params, float h);

// Empty when the last read-back holds only finite values; otherwise names the first bad one.
std::string findNonFiniteSprite(const SpriteParticles& s);

}  // namespace game
