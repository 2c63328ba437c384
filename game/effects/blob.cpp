// The `blob` effect: the marching-slices paper's second demo (Rosenberg & Birdwell 2008, §7 and
// Figure 8), an amorphous particle monster that emerges from a sewer, forms a ball, grows textured
// tentacles, coats a wall, chases the player and reassembles after explosives. The body and the
// behaviours are fluid/blob; this file builds them from the scene, runs the behaviour program (scene
// data: a JSON file the section names), collides the body with the level's baked depth-map colliders
// and the crates (both ways), applies this step's blasts, catches the player, and meshes the body per
// frame through marching slices with the tentacle texturing policy. State: game/world/blob_monster.hpp.
#include "game/world/blob_monster.hpp"

#include "engine/physics/physics_world.hpp"
#include "engine/render/frame.hpp"
#include "fluid/blob/tentacle_uv.hpp"
#include "fluid/collide/collider_cache.hpp"
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/surface/marching_slices_policy.hpp"
#include "game/world/collider_model.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/world/level_assets.hpp"
#include "game/world/rigid_bodies.hpp"

#include <imgui.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace game {
namespace {

using Json = nlohmann::json;

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

// ---- The behaviour program file ----------------------------------------------------------------

struct ProgramReader {
  std::string file;
  std::string error;

  bool fail(const std::string& path, const Json& value, const std::string& why) {
    if (error.empty()) error = file + ": " + path + " = " + value.dump() + ": " + why;
    return false;
  }
  bool number(const Json& v, const std::string& path, float& out) {
    if (!v.is_number()) return fail(path, v, "expected a number");
    out = v.get<float>();
    if (!std::isfinite(out)) return fail(path, v, "not finite");
    return true;
  }
  bool integer(const Json& v, const std::string& path, int& out) {
    if (!v.is_number_integer()) return fail(path, v, "expected an integer");
    out = v.get<int>();
    return true;
  }
  bool vec3(const Json& v, const std::string& path, glm::vec3& out) {
    if (!v.is_array() || v.size() != 3) return fail(path, v, "expected [x, y, z]");
    for (int k = 0; k < 3; ++k)
      if (!number(v[k], path + "[" + std::to_string(k) + "]", out[k])) return false;
    return true;
  }
  bool text(const Json& v, const std::string& path, std::string& out) {
    if (!v.is_string()) return fail(path, v, "expected a string");
    out = v.get<std::string>();
    return true;
  }

  // One behaviour's keys besides name/behaviour/triggers; `walls` names the level's colliders
  // (the coat_wall `wall` key resolves to its index).
  bool behaviourKey(const std::string& key, const Json& v, const std::string& path, fluid::BlobBehaviour& b,
                    const std::vector<std::string>& walls) {
    if (key == "point") return vec3(v, path, b.point);
    if (key == "height") return number(v, path, b.height);
    if (key == "speed") return number(v, path, b.speed);
    if (key == "weight") return number(v, path, b.weight);
    if (key == "tentacles") return integer(v, path, b.tentacles);
    if (key == "tentacle_particles") return integer(v, path, b.tentacle_particles);
    if (key == "tentacle_length") return number(v, path, b.tentacle_length);
    if (key == "tentacle_spread") return number(v, path, b.tentacle_spread);
    if (key == "tip_strength") return number(v, path, b.tip_strength);
    if (key == "tip_radius_scale") return number(v, path, b.tip_radius_scale);
    if (key == "catch_distance") return number(v, path, b.catch_distance);
    if (key == "reach_range") return number(v, path, b.reach_range);
    if (key == "grow_speed") return number(v, path, b.grow_speed);
    if (key == "curl") return number(v, path, b.curl);
    if (key == "stretch") return number(v, path, b.stretch);
    if (key == "wall") {
      std::string name;
      if (!text(v, path, name)) return false;
      for (std::size_t i = 0; i < walls.size(); ++i)
        if (walls[i] == name) b.wall_collider = static_cast<int>(i);
      if (b.wall_collider < 0) return fail(path, v, "not a collider of the level (its .colliders file)");
      return true;
    }
    return fail(path, v, "unknown key");
  }

