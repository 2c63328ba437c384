// The `blob` effect: the marching-slices paper's second demo (Rosenberg & Birdwell 2008, §7 and
// Figure 8), an amorphous particle monster that emerges from a sewer, forms a ball, grows textured
// tentacles, coats a wall, chases the player and reassembles after explosives. The body and the
// behaviours are fluid/blob; this file builds them from the scene, runs the behaviour program
// (game/world/blob_program.hpp reads it), collides the body with the level's baked depth-map
// colliders and the crates (game/world/blob_crates.hpp, both ways), applies this step's blasts,
// catches the player, and meshes the body per frame through marching slices with the tentacle
// texturing policy (the shared meshing job, game/world/surface_job.hpp). State:
// game/world/blob_monster.hpp.
#include "game/world/blob_crates.hpp"
#include "game/world/blob_monster.hpp"
#include "game/world/blob_program.hpp"

#include "engine/render/frame.hpp"
#include "fluid/blob/tentacle_uv.hpp"
#include "fluid/collide/collider_cache.hpp"
#include "fluid/surface/marching_slices_policy.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/world/collider_model.hpp"
#include "game/world/level_assets.hpp"
#include "game/world/rigid_bodies.hpp"

#include <imgui.h>

#include <cmath>
#include <cstdio>

namespace game {
namespace {

const ParamTable<BlobMonsterParams>& table() {
  using P = BlobMonsterParams;
  static const ParamTable<P> rows{
      fixed(param<&P::particles>("particles", 1, 65536, "particles of the body (the paper had 250)")),
      fixed(param<&P::spacing>("spacing", 0.02, 0.3, "rest distance d (m); particle radius d/2")),
      param<&P::cohesion>("cohesion", 0.0, 50.0, "Akinci et al. 2013 cohesion peak (m/s^2): keeps it one body"),
      param<&P::goal_stiffness>("goal_stiffness", 0.0, 5000.0,
                                "Mueller et al. 2005 goal spring (1/s^2) toward the behaviour's shape"),
      param<&P::substeps>("substeps", 1, 64, "explicit sub-steps per fixed step (stability)"),
      param<&P::grate>("grate", -100.0, 100.0, "top of the sewer pipe (m): each round starts in the pipe below it"),
      param<&P::pipe_radius>("pipe_radius", 0.05, 2.0, "radius (m) of the particle column in the pipe"),
      fixed(text<&P::program>("program",
                              "behaviour program (states, their parameters and triggers), a JSON file relative to "
                              "content/ (format: docs/blob.md)")),
      param<&P::caught_seconds>("caught_seconds", 0.0, 10.0,
                                "the caught effect (the camera is pulled into the goo, the screen tints, the goo "
                                "flashes red, a banner gives the round's time) lasts this long, then the round resets"),
      param<&P::smoothing>("smoothing", 1.0, 4.0, "surface field cutoff Rc in spacings"),
      param<&P::cube>("cube", 0.2, 2.0, "marching cube edge in spacings"),
      param<&P::threshold>("threshold", 0.01, 0.24, "iso level T of the field"),
      param<&P::colour>("colour", 0.0, 1.0, "goo colour (RGB)"),
      param<&P::visible>("visible", "false: the monster is not drawn (it still moves)"),
      param<&P::async>("async",
                       "mesh on a worker thread while the next steps run, drawing the previous frame's surface "
                       "(Janisz 3.2.6); false: mesh before drawing"),
  };
  return rows;
}

// ---- Body ---------------------------------------------------------------------------------------

void deriveBody(const BlobMonsterParams& p, glm::vec3 gravity, double step_seconds, fluid::BlobParams& out) {
  out.particle_count = static_cast<std::size_t>(p.particles);
  out.spacing = p.spacing;
  out.cohesion = p.cohesion;
  out.goal_stiffness = p.goal_stiffness;
  out.substeps = p.substeps;
  out.gravity = gravity;
  out.step = static_cast<float>(step_seconds);
}

// A new round: the body as a column in the pipe below the grate, the program from its start.
void startRound(BlobMonster& s) {
  fluid::placeBlob(s.world, s.start_column);
  s.machine = fluid::BlobMachine{};
  s.caught_timer = 0.0f;
}

// The goo's particles as the mesher's input, positions read in place (one particle layout).
fluid::SurfaceInput inputOf(const fluid::BlobParticles& p) {
  return {fluid::pointView(p.position), p.strength, p.radius_scale, {}};
}

// The goo's surface of one set of particles (paper §7): marching slices with the tentacle texturing
// policy, then u around each tentacle (tentacle_uv.hpp says why that is a pass of its own). The
// synchronous path and the async job both run this, so they give the same bits.
fluid::SurfaceStatus meshBlob(fluid::SurfaceExtractor& extractor, const fluid::SurfaceInput& in,
                              const fluid::SurfaceParams& sp, const fluid::BlobParticles& particles,
                              std::span<const std::vector<std::uint32_t>> tentacles, float spacing,
                              fluid::SurfaceMesh& mesh) {
  const fluid::SurfaceStatus st =
      fluid::extractWithPolicy(extractor, in, sp, fluid::BlobTentaclePolicy{particles.length_coord.data()}, mesh);
  if (st.ok()) fluid::blobTentacleU(mesh, particles, tentacles, spacing);
  return st;
}

class BlobEffect final : public EffectOf<BlobMonster> {
 public:
  BlobEffect(RigidBodies* bodies, double step_seconds) : bodies_(bodies), step_seconds_(step_seconds) {}

