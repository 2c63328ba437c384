#include "game/world/world.hpp"

#include <cstdio>
#include <optional>

namespace game {
namespace {

void applyCamera(const SectionConfig& section, engine::FpsCamera& camera, bool include_pose) {
  if (include_pose) {
    camera.position = section.vec3("position");
    camera.yaw_degrees = static_cast<float>(section.number("yaw_degrees"));
    camera.pitch_degrees = static_cast<float>(section.number("pitch_degrees"));
  }
  camera.fov_degrees = static_cast<float>(section.number("fov_degrees"));
  camera.move_speed = static_cast<float>(section.number("move_speed"));
}

}  // namespace

glm::vec3 sceneGravity(const SceneConfig& scene) {
  // Particles fall with the rigid bodies' gravity when that effect is present.
  if (const SectionConfig* rigid = scene.effect("rigid_bodies")) return rigid->vec3("gravity");
  return {0.0f, -9.81f, 0.0f};
}

bool buildWorld(const SceneConfig& scene, const std::filesystem::path& content_dir, World& out, std::string& error) {
  out = World{};
  out.scene = scene;
  out.step_seconds = 1.0 / scene.scene.number("step_hz");
  out.substeps = scene.scene.integer("substeps");
  const auto seed = static_cast<std::uint32_t>(scene.scene.integer("seed"));
  applyCamera(scene.camera, out.camera, true);

  if (scene.has("fluid_surface") && !scene.has("sph_fluid")) {
    const std::string file = scene.source.empty() ? scene.name : scene.source.string();
    error = file + ": effect fluid_surface requires effect sph_fluid (list sph_fluid too, or remove fluid_surface)";
    return false;
  }
  // Effects are built in schema order; anything not listed is simply never touched.
  if (const SectionConfig* section = scene.effect("rigid_bodies")) {
    auto bodies = std::make_unique<RigidBodies>();
    if (!buildRigidBodies(rigidParamsFrom(*section), content_dir, seed, *bodies, error)) {
      error = "rigid_bodies: " + error;
      return false;
    }
    out.rigid_bodies = std::move(bodies);
    out.systems.emplace_back("rigid_bodies");
  }
  if (const SectionConfig* section = scene.effect("sprite_particles")) {
    auto particles = std::make_unique<SpriteParticles>();
    initSpriteParticles(*particles, spriteParamsFrom(*section, sceneGravity(scene), out.fountain.geometry().nozzle),
                        static_cast<std::uint32_t>(section->integer("max_particles")), seed ^ 0x9e3779b9u);
    out.sprite_particles = std::move(particles);
    out.systems.emplace_back("sprite_particles");
  }
  if (const SectionConfig* section = scene.effect("sph_fluid")) {
    SphFluidParams params;
    auto fluid = std::make_unique<SphFluid>();
    if (!sphParamsFrom(*section, params, error) ||
        !initSphFluid(*fluid, params, out.fountain.geometry(), sceneGravity(scene), error)) {
      return false;
    }
    out.sph_fluid = std::move(fluid);
    out.systems.emplace_back("sph_fluid");
    if (out.rigid_bodies && section->boolean("couple_bodies")) {
      // Crates couple while their centre is within a crate's reach of the fluid's grid domain.
      fluid::SphWorld& sph = out.sph_fluid->world;
      const glm::vec3 half(0.5f * out.rigid_bodies->params.crate_size);
      const glm::vec3 reach(glm::length(half));
      out.body_coupling = std::make_unique<BodyFluidCoupling>();
      initBodyFluidCoupling(*out.body_coupling, sph, half, sph.params.domain_min - reach,
                            sph.params.domain_max + reach);
    }
  }
  if (const SectionConfig* section = scene.effect("fluid_surface")) {
    auto surface = std::make_unique<FluidSurface>();
    if (!surfaceParamsFrom(*section, surface->params, error)) return false;
    out.fluid_surface = std::move(surface);
    out.systems.emplace_back("fluid_surface");
  }
  return true;
}

void attachWorldGpu(World& world, const std::filesystem::path& shader_dir, const std::filesystem::path& content_dir) {
  if (!world.sprite_particles) return;
  SpriteParticles& s = *world.sprite_particles;
  if (!attachSpriteGpu(s, shader_dir, content_dir, static_cast<float>(world.step_seconds)))
    std::fprintf(stderr, "fluiddemo: sprite_particles off: %s\n", s.gpu_error.c_str());
}

void detachWorldGpu(World& world) {
  if (world.sprite_particles) detachSpriteGpu(*world.sprite_particles);
}

void applyLiveParams(World& world) {
  applyCamera(world.scene.camera, world.camera, false);
  if (world.rigid_bodies) {
    if (const SectionConfig* section = world.scene.effect("rigid_bodies")) {
      const RigidBodyParams fresh = rigidParamsFrom(*section);
      RigidBodyParams& live = world.rigid_bodies->params;
      if (fresh.gravity != live.gravity) engine::setGravity(*world.rigid_bodies->physics, fresh.gravity);
      live.gravity = fresh.gravity;
      live.throw_speed = fresh.throw_speed;
    }
  }
  if (world.sprite_particles) {
    if (const SectionConfig* section = world.scene.effect("sprite_particles")) {
      world.sprite_particles->params =
          spriteParamsFrom(*section, sceneGravity(world.scene), world.fountain.geometry().nozzle);
    }
  }
  if (world.sph_fluid) {
    SphFluidParams fresh;
    std::string ignored;  // the solver name was validated at construction; it needs a rebuild
    if (const SectionConfig* section = world.scene.effect("sph_fluid");
        section && sphParamsFrom(*section, fresh, ignored)) {
      SphFluid& f = *world.sph_fluid;
      f.params.jet_speed = fresh.jet_speed;
      f.params.rate = fresh.rate;
      f.params.viscosity = fresh.viscosity;
      // Accuracy against time, live: the step bounds and the pressure-solve tolerance.
      f.params.cfl = fresh.cfl;
      f.params.max_time_step = fresh.max_time_step;
      f.params.density_error = fresh.density_error;
      f.params.force_bound = fresh.force_bound;
      f.params.warm_start = fresh.warm_start;
      applySolverKnobs(f.params, f.world.params);
      for (fluid::SphEmitter& e : f.world.emitters) {
        e.speed = fresh.jet_speed;
        e.rate = fresh.rate;
      }
    }
  }
  if (world.fluid_surface) {
    FluidSurfaceParams fresh;
    std::string ignored;  // text edits are not offered by the overlay
    if (const SectionConfig* section = world.scene.effect("fluid_surface");
        section && surfaceParamsFrom(*section, fresh, ignored)) {
      world.fluid_surface->params = fresh;
    }
  }
}

void recordFailure(World& world, const std::string& what) {
  const std::string text = what + " at step " + std::to_string(world.steps);
  if (world.failures.count++ == 0) world.failures.first = text;
  world.failures.last = text;
}

void stepWorld(World& world, engine::Profiler* profiler) {
  if (world.rigid_bodies) {
    std::optional<engine::ScopedPhase> scope;
    if (profiler != nullptr) scope.emplace(*profiler, engine::Phase::physics);
    stepRigidBodies(*world.rigid_bodies, world.step_seconds, world.substeps);
  }
  std::string coupling_error;
  if (world.sph_fluid) {
    std::optional<engine::ScopedPhase> scope;
    if (profiler != nullptr) scope.emplace(*profiler, engine::Phase::fluid);
    // Staggered two-way coupling: the crates as they are after this physics step push the water;
    // the water's push on them acts during the next physics step.
    if (world.body_coupling)
      collidersFromBodies(*world.body_coupling, *world.rigid_bodies->physics, world.rigid_bodies->crates,
                          world.sph_fluid->world);
    const bool was_running = world.sph_fluid->error.empty();
    if (!stepSphFluid(*world.sph_fluid, world.step_seconds) && was_running)
      recordFailure(world, "sph_fluid: " + world.sph_fluid->error + " (the fluid stops stepping)");
    if (world.body_coupling)
      coupling_error = forcesToBodies(*world.body_coupling, world.sph_fluid->world, *world.rigid_bodies->physics);
  }
  // After the water: spray is born from this step's SPH state. GPU work; a no-op while the
  // effect has no GL context (attachWorldGpu), so it only enters the phase when attached.
  if (world.sprite_particles && world.sprite_particles->attached) {
    std::optional<engine::ScopedPhase> scope;
    if (profiler != nullptr) scope.emplace(*profiler, engine::Phase::fluid);
    stepSpriteParticles(*world.sprite_particles, world.sph_fluid.get(), static_cast<float>(world.step_seconds));
  }
  ++world.steps;
  if (world.nonfinite_state.empty()) {
    std::string bad;
    if (world.rigid_bodies) bad = findNonFiniteBodyState(*world.rigid_bodies);
    if (bad.empty() && world.sprite_particles) bad = findNonFiniteSprite(*world.sprite_particles);
    if (bad.empty() && world.sph_fluid) bad = findNonFiniteSph(*world.sph_fluid);
    if (bad.empty()) bad = coupling_error;
    if (!bad.empty()) world.nonfinite_state = bad + " at step " + std::to_string(world.steps);
  }
}

void meshWorld(World& world, engine::Profiler* profiler) {
  if (!world.fluid_surface || !world.sph_fluid) return;
  std::optional<engine::ScopedPhase> scope;
  if (profiler != nullptr) scope.emplace(*profiler, engine::Phase::meshing);
  if (!meshFluidSurface(*world.fluid_surface, *world.sph_fluid, world.camera.position,
                        engine::cameraForward(world.camera)))
    recordFailure(world, world.fluid_surface->error);
}

void playerThrow(World& world) {
  if (!world.rigid_bodies) return;
  throwCrate(*world.rigid_bodies, world.camera.position, engine::cameraForward(world.camera));
}

}  // namespace game