  bool trigger(const Json& t, const std::string& path, fluid::BlobTrigger& out) {
    if (!t.is_object()) return fail(path, t, "expected an object {\"when\": ..., \"next\": ...}");
    for (const auto& [key, v] : t.items()) {
      const std::string at = path + "." + key;
      if (key == "when") {
        std::string name;
        if (!text(v, at, name)) return false;
        if (!fluid::parseBlobTrigger(name, out.kind))
          return fail(at, v,
                      "unknown trigger (after_seconds, goal_reached, target_within, target_beyond, blasted, event)");
      } else if (key == "value") {
        if (!number(v, at, out.value)) return false;
      } else if (key == "event") {
        if (!text(v, at, out.event)) return false;
      } else if (key == "next") {
        if (!text(v, at, out.next)) return false;
      } else {
        return fail(at, v, "unknown key (when, value, event, next)");
      }
    }
    if (!t.contains("when")) return fail(path, t, "missing \"when\"");
    if (!t.contains("next")) return fail(path, t, "missing \"next\"");
    return true;
  }

  bool state(const Json& s, const std::string& path, fluid::BlobState& out, const std::vector<std::string>& walls) {
    if (!s.is_object()) return fail(path, s, "expected an object");
    if (!s.contains("name")) return fail(path, s, "missing \"name\"");
    if (!s.contains("behaviour")) return fail(path, s, "missing \"behaviour\"");
    for (const auto& [key, v] : s.items()) {
      const std::string at = path + "." + key;
      if (key == "name") {
        if (!text(v, at, out.name)) return false;
      } else if (key == "behaviour") {
        std::string name;
        if (!text(v, at, name)) return false;
        if (!fluid::parseBlobBehaviour(name, out.behaviour.kind))
          return fail(at, v, "unknown behaviour (idle, emerge, ball, tentacles, coat_wall, chase, reassemble)");
      } else if (key == "triggers") {
        if (!v.is_array()) return fail(at, v, "expected an array");
        for (std::size_t k = 0; k < v.size(); ++k) {
          out.triggers.emplace_back();
          if (!trigger(v[k], at + "[" + std::to_string(k) + "]", out.triggers.back())) return false;
        }
      } else if (!behaviourKey(key, v, at, out.behaviour, walls)) {
        return false;
      }
    }
    return true;
  }

  bool program(const std::string& text_in, fluid::BlobProgram& out, const std::vector<std::string>& walls) {
    Json root;
    try {
      root = Json::parse(text_in);
    } catch (const Json::parse_error& e) {
      error = file + ": invalid JSON: " + e.what();
      return false;
    }
    if (!root.is_object()) return fail("(top level)", root, "expected an object with \"states\"");
    for (const auto& [key, v] : root.items()) {
      if (key == "initial") {
        if (!text(v, key, out.initial)) return false;
      } else if (key == "description") {
        continue;
      } else if (key == "states") {
        if (!v.is_array() || v.empty()) return fail(key, v, "expected a non-empty array of states");
        for (std::size_t k = 0; k < v.size(); ++k) {
          out.states.emplace_back();
          if (!state(v[k], "states[" + std::to_string(k) + "]", out.states.back(), walls)) return false;
        }
      } else {
        return fail(key, v, "unknown key (description, initial, states)");
      }
    }
    if (out.states.empty()) return fail("(top level)", root, "missing \"states\"");
    return true;
  }
};

// Reads and validates the program; errors name the file, the key path and the value.
bool loadBlobProgram(const std::filesystem::path& path, const fluid::BlobParams& params,
                     const std::vector<std::string>& walls, fluid::BlobProgram& out, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = "blob.program: cannot read " + path.string();
    return false;
  }
  std::stringstream text;
  text << in.rdbuf();
  ProgramReader reader{path.string(), {}};
  if (!reader.program(text.str(), out, walls)) {
    error = "blob.program: " + reader.error;
    return false;
  }
  const fluid::BlobStatus st = fluid::validateBlobProgram(out, params);
  if (!st.ok()) {
    error = "blob.program: " + path.string() + ": " + st.error;
    return false;
  }
  return true;
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

void toSoa(const std::vector<glm::vec3>& x, std::vector<float>& xs, std::vector<float>& ys, std::vector<float>& zs) {
  xs.resize(x.size()), ys.resize(x.size()), zs.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) xs[i] = x[i].x, ys[i] = x[i].y, zs[i] = x[i].z;
}