  std::string_view name() const override { return "blob"; }

  void applyLive(const SectionConfig& section, EffectLinks& links) override {
    const BlobMonsterParams fresh = table().parseLive(section, state.params);
    state.params = fresh;
    deriveBody(fresh, links.gravity, step_seconds_, state.world.params);
  }

  StepOutcome step(const StepContext& ctx) override {
    const PhaseScope phase(ctx.profiler, engine::Phase::fluid);
    if (!state.error.empty()) return {};
    BlobMonster& s = state;
    if (requested_state_ >= 0) {  // the overlay's button
      fluid::enterBlobState(s.program, s.machine, s.world, requested_state_, s.target);
      requested_state_ = -1;
    }
    if (bodies_ != nullptr) blobCollidersFromCrates(s, *bodies_);
    s.blasted_particles = 0;
    for (const fluid::Blast& blast : ctx.links.blasts) s.blasted_particles += fluid::blastBlob(s.world, blast);
    // Tentacles reach for the player's eye; the chase moves over the ground below it and catches by
    // the horizontal distance (fluid::BlobBehaviour::catch_distance).
    s.target = ctx.links.player;
    const std::vector<std::string> events;
    fluid::stepBlobMachine(s.program, s.machine, s.world, {s.target, s.blasted_particles > 0, events});
    const fluid::BlobStatus st = fluid::stepBlob(s.world, &s.stats);
    if (!st.ok()) {
      s.error = st.error;
      return {"blob: " + st.error + " (the monster stops stepping)"};
    }
    if (bodies_ != nullptr) blobImpulsesToCrates(s, *bodies_, ctx.step_seconds);
    stepRound(s, ctx);
    return {};
  }

  void reportColumns(FrameColumns& row) const override {
    row.add("triangles", static_cast<double>(state.job.mesh.indices.size() / 3));
    row.add("mesh_worker_ms", state.job.worker_ms);
  }

  // The goo's particles in index order (their order never changes), the behaviour machine, the round.
  bool hashState(Fnv1a64& h, StateHashScratch&) const override {
    const fluid::BlobParticles& p = state.world.particles;
    h.add(static_cast<std::uint64_t>(p.size()));
    for (std::size_t i = 0; i < p.size(); ++i) {
      hashVec3(h, p.position[i]);
      hashVec3(h, p.velocity[i]);
    }
    h.add(static_cast<std::int64_t>(state.machine.state));
    h.add(state.machine.time_in_state);
    h.add(static_cast<std::int64_t>(state.catches));
    h.add(state.caught_timer);
    return true;
  }

  std::string findNonFinite() const override {
    return fluid::blobAllFinite(state.world.particles) ? std::string() : "blob: a particle is not finite";
  }

  bool prepareFrame(const FrameContext& frame, std::string& error) override {
    const PhaseScope phase(frame.profiler, engine::Phase::meshing);
    BlobMonster& s = state;
    fluid::SurfaceParams sp;
    sp.rc = s.params.smoothing * s.params.spacing;
    sp.cube = s.params.cube * s.params.spacing;
    sp.threshold = s.params.threshold;
    sp.order = fluid::SurfaceOrder::backToFront;  // paper §5: blocks far to near
    sp.eye = frame.eye;
    sp.viewDir = frame.view_dir;
    BlobMeshFrame& f = s.mesh_frame;
    if (!s.params.async) {
      return meshed(s.job.meshNow([&](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
        return meshBlob(extractor, inputOf(s.world.particles), sp, s.world.particles, s.world.target.tentacle_particles,
                        s.world.params.spacing, mesh);
      }),
                    error);
    }
    // The worker meshes a copy of this frame (the next steps move the particles and change the
    // tentacles while it runs); the copy is taken once the job that read the previous one is in.
    return meshed(s.job.meshBehind([&](fluid::AsyncSurfaceExtractor& worker) {
      f.particles = s.world.particles;  // copy-assigned: no allocation once the vectors have grown
      f.tentacles = s.world.target.tentacle_particles;
      f.spacing = s.world.params.spacing;
      f.params = sp;
      fluid::SurfaceStatus valid = fluid::validateSurface(inputOf(f.particles), sp);
      if (valid.ok())
        worker.startJob([&f](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
          return meshBlob(extractor, inputOf(f.particles), f.params, f.particles, f.tentacles, f.spacing, mesh);
        });
      return valid;
    }),
                  error);
  }

