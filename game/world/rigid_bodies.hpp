#pragma once
// The `rigid_bodies` effect: a Bullet world holding the static fountain (ground plane, basin
// and statue as triangle meshes loaded from content/models) and dynamic crates: some stacked
// around the fountain at start, more thrown by the player (left click).

#include "engine/assets/assets.hpp"
#include "engine/physics/physics_world.hpp"
#include "game/scene/scene_config.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace game {

struct RigidBodyParams {
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};
  int crates = 6;
  float crate_size = 0.6f;    // edge, m
  float density = 250.0f;     // crate density, kg/m^3 (light wood; water is 1000: above floats, below sinks)
  float throw_speed = 14.0f;  // m/s
  std::string level = "fountain";  // scene.level: its solid models are static Bullet meshes (game/world/level.hpp)
};

// Reads a validated "rigid_bodies" section through the effect's parameter table
// (game/effects/rigid_bodies.cpp). The defaults above are the scene defaults.
RigidBodyParams rigidParamsFrom(const SectionConfig& section);

struct RigidBodies {
  static constexpr int kMaxThrown = 48;  // thrown crates beyond this recycle the oldest

  RigidBodyParams params;
  std::unique_ptr<engine::PhysicsWorld> physics;
  std::vector<engine::BodyId> crates;       // stacked crates first, then thrown ones
  std::vector<engine::BodyState> previous;  // per crate, before the last step
  std::vector<engine::BodyState> current;   // per crate, after the last step
  int thrown = 0;                           // crates thrown so far
  std::uint64_t steps = 0;
};

// Builds the Bullet world; `content_dir` holds models/basin.obj and models/statue.obj.
// On a missing/corrupt model returns false with the loader's message (naming the file).
bool buildRigidBodies(const RigidBodyParams& params, const std::filesystem::path& content_dir, std::uint32_t seed,
                      RigidBodies& out, std::string& error);

// Throws a crate from `origin` along `direction` (normalised here) at params.throw_speed.
void throwCrate(RigidBodies& bodies, glm::vec3 origin, glm::vec3 direction);

// One fixed step of `step_seconds`, in `substeps` Bullet steps.
void stepRigidBodies(RigidBodies& bodies, double step_seconds, int substeps);

// Empty when every body is finite; otherwise names the first bad body.
std::string findNonFiniteBodyState(const RigidBodies& bodies);

}  // namespace game