fluid::SurfaceInput inputOf(const BlobMeshFrame& f) {
  return {f.xs, f.ys, f.zs, f.particles.strength, f.particles.radius_scale, {}};
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

// Crates near the body become colliders after the level's (Bullet pose and velocity: a thrown
// crate dents the blob); the start of the list is the level, fixed at build and marked `level`, so
// stepBlob resolves the crates first and a particle a crate presses into a wall ends outside it.
void collidersFromCrates(BlobMonster& s, const RigidBodies& bodies) {
  s.world.colliders.resize(s.level_colliders);
  s.crate_of_collider.clear();
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& x : s.world.particles.position) lo = glm::min(lo, x), hi = glm::max(hi, x);
  const float half = 0.5f * bodies.params.crate_size;
  const float reach = std::sqrt(3.0f) * half + s.params.spacing;
  if (!s.crate_shape) s.crate_shape = std::make_shared<fluid::BoxShape>(glm::vec3(half));
  for (std::size_t k = 0; k < bodies.crates.size(); ++k) {
    const engine::BodyState& b = bodies.current[k];
    if (glm::any(glm::lessThan(b.position, lo - reach)) || glm::any(glm::greaterThan(b.position, hi + reach))) continue;
    fluid::BlobCollider c;
    c.shape = s.crate_shape;
    c.pose = engine::colliderPoseOf(b);  // box centre = centre of mass
    s.world.colliders.push_back(c);
    s.crate_of_collider.push_back(static_cast<int>(k));
  }
}