  void submit(engine::FrameBatches& frame, const SubmitContext& ctx) override {
    engine::WaterBatch goo;
    goo.method = "mesh";  // the goo is always the marching-slices mesh (its skin needs vertices)
    goo.style = engine::FluidStyle::goo;
    goo.visible = state.params.visible;
    // Caught: the goo pulses red while the caught effect plays.
    const float flash = state.caught_timer > 0.0f ? 0.5f + 0.5f * std::cos(12.0f * state.caught_timer) : 0.0f;
    goo.goo_colour = glm::mix(state.params.colour, glm::vec3(0.9f, 0.1f, 0.08f), flash);
    goo.positions = state.job.mesh.positions;
    goo.normals = state.job.mesh.normals;
    goo.indices = state.job.mesh.indices;
    // The tentacles' skin at the (u, v) the tentacle policy put on each vertex (prepareFrame).
    goo.attributes = state.job.mesh.attributes;
    goo.goo_texture = &ctx.assets.blob_tentacle;
    goo.particles = state.world.particles.position;
    goo.rc = state.params.smoothing * state.params.spacing;
    goo.threshold = state.params.threshold;
    frame.water.push_back(goo);
    if (state.tint.a > frame.screen_tint.a) frame.screen_tint = state.tint;
  }

  HudText hud() const override {
    const BlobMonster& s = state;
    char line[96], banner[96];
    std::snprintf(line, sizeof line, "round %d | %.1f s | caught %d", s.round, s.round_seconds, s.catches);
    if (s.caught_timer <= 0.0f) return {line, {}};
    std::snprintf(banner, sizeof banner, "CAUGHT! round %d lasted %.1f s", s.round, s.last_round_seconds);
    return {line, banner};
  }

  void drawStatus() const override {
    const BlobMonster& s = state;
    const char* current = s.machine.state >= 0 ? s.program.states[s.machine.state].name.c_str() : "(not started)";
    ImGui::Text("blob: state %s (%s) %.1f s, %zu particles, caught %d, step %.2f ms, %llu triangles", current,
                s.machine.state >= 0 ? fluid::blobBehaviourName(s.program.states[s.machine.state].behaviour.kind) : "-",
                s.machine.time_in_state, s.world.particles.size(), s.catches, s.stats.step_ms,
                static_cast<unsigned long long>(s.job.mesh.stats.triangles));
    // Trigger any state of the program now (as if one of its triggers fired); the current state's
    // button is lit, and the buttons wrap onto new lines in a narrow panel.
    const float right = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
    for (std::size_t k = 0; k < s.program.states.size(); ++k) {
      const char* name = s.program.states[k].name.c_str();
      const float width = ImGui::CalcTextSize(name).x + 2.0f * ImGui::GetStyle().FramePadding.x;
      if (k > 0 && ImGui::GetItemRectMax().x + ImGui::GetStyle().ItemSpacing.x + width <= right) ImGui::SameLine();
      const bool lit = static_cast<int>(k) == s.machine.state;
      if (lit) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.85f, 0.45f, 0.10f, 1.0f));
      if (ImGui::SmallButton(name)) requested_state_ = static_cast<int>(k);
      if (lit) ImGui::PopStyleColor();
    }
  }

 private:
  static bool meshed(const fluid::SurfaceStatus& st, std::string& error) {
    if (st.ok()) return true;
    error = "blob: " + st.error;
    return false;
  }

  void stepRound(BlobMonster& s, const StepContext& ctx) {
    const float dt = static_cast<float>(ctx.step_seconds);
    if (s.caught_timer > 0.0f) {
      s.caught_timer -= dt;
      s.caught_elapsed += dt;
      if (s.caught_timer <= 0.0f) {
        s.caught_timer = 0.0f;
        s.tint = glm::vec4(0.0f);
        ++s.round;
        s.round_seconds = 0.0;
        startRound(s);
        ctx.links.reset_player = true;
        return;
      }
      grab(s, ctx.links);
      return;
    }
    s.round_seconds += ctx.step_seconds;
    const fluid::BlobBehaviour& b = s.program.states[s.machine.state].behaviour;
    if (b.kind == fluid::BlobBehaviourKind::chase && fluid::blobGoalReached(s.world, b, s.target)) {
      ++s.catches;
      s.last_round_seconds = s.round_seconds;
      s.caught_timer = std::max(s.params.caught_seconds, dt);
      s.caught_elapsed = 0.0f;
      grab(s, ctx.links);
    }
  }

