#pragma once
// The `blob` effect's state (game/effects/blob.cpp): the monster's particle body and behaviour
// machine (fluid/blob), the level's depth-map colliders it slides on, its per-frame surface, and
// the round (catching the player resets it). Readable without a World through findState<BlobMonster>.

#include "fluid/blob/behaviour.hpp"
#include "fluid/blob/blob.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "game/world/surface_job.hpp"

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace game {

struct BlobMonsterParams {
  int particles = 1000;   // fluid::BlobParams::particle_count
  float spacing = 0.08f;  // d (m)
  float cohesion = 4.0f;  // Akinci 2013 cohesion peak (m/s^2)
  float goal_stiffness = 500.0f;
  int substeps = 4;
  glm::vec3 grate{0.0f, 0.0f, 0.0f};                  // top of the sewer pipe (m): the column starts below it
  float pipe_radius = 0.3f;                           // m: radius of the particle column in the pipe
  std::string program = "blob/monster.program.json";  // behaviour program, relative to content/
  float caught_seconds = 2.5f;                        // the caught effect lasts this long, then the round resets
  // Surface (marching slices, paper §7): field cutoff and cube edge in spacings, iso level.
  float smoothing = 2.0f;
  float cube = 0.5f;
  float threshold = 0.2f;
  glm::vec3 colour{0.35f, 0.8f, 0.2f};
  bool visible = true;
  // Mesh frame N on a worker thread while the next steps run (Janisz §3.2.6), drawing the surface
  // of the previous frame's particles; false: mesh before drawing.
  bool async = true;
};

// What the goo's surface reads (prepareFrame): for the async job, a copy taken at the frame it
// belongs to, since the next steps move the particles and change the tentacles while it meshes;
// the synchronous path reads the world's particles in place.
struct BlobMeshFrame {
  fluid::BlobParticles particles;
  std::vector<std::vector<std::uint32_t>> tentacles;  // fluid::BlobTarget::tentacle_particles
  float spacing = 0.0f;
  fluid::SurfaceParams params;
};

struct BlobMonster {
  BlobMonsterParams params;
  fluid::BlobWorld world;
  fluid::BlobProgram program;
  fluid::BlobMachine machine;
  std::vector<glm::vec3> start_column;  // where each round starts: the column in the pipe
  std::size_t level_colliders = 0;      // world.colliders[0, level_colliders) is the level; crates follow
  std::shared_ptr<const fluid::SignedDistanceShape> crate_shape;  // a crate's box (shared by its colliders)
  std::vector<int> crate_of_collider;     // per collider after the level: index into RigidBodies::crates
  std::uint64_t crate_forces_capped = 0;  // crate forces the stability cap shortened (blob_crates.hpp)
  glm::vec3 target{0.0f};                 // what the behaviours aim at this step (the player)
  float caught_timer = 0.0f;              // > 0 while the caught effect plays
  int catches = 0;
  // The rounds (issue 35: the catch is seen): round 1 starts at build, each catch ends one; the
  // time (s, steps x step) the current round has lasted, and what the last caught round lasted.
  int round = 1;
  double round_seconds = 0.0;
  double last_round_seconds = 0.0;
  float caught_elapsed = 0.0f;        // s since the catch, while the caught effect plays
  glm::vec4 tint{0.0f};               // the screen tint this step (engine::FrameBatches::screen_tint)
  std::size_t blasted_particles = 0;  // reached by this step's blasts
  fluid::BlobStepStats stats;
  // Per frame: the surface with the tentacle (u, v) attributes (fluid::BlobTentaclePolicy), meshed
  // by the shared job (game/world/surface_job.hpp). The frame is what the job reads; declared before
  // the job so that it outlives the worker, which waits for its job when destroyed.
  BlobMeshFrame mesh_frame;
  SurfaceJob job;
  std::string error;  // a refused step or mesh (the effect stops stepping on a refused step)
};

}  // namespace game