// The momentum the particles lost to each crate, as a force and torque over the next physics step.
// Stability guard, as the water's (game/world/body_fluid_coupling.hpp): within one step the crate is
// a kinematic collider, so a falling crate drags every particle it meets to its own speed and the
// momentum handed back can exceed what the crate brought (measured: 1,266 N s in 3 steps on a 54 kg
// crate dropped 2.5 m, which Bullet fires away upward). The force is capped at kForceLimit times the
// buoyancy of the fully submerged crate (rho |g| V), the torque at that force times the half diagonal.
constexpr float kForceLimit = 3.0f;
void impulsesToCrates(BlobMonster& s, RigidBodies& bodies, double step_seconds) {
  const float inv_dt = static_cast<float>(1.0 / step_seconds);
  const float edge = bodies.params.crate_size;
  const float max_force =
      kForceLimit * s.world.params.density * glm::length(s.world.params.gravity) * edge * edge * edge;
  const float max_torque = max_force * 0.5f * std::sqrt(3.0f) * edge;
  for (std::size_t k = 0; k < s.crate_of_collider.size(); ++k) {
    const fluid::BlobCollider& c = s.world.colliders[s.level_colliders + k];
    const engine::BodyId id = bodies.crates[static_cast<std::size_t>(s.crate_of_collider[k])];
    glm::vec3 force = c.impulse * inv_dt, torque = c.angular_impulse * inv_dt;
    const float f = glm::length(force), t = glm::length(torque);
    if (f > max_force) force *= max_force / f;
    if (t > max_torque) torque *= max_torque / t;
    s.crate_forces_capped += (f > max_force || t > max_torque) ? 1u : 0u;
    engine::setExternalForce(*bodies.physics, id, force, torque);
  }
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
    if (bodies_ != nullptr) collidersFromCrates(s, *bodies_);
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
    if (bodies_ != nullptr) impulsesToCrates(s, *bodies_, ctx.step_seconds);
    stepRound(s, ctx);
    return {};
  }

  void reportColumns(FrameColumns& row) const override {
    row.add("triangles", static_cast<double>(state.mesh.indices.size() / 3));
    row.add("mesh_worker_ms", state.mesh_worker_ms);
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
    if (!s.params.async) {
      s.async_job.reset();
      s.mesh_worker_ms = 0.0;
      toSoa(s.world.particles.position, s.xs, s.ys, s.zs);
      const fluid::SurfaceInput in{s.xs, s.ys, s.zs, s.world.particles.strength, s.world.particles.radius_scale, {}};
      return meshed(meshBlob(s.extractor, in, sp, s.world.particles, s.world.target.tentacle_particles,
                             s.world.params.spacing, s.mesh),
                    error);
    }
    if (!s.async_job) s.async_job = std::make_unique<BlobMonster::MeshJob>();
    fluid::AsyncSurfaceExtractor& worker = s.async_job->worker;
    BlobMeshFrame& f = s.async_job->frame;
    // The job in flight meshed the previous frame's copy: collect it, then the copy is ours again.
    const bool in_flight = worker.pending();
    fluid::SurfaceStatus st;
    if (in_flight) st = worker.collect(s.mesh), s.mesh_worker_ms = worker.lastJobMs();
    f.particles = s.world.particles;  // copy-assigned: no allocation once the vectors have grown
    f.tentacles = s.world.target.tentacle_particles;
    f.spacing = s.world.params.spacing;
    f.params = sp;
    toSoa(f.particles.position, f.xs, f.ys, f.zs);
    // Refused input is reported in its own frame and starts no job; the next good frame waits for
    // its own surface, like the first.
    if (const fluid::SurfaceStatus valid = fluid::validateSurface(inputOf(f), sp); !valid.ok())
      return meshed(valid, error);
    const auto job = [&f](fluid::SurfaceExtractor& extractor, fluid::SurfaceMesh& mesh) {
      return meshBlob(extractor, inputOf(f), f.params, f.particles, f.tentacles, f.spacing, mesh);
    };
    if (!in_flight) {  // first frame: this frame's own surface, waited for
      worker.startJob(job);
      st = worker.collect(s.mesh);
      s.mesh_worker_ms = worker.lastJobMs();
    }
    worker.startJob(job);
    return meshed(st, error);
  }

  void submit(engine::FrameBatches& frame, const SubmitContext& ctx) override {
    engine::WaterBatch goo;
    goo.method = "mesh";  // the goo is always the marching-slices mesh (its skin needs vertices)
    goo.style = engine::FluidStyle::goo;
    goo.visible = state.params.visible;
    // Caught: the goo pulses red while the caught effect plays.
    const float flash = state.caught_timer > 0.0f ? 0.5f + 0.5f * std::cos(12.0f * state.caught_timer) : 0.0f;
    goo.goo_colour = glm::mix(state.params.colour, glm::vec3(0.9f, 0.1f, 0.08f), flash);
    goo.positions = state.mesh.positions;
    goo.normals = state.mesh.normals;
    goo.indices = state.mesh.indices;
    // The tentacles' skin at the (u, v) the tentacle policy put on each vertex (prepareFrame).
    goo.attributes = state.mesh.attributes;
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
                static_cast<unsigned long long>(s.mesh.stats.triangles));
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
  bool meshed(const fluid::SurfaceStatus& st, std::string& error) {
    if (st.ok()) return true;
    state.mesh.clear();
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