  // The catch as the player sees it: the goo grabs the camera and pulls it in, down to kHold from its
  // centre and kElevation above it on the player's side, turning it to face the goo (the catch
  // happened at the player's feet, below the view), and the screen goes goo-dark. Close enough that
  // the body and its tentacles fill the view, far enough that it is seen as a body, not a green wall.
  static void grab(BlobMonster& s, EffectLinks& links) {
    constexpr float kHold = 1.1f;        // m from the goo's centroid
    constexpr float kElevation = 0.52f;  // rad (30 degrees) above it
    constexpr float kRate = 0.08f;       // of the remaining way per step: 92 % of it in half a second at 60 Hz
    const glm::vec3 centre = fluid::blobCentroid(s.world.particles.position);
    glm::vec3 away(links.player.x - centre.x, 0.0f, links.player.z - centre.z);
    const float len = glm::length(away);
    away = len > 1e-4f && std::isfinite(len) ? away / len : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 hold = centre + kHold * (std::cos(kElevation) * away + glm::vec3(0.0f, std::sin(kElevation), 0.0f));
    links.camera_pull = {hold, centre, kRate};
    const float ramp = std::min(1.0f, s.caught_elapsed / 0.4f);
    s.tint = glm::vec4(0.45f * s.params.colour, 0.55f * ramp);
  }

  RigidBodies* bodies_;
  double step_seconds_;
  mutable int requested_state_ = -1;  // set by the overlay's buttons (drawStatus), applied at the next step
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& error) {
  const double step_seconds = 1.0 / ctx.scene.scene.number("step_hz");
  auto effect = std::make_unique<BlobEffect>(ctx.links.bodies, step_seconds);
  BlobMonster& s = effect->state;
  s.params = table().parse(section);
  deriveBody(s.params, ctx.links.gravity, step_seconds, s.world.params);
  s.world.params.seed = ctx.seed;
  // The monster hunts in the player's street: its chase keeps inside the camera's bounds (the
  // level's edges, camera.bounds_min/max), so it never follows the player over the level's edge.
  s.world.keep_min = ctx.scene.camera.vec3("bounds_min");
  s.world.keep_max = ctx.scene.camera.vec3("bounds_max");
  if (const fluid::BlobStatus st = fluid::validateBlobParams(s.world.params); !st.ok()) {
    error = "blob: " + st.error;
    return nullptr;
  }
  // The level's depth-map colliders, baked from the models the renderer draws (re-baked when stale).
  const std::string level = ctx.scene.scene.text("level");
  std::vector<fluid::CachedCollider> parts;
  const fluid::CacheStatus cache =
      fluid::loadLevelColliders(ctx.content_dir, level, colliderModelLoader(), fluid::CachePolicy::load_or_bake, parts);
  if (!cache.ok()) {
    error = "blob: level " + level + ": " + cache.error;
    return nullptr;
  }
  std::vector<std::string> walls;
  for (fluid::CachedCollider& part : parts) {
    fluid::BlobCollider c;
    c.level = true;  // resolved after the crates (BlobCollider)
    auto shape = std::make_shared<fluid::DepthMapCollider>(std::move(part.collider));
    fluid::blobDepthMapBounds(c, *shape);  // particles far from it skip its queries
    c.shape = std::move(shape);
    s.world.colliders.push_back(std::move(c));
    walls.push_back(part.name);
  }
  s.level_colliders = s.world.colliders.size();
  if (!loadBlobProgram(ctx.content_dir / s.params.program, s.world.params, walls, s.program, error)) return nullptr;
  if (const fluid::BlobStatus st = fluid::initBlob(s.world, s.params.grate); !st.ok()) {
    error = "blob: " + st.error;
    return nullptr;
  }
  s.start_column =
      fluid::blobColumn(s.world.params, s.params.grate - glm::vec3(0.0f, s.params.spacing, 0.0f), s.params.pipe_radius);
  startRound(s);
  ctx.links.blob = &s.world;  // the audio effect hears the goo's impacts
  return effect;
}

using enum ColumnFormat;
constexpr ColumnSpec kColumns[] = {
    {"triangles", count, "triangles of the meshed surfaces (the water's and the goo's)"},
    {"mesh_worker_ms", milliseconds,
     "the asynchronous meshing worker's time for the surfaces drawn (meshing_ms is then the main thread's wait)"},
};

}  // namespace

const EffectDesc& blobEffect() {
  static const EffectDesc desc{"blob",
                               "the blob monster (marching slices paper §7): a particle body run by a behaviour "
                               "program, colliding with the level's baked colliders and the crates, meshed as goo",
                               table().specs,
                               {},
                               &build,
                               kColumns};
  return desc;
}

}  // namespace game
