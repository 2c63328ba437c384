#pragma once
// A game effect is one unit: an EffectDesc (name, doc, parameter table, what it needs) and the
// Effect object it builds. World holds the built effects in registry order and loops over them;
// nothing outside game/effects/ names a particular effect to build, step, tune or draw it.
//
// Life of an effect (World, game/world/world.cpp):
//   desc.build(section, ctx)    the scene lists it: parse its table, build its state, publish
//                               what it offers the others into EffectLinks
//   attachGpu / detachGpu       GL context current (runScene only; `replay --no-render` never does)
//   step                        one fixed step, in registry order (a later effect sees this step's
//                               state of an earlier one: sprites spray from this step's water)
//   prepareFrame                once per rendered frame, after the steps (CPU meshing)
//   submit                      what the renderer draws this frame (engine::FrameBatches)
//   applyLive                   the overlay edited its section: re-parse the table and re-derive the
//                               dependent values by the same code `build` uses
//   hashState                   what the replay's checkpoints gate on (game/replay/state_hash.hpp)
//   reportColumns               its cells of the replay CSV row (the columns its desc declares)
//   soakCheck                   its checks after every frame of `fluiddemo soak` (game/soak_monitor.hpp)
// Effects talk to each other only through EffectLinks (one slot per capability, filled at build).
//
// Adding an effect: one file game/effects/<name>.cpp defining `const EffectDesc& <name>Effect()`
// (sources.cmake takes every file there) and its line in game/effects/registry.cpp; gulls.cpp is
// the smallest whole example.

#include "engine/profile/profiler.hpp"
#include "fluid/core/blast.hpp"
#include "game/effects/effect_report.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/fountain.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace engine {
struct FrameBatches;
struct WaterStats;
namespace audio {
struct Mixer;
}  // namespace audio
}  // namespace engine

namespace fluid {
struct BlobWorld;
}  // namespace fluid

namespace game {

struct Explosives;
struct RigidBodies;
struct SphFluid;

// What effects offer each other. An effect publishes into its slot when it is built and reads
// the slots of effects built before it (registry order); a slot stays null when no listed effect
// offers it.
struct EffectLinks {
  // The particles' gravity: rigid_bodies publishes its own; (0, -9.81, 0) m/s^2 without it.
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};
  FountainGeometry level;           // the level's shape: the nozzle, the basin
  // The level's baked colliders (content/colliders), loaded by the first effect that needs them
  // (ensureFountainColliders): the SPH boundary and the sprites share them.
  std::shared_ptr<const LevelColliders> colliders;
  RigidBodies* bodies = nullptr;    // rigid_bodies: Bullet world + crates (the water pushes them)
  const SphFluid* fluid = nullptr;  // sph_fluid: the particles (surface meshes, spray sprites)
  Explosives* explosives = nullptr;  // explosives: the player's charges (playerThrowExplosive)
  // This step's detonations (explosives publishes them in its step; empty otherwise). Effects after
  // it in registry order push their own matter with each blast by the shared law of
  // fluid/core/blast.hpp in the same step: the water, the blob, the sprites.
  std::span<const fluid::Blast> blasts;
  // The player: World writes the camera position before each step; an effect that catches the
  // player (blob) sets reset_player and World puts the camera back at the scene's start pose after
  // the step (the round restarts).
  glm::vec3 player{0.0f};
  bool reset_player = false;
  // An effect that grabs the player (the blob's catch) sets camera_pull in its step; World then
  // moves the camera `rate` (in (0, 1]) of the way to `toward` and turns it by the same share
  // toward `look_at`, after the step, and clears it. rate 0: no pull.
  struct CameraPull {
    glm::vec3 toward{0.0f};
    glm::vec3 look_at{0.0f};
    float rate = 0.0f;
  } camera_pull;
  // blob: the goo's particles (the audio effect hears their impacts).
  const fluid::BlobWorld* blob = nullptr;
  // audio: the mixer its step queues the simulation's sounds into (engine/audio/synth.hpp). The
  // live device pulls it from SDL's audio thread; `replay --wav` sets the listener before each step
  // and renders the step's samples after it (game/replay/replay_runner.cpp).
  engine::audio::Mixer* audio = nullptr;
};

struct BuildContext {
  const SceneConfig& scene;
  const std::filesystem::path& content_dir;
  std::uint32_t seed = 0;  // scene.seed
  EffectLinks& links;
};

