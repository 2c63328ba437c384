#include "game/world/rigid_bodies.hpp"

#include "game/world/level.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace game {
namespace {

float uniform01(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

}  // namespace

bool buildRigidBodies(const RigidBodyParams& params, const std::filesystem::path& content_dir, std::uint32_t seed,
                      RigidBodies& out, std::string& error) {
  out = RigidBodies{};
  out.params = params;
  const std::span<const LevelModelDesc> models = levelModels(params.level);
  if (models.empty()) {
    error = "scene.level = \"" + params.level + "\": no such level";
    return false;
  }
  out.physics = engine::createPhysicsWorld({params.gravity});
  engine::PhysicsWorld& world = *out.physics;
  engine::addStaticPlane(world, {0.0f, 1.0f, 0.0f}, 0.0f);
  engine::BodyDesc stone;
  stone.friction = 0.7f;
  for (const LevelModelDesc& model : models) {  // the level's solid models (the fountain: basin, statue)
    if (!model.solid) continue;
    engine::MeshData mesh;
    if (!engine::loadMesh(content_dir / "models" / model.file, mesh, error)) return false;
    if (engine::addStaticTriangleMesh(world, stone, mesh, error) < 0) {
      error = params.level + " collision mesh " + model.file + ": " + error;
      return false;
    }
  }

  // Stacks of up to three crates on a ring outside the basin, placed by the scene's seed.
  std::mt19937 rng(seed);
  const float size = params.crate_size;
  const float mass = params.density * size * size * size;
  const int stacks = (params.crates + 2) / 3;
  const float base_angle = 2.0f * std::numbers::pi_v<float> * uniform01(rng);
  for (int i = 0; i < params.crates; ++i) {
    const int stack = i % std::max(stacks, 1);
    const int level = i / std::max(stacks, 1);
    const float angle = base_angle + 2.0f * std::numbers::pi_v<float> *
                                         (static_cast<float>(stack) + 0.3f * uniform01(rng)) /
                                         static_cast<float>(std::max(stacks, 1));
    const float radius = 4.6f + 1.4f * uniform01(rng) * (level == 0 ? 1.0f : 0.0f);
    engine::BodyDesc desc;
    desc.mass = mass;
    desc.position = glm::vec3(std::cos(angle) * radius, size * (0.5f + static_cast<float>(level)) + 0.01f,
                              std::sin(angle) * radius);
    if (level > 0) {
      // Stack on the one below: same stack's base position.
      const engine::BodyState below = engine::bodyState(world, out.crates[static_cast<std::size_t>(i - stacks)]);
      desc.position.x = below.position.x + (uniform01(rng) - 0.5f) * 0.1f * size;
      desc.position.z = below.position.z + (uniform01(rng) - 0.5f) * 0.1f * size;
    }
    desc.rotation = glm::angleAxis(2.0f * std::numbers::pi_v<float> * uniform01(rng), glm::vec3(0, 1, 0));
    desc.friction = 0.8f;
    desc.restitution = 0.05f;
    out.crates.push_back(engine::addBox(world, desc, glm::vec3(0.5f * size)));
  }
  out.crates.reserve(out.crates.size() + RigidBodies::kMaxThrown);
  out.previous.reserve(out.crates.size() + RigidBodies::kMaxThrown);
  out.current.reserve(out.crates.size() + RigidBodies::kMaxThrown);
  for (engine::BodyId id : out.crates) out.current.push_back(engine::bodyState(world, id));
  out.previous = out.current;
  return true;
}

void throwCrate(RigidBodies& bodies, glm::vec3 origin, glm::vec3 direction) {
  const float length = glm::length(direction);
  if (!(length > 1e-6f) || !std::isfinite(length)) return;
  direction /= length;
  engine::BodyState state;
  state.position = origin + direction * (0.6f + bodies.params.crate_size);
  state.rotation =
      glm::angleAxis(0.3f * static_cast<float>(bodies.thrown), glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)));
  state.linear_velocity = direction * bodies.params.throw_speed;
  state.angular_velocity = glm::vec3(1.5f, 0.7f, -1.0f);
  const std::size_t stacked =
      bodies.crates.size() - static_cast<std::size_t>(std::min(bodies.thrown, RigidBodies::kMaxThrown));
  if (bodies.thrown < RigidBodies::kMaxThrown) {
    const float size = bodies.params.crate_size;
    engine::BodyDesc desc;
    desc.mass = bodies.params.density * size * size * size;
    desc.position = state.position;
    desc.rotation = state.rotation;
    desc.linear_velocity = state.linear_velocity;
    desc.angular_velocity = state.angular_velocity;
    desc.friction = 0.8f;
    desc.restitution = 0.05f;
    bodies.crates.push_back(engine::addBox(*bodies.physics, desc, glm::vec3(0.5f * size)));
    bodies.current.push_back(state);
    bodies.previous.push_back(state);
  } else {
    // Recycle the oldest thrown crate.
    const std::size_t slot = stacked + static_cast<std::size_t>(bodies.thrown % RigidBodies::kMaxThrown);
    engine::resetBody(*bodies.physics, bodies.crates[slot], state);
    bodies.current[slot] = state;
    bodies.previous[slot] = state;
  }
  ++bodies.thrown;
}

void stepRigidBodies(RigidBodies& bodies, double step_seconds, int substeps) {
  engine::stepPhysics(*bodies.physics, step_seconds, substeps);
  std::swap(bodies.previous, bodies.current);
  for (std::size_t i = 0; i < bodies.crates.size(); ++i) {
    bodies.current[i] = engine::bodyState(*bodies.physics, bodies.crates[i]);
  }
  ++bodies.steps;
}

std::string findNonFiniteBodyState(const RigidBodies& bodies) {
  const engine::BodyId bad = engine::findNonFiniteBody(*bodies.physics);
  if (bad < 0) return {};
  const engine::BodyState state = engine::bodyState(*bodies.physics, bad);
  return "rigid_bodies: body " + std::to_string(bad) + " has a non-finite transform or velocity (position " +
         std::to_string(state.position.x) + ", " + std::to_string(state.position.y) + ", " +
         std::to_string(state.position.z) + ")";
}

}  // namespace game
