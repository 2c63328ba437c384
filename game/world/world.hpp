#pragma once
// The game world built from a SceneConfig: one Effect per listed effect (game/effects/),
// constructed ONLY when the scene lists it, in registry order. An unlisted effect allocates
// nothing and stepWorld never enters its profiler phase. `systems` lists what was built.

#include "engine/camera/camera.hpp"
#include "engine/profile/profiler.hpp"
#include "game/effects/effect.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/body_fluid_coupling.hpp"
#include "game/world/fluid_surface.hpp"
#include "game/world/fountain.hpp"
#include "game/world/rigid_bodies.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/sprite_particles.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace game {

// A system that fails on content at run time (the mesher or the SPH solver returning an error)
// does not end the game: the failure is counted and kept here, the overlay and the run summary show
// it, and the frame goes on (the surface is empty for that frame and retried the next; a fluid
// whose solver refused a step stops stepping). Broken invariants stay asserts; NaN/inf in the
// state goes to World::nonfinite_state.
struct RuntimeFailures {
  std::uint64_t count = 0;
  std::string first;  // "<system>: <error> at step N"
  std::string last;
};

struct World {
  SceneConfig scene;                             // live copy; the overlay edits it
  std::vector<std::string> systems;              // effect names constructed, registry order
  std::vector<std::unique_ptr<Effect>> effects;  // the listed effects, registry order
  EffectLinks links;                             // what the effects offer each other
  engine::FpsCamera camera;
  bool player_aiming = false;  // the throw key is held this frame (FrameContext::aiming; never simulated)
  double step_seconds = 1.0 / 60.0;
  int substeps = 1;
  std::uint64_t steps = 0;
  std::string nonfinite_state;  // first NaN/inf seen (empty while everything is finite)
  RuntimeFailures failures;     // systems that refused content this run (the frame went on)
};

// The state of the built effect of type EffectOf<State> (RigidBodies, SphFluid, SpriteParticles,
// FluidSurface), or null when the scene does not list it. For readers of one effect's state
// (tests, soak checks, state hashes); the world itself never asks.
template <class State>
State* findState(World& world) {
  for (const std::unique_ptr<Effect>& effect : world.effects)
    if (auto* typed = dynamic_cast<EffectOf<State>*>(effect.get())) return &typed->state;
  return nullptr;
}
template <class State>
const State* findState(const World& world) {
  return findState<State>(const_cast<World&>(world));
}

// Gravity of the scene's particles: the rigid bodies' gravity when that effect is listed, else
// (0, -9.81, 0) m/s^2. For code that builds one effect's state without a World (the fountain
// benchmark); inside a World the effects read EffectLinks::gravity.
glm::vec3 sceneGravity(const SceneConfig& scene);

// Builds the world. `content_dir` is the content/ folder (models for the Bullet meshes).
// Returns false with a message naming the file/effect on failure (also when an effect is listed
// without one it needs, e.g. fluid_surface without sph_fluid).
bool buildWorld(const SceneConfig& scene, const std::filesystem::path& content_dir, World& out, std::string& error);

// GL resources of the world's effects (Effect::attachGpu), created with the GL context
// current (runScene after the renderer; never by `replay --no-render`, whose sprites then do not
// run). A world without a GPU effect creates no GL object. detachWorldGpu frees them and must run
// while the same context is current (before a rebuild and before the context goes).
void attachWorldGpu(World& world, const std::filesystem::path& shader_dir, const std::filesystem::path& content_dir);
void detachWorldGpu(World& world);

// Re-reads the live-tunable parameters from world.scene (after the overlay edited them): the
// camera, then Effect::applyLive of each effect in registry order. Parameters fixed at
// construction (crates, crate_size, max_particles, particle_radius, solver, pump, scene.*) need
// a rebuild.
void applyLiveParams(World& world);

// One fixed simulation step of every constructed system, timed into `profiler` (physics for
// rigid bodies, fluid for particles and the crate <-> water coupling; may be null). Checks every value for NaN/inf
// after the step and records the first one in world.nonfinite_state; a solver error is recorded in
// world.failures.
void stepWorld(World& world, engine::Profiler* profiler);

// What the world draws this frame: every effect's batches (Effect::submit) in registry order,
// interpolated by `alpha` between the last two steps. The level's own meshes are not included
// (submitLevel, level_assets.hpp).
void submitWorld(World& world, engine::FrameBatches& frame, const LevelAssets& assets, float alpha);

// After engine::renderFrame: what the water backends tell of the frame, handed to every effect
// (Effect::readRenderStats) by the game; the engine writes nothing into game state.
void readWorldRenderStats(World& world, std::span<const engine::WaterStats> water);

// Meshes the fluid surface for the camera (no-op without fluid_surface), timed into the
// profiler's meshing phase (may be null). Call once per rendered frame, after stepping.
// A failed extraction leaves an empty mesh and records the error in world.failures.
void meshWorld(World& world, engine::Profiler* profiler);

// Counts a run-time failure of a system ("<system>: <error>") at the current step.
void recordFailure(World& world, const std::string& what);

// Throws a crate from the camera along its view (no-op without rigid_bodies).
void playerThrow(World& world);
// Throws a fused charge from the camera along its view (no-op without the explosives effect).
void playerThrowExplosive(World& world);

}  // namespace game