struct StepContext {
  double step_seconds = 1.0 / 60.0;
  int substeps = 1;
  engine::Profiler* profiler = nullptr;  // may be null
  EffectLinks& links;
};

// An effect's step may fail on content without ending the game: `failure` is counted by World
// (RuntimeFailures) and the frame goes on.
struct StepOutcome {
  std::string failure;  // "<effect>: <error>", empty when fine
};

struct FrameContext {
  glm::vec3 eye{0.0f};
  glm::vec3 view_dir{0.0f, 0.0f, -1.0f};
  engine::Profiler* profiler = nullptr;  // may be null
  bool aiming = false;  // the player holds the throw key: an effect that throws draws its aim (rendering only)
};

struct LevelAssets;

// What an effect hands the renderer for one frame.
struct SubmitContext {
  const LevelAssets& assets;  // the level's GPU meshes and textures (the crate model)
  float alpha = 1.0f;         // interpolation between the last two steps
};

struct GpuContext {
  const std::filesystem::path& shader_dir;
  const std::filesystem::path& content_dir;
  double step_seconds = 1.0 / 60.0;
};

// What an effect tells the player on screen, outside the full panels (game/scene_panel.cpp).
struct HudText {
  std::string line;    // joins the compact strip's status line (short; empty: nothing)
  std::string banner;  // a large message mid-screen while it lasts, e.g. "caught" (empty: none)
};

class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string_view name() const = 0;
  virtual void applyLive(const SectionConfig& section, EffectLinks& links) = 0;
  virtual StepOutcome step(const StepContext& ctx) = 0;
  // Empty when every value is finite; otherwise names the first NaN/inf.
  virtual std::string findNonFinite() const { return {}; }
  virtual void attachGpu(const GpuContext&) {}
  virtual void detachGpu() {}
  // CPU work for the frame about to be drawn; false + error when the effect refused its input
  // (the frame goes on without it).
  virtual bool prepareFrame(const FrameContext&, std::string& /*error*/) { return true; }
  virtual void submit(engine::FrameBatches& /*frame*/, const SubmitContext&) {}
  // After the frame: the water backends' account of it, per FrameBatches::water entry in
  // submission order (engine::lastWaterStats); an effect that submitted water reads its entry.
  virtual void readRenderStats(std::span<const engine::WaterStats> /*water*/) {}
  virtual void drawStatus() const {}  // the overlay's status lines (ImGui text)
  virtual HudText hud() const { return {}; }  // the player-facing line and banner, every frame
  // Feeds the CPU state a replay gates on into `hash` and returns true; false (the default): the
  // effect has no such state (GPU-only or derived from the others every frame).
  virtual bool hashState(Fnv1a64& /*hash*/, StateHashScratch& /*scratch*/) const { return false; }
  // This frame's values of the CSV columns its EffectDesc declares (FrameColumns::set / add).
  virtual void reportColumns(FrameColumns& /*row*/) const {}
  // `fluiddemo soak`: before each step (e.g. ask for a GPU read-back) and after each frame.
  virtual void soakBeforeStep(SoakProbe& /*probe*/) {}
  virtual void soakCheck(SoakProbe& /*probe*/) const {}
};

// An effect whose state other code may read (tests, soak checks, state hashes): findState<State>.
template <class State>
class EffectOf : public Effect {
 public:
  State state;
};

struct EffectDesc {
  std::string_view name;
  std::string_view doc;
  std::span<const ParamSpec> params;        // the effect's parameter table as schema rows
  std::span<const std::string_view> needs;  // effects that must be listed too
  // Builds the effect for a listed section. False + error naming the effect, key and value.
  std::unique_ptr<Effect> (*build)(const SectionConfig& section, BuildContext& ctx, std::string& error);
  std::span<const ColumnSpec> columns = {};  // its replay CSV columns (Effect::reportColumns fills them)
};

// Every effect the game knows, in build and step order (game/effects/registry.cpp).
std::span<const EffectDesc* const> effectRegistry();
const EffectDesc* findEffectDesc(std::string_view name);

// A profiler phase for this scope when `profiler` is set (steps run without one in tests).
class PhaseScope {
 public:
  PhaseScope(engine::Profiler* profiler, engine::Phase phase) {
    if (profiler != nullptr) scope_.emplace(*profiler, phase);
  }

 private:
  std::optional<engine::ScopedPhase> scope_;
};

}  // namespace game
