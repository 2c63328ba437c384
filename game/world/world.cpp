#include "game/world/world.hpp"

#include "game/explosives/explosives.hpp"
#include "game/scene/camera_params.hpp"

#include <algorithm>
#include <cmath>

namespace game {
namespace {

void applyCamera(const SectionConfig& section, engine::FpsCamera& camera, bool include_pose) {
  const engine::FpsCamera fresh = cameraParamTable().parse(section);
  if (include_pose) {
    camera.position = fresh.position;
    camera.yaw_degrees = fresh.yaw_degrees;
    camera.pitch_degrees = fresh.pitch_degrees;
  }
  camera.fov_degrees = fresh.fov_degrees;
  camera.move_speed = fresh.move_speed;
  camera.bounds_min = fresh.bounds_min;
  camera.bounds_max = fresh.bounds_max;
}

// The camera's box must hold its start position (so the first frame does not snap it).
bool checkCameraBounds(const SceneConfig& scene, std::string& error) {
  const glm::vec3 lo = scene.camera.vec3("bounds_min"), hi = scene.camera.vec3("bounds_max");
  const glm::vec3 start = scene.camera.vec3("position");
  for (int axis = 0; axis < 3; ++axis) {
    if (lo[axis] <= start[axis] && start[axis] <= hi[axis]) continue;
    const std::string file = scene.source.empty() ? scene.name : scene.source.string();
    error = file + ": camera.position's " + "xyz"[axis] + " = " + std::to_string(start[axis]) +
            " is outside camera.bounds_min .. bounds_max (" + std::to_string(lo[axis]) + " .. " +
            std::to_string(hi[axis]) + ")";
    return false;
  }
  return true;
}

// Every effect listed must find the effects it needs listed too.
bool checkNeeds(const SceneConfig& scene, std::string& error) {
  for (const EffectDesc* desc : effectRegistry()) {
    if (!scene.has(desc->name)) continue;
    for (std::string_view need : desc->needs) {
      if (scene.has(need)) continue;
      const std::string file = scene.source.empty() ? scene.name : scene.source.string();
      const std::string name(desc->name), needed(need);
      error = file + ": effect " + name + " requires effect " + needed + " (list " + needed + " too, or remove " +
              name + ")";
      return false;
    }
  }
  return true;
}

// An effect grabbed the player this step (EffectLinks::camera_pull): move the camera its share of
// the way and turn it by the same share toward what grabbed it, then let go until the next step.
void applyCameraPull(EffectLinks::CameraPull& pull, engine::FpsCamera& camera) {
  if (!(pull.rate > 0.0f)) return;
  const float r = std::min(pull.rate, 1.0f);
  camera.position += (pull.toward - camera.position) * r;
  const glm::vec3 to = pull.look_at - camera.position;
  const float len = glm::length(to);
  if (len > 1e-4f && std::isfinite(len)) {  // yaw and pitch as engine::cameraForward reads them
    const float yaw = glm::degrees(std::atan2(to.z, to.x));
    const float pitch = std::clamp(glm::degrees(std::asin(std::clamp(to.y / len, -1.0f, 1.0f))), -89.0f, 89.0f);
    camera.yaw_degrees =
        std::remainder(camera.yaw_degrees + r * std::remainder(yaw - camera.yaw_degrees, 360.0f), 360.0f);
    camera.pitch_degrees += r * (pitch - camera.pitch_degrees);
  }
  pull.rate = 0.0f;
}

}  // namespace

glm::vec3 sceneGravity(const SceneConfig& scene) {
  // Particles fall with the rigid bodies' gravity when that effect is present.
  if (const SectionConfig* rigid = scene.effect("rigid_bodies")) return rigid->vec3("gravity");
  return EffectLinks{}.gravity;
}

bool buildWorld(const SceneConfig& scene, const std::filesystem::path& content_dir, World& out, std::string& error) {
  out = World{};
  out.scene = scene;
  out.step_seconds = 1.0 / scene.scene.number("step_hz");
  out.substeps = scene.scene.integer("substeps");
  out.links.level = FountainGeometry{};
  applyCamera(scene.camera, out.camera, true);
  if (!checkNeeds(scene, error) || !checkCameraBounds(scene, error)) return false;
  // Effects are built in registry order; anything not listed is simply never touched.
  BuildContext context{scene, content_dir, static_cast<std::uint32_t>(scene.scene.integer("seed")), out.links};
  for (const EffectDesc* desc : effectRegistry()) {
    const SectionConfig* section = scene.effect(desc->name);
    if (section == nullptr) continue;
    std::unique_ptr<Effect> effect = desc->build(*section, context, error);
    if (!effect) return false;
    out.effects.push_back(std::move(effect));
    out.systems.emplace_back(desc->name);
  }
  return true;
}

void attachWorldGpu(World& world, const std::filesystem::path& shader_dir, const std::filesystem::path& content_dir) {
  const GpuContext gpu{shader_dir, content_dir, world.step_seconds};
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->attachGpu(gpu);
}

void detachWorldGpu(World& world) {
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->detachGpu();
}

void applyLiveParams(World& world) {
  applyCamera(world.scene.camera, world.camera, false);
  for (const std::unique_ptr<Effect>& effect : world.effects)
    if (const SectionConfig* section = world.scene.effect(effect->name())) effect->applyLive(*section, world.links);
}

void recordFailure(World& world, const std::string& what) {
  const std::string text = what + " at step " + std::to_string(world.steps);
  if (world.failures.count++ == 0) world.failures.first = text;
  world.failures.last = text;
}

void stepWorld(World& world, engine::Profiler* profiler) {
  const StepContext context{world.step_seconds, world.substeps, profiler, world.links};
  world.links.player = world.camera.position;
  for (const std::unique_ptr<Effect>& effect : world.effects) {
    const StepOutcome outcome = effect->step(context);
    if (!outcome.failure.empty()) recordFailure(world, outcome.failure);
  }
  applyCameraPull(world.links.camera_pull, world.camera);
  if (world.links.reset_player) applyCamera(world.scene.camera, world.camera, true);  // caught: a new round
  world.links.reset_player = false;
  ++world.steps;
  if (!world.nonfinite_state.empty()) return;
  for (const std::unique_ptr<Effect>& effect : world.effects) {
    const std::string bad = effect->findNonFinite();
    if (bad.empty()) continue;
    world.nonfinite_state = bad + " at step " + std::to_string(world.steps);
    return;
  }
}

void meshWorld(World& world, engine::Profiler* profiler) {
  const FrameContext frame{world.camera.position, engine::cameraForward(world.camera), profiler, world.player_aiming};
  std::string error;
  for (const std::unique_ptr<Effect>& effect : world.effects)
    if (!effect->prepareFrame(frame, error)) recordFailure(world, error);
}

void readWorldRenderStats(World& world, std::span<const engine::WaterStats> water) {
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->readRenderStats(water);
}

void submitWorld(World& world, engine::FrameBatches& frame, const LevelAssets& assets, float alpha) {
  const SubmitContext context{assets, alpha};
  for (const std::unique_ptr<Effect>& effect : world.effects) effect->submit(frame, context);
}

void playerThrowExplosive(World& world) {
  if (world.links.explosives == nullptr || world.links.bodies == nullptr) return;
  const glm::vec3 forward = engine::cameraForward(world.camera);
  throwExplosive(*world.links.explosives, *world.links.bodies->physics, throwOrigin(world.camera.position, forward),
                 forward);
}

void playerThrow(World& world) {
  if (world.links.bodies == nullptr) return;
  throwCrate(*world.links.bodies, world.camera.position, engine::cameraForward(world.camera));
}

}  // namespace game
