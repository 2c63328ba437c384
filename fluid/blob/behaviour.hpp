#pragma once
// fluid/blob behaviours (Rosenberg & Birdwell 2008 §7: "emerging from a sewer, growing tentacles,
// forming a ball, coating a wall, and chasing players", and reassembling after explosives) and the
// data-driven state machine that sequences them. Every behaviour only sets BlobWorld::target (goal
// offsets, weights, anchor): the body reaches it through forces in stepBlob, never by moving
// particles. Programs are plain data (the game parses them from the scene JSON); validate one with
// validateBlobProgram before running it.

#include "fluid/blob/blob.hpp"

#include <glm/glm.hpp>

#include <span>
#include <string>
#include <vector>

namespace fluid {

enum class BlobBehaviourKind { idle, emerge, ball, tentacles, coat_wall, chase, reassemble };

// "idle", "emerge", ...; false for anything else.
bool parseBlobBehaviour(const std::string& name, BlobBehaviourKind& out);
const char* blobBehaviourName(BlobBehaviourKind kind);

// Parameters of one behaviour; each kind reads the fields named in its comment.
struct BlobBehaviour {
  BlobBehaviourKind kind = BlobBehaviourKind::idle;
  // emerge: the grate (top of the pipe); the body rises until its centroid is `height` above it.
  // coat_wall: a point on (or near) the wall to coat; the layer is centred on its projection.
  glm::vec3 point{0.0f};
  float height = 0.0f;  // emerge: m above `point` (0 = the body radius)
  float speed = 1.0f;   // m/s > 0: how fast the anchor moves (emerge rise, chase)
  float weight = 1.0f;  // in [0, 4]: goal spring scale of the behaviour
  // tentacles: count in [1, 16], particles per tentacle in [2, 256], reach (m), cone half-angle
  // (rad) between the tentacles around the direction to the target, and the tip's field strength
  // and radius scale (the paper's radius modulation; 1 at the base).
  int tentacles = 4;
  int tentacle_particles = 30;
  float tentacle_length = 1.5f;
  float tentacle_spread = 0.5f;
  float tip_strength = 0.5f;
  float tip_radius_scale = 0.6f;
  // coat_wall: collider index of the wall (-1 = every collider, the nearest surface wins).
  int wall_collider = -1;
  // chase: horizontal distance (m) from the centroid to the target at which the target counts as
  // caught (the target is the player's eye; the body keeps to the ground below it).
  float catch_distance = 0.8f;
  // Hunting (paper §7: tentacles that reach for the player). tentacles: the tentacles extend
  // while the target is within `reach_range` (m) of the body's anchor and retract to stubs beyond
  // it (0 = always extended). chase: 0 = no tentacles; > 0 grows `tentacles` hunting tentacles
  // that reach for the target within that range. grow_speed (m/s > 0): how fast a tentacle's
  // visible length follows what it wants. curl in [0, 1]: how far a tentacle's tip bends aside, as
  // a fraction of its length (most when retracted, least when reaching), the bend's plane turning
  // about the tentacle's axis over time.
  float reach_range = 0.0f;
  float grow_speed = 2.0f;
  float curl = 0.0f;
  // chase: squash and stretch in [0, 2]. Moving at `speed` the core stretches by 1 + stretch along
  // its heading and shrinks by 1 / sqrt(1 + stretch) across it (volume kept); at rest it relaxes
  // back (time constant 0.15 s). 0 = a rigid shape.
  float stretch = 0.0f;
};

// A transition. `next` names a state; validateBlobProgram resolves it to next_index.
enum class BlobTriggerKind {
  after_seconds,  // time in the state >= value
  goal_reached,   // the behaviour's goal measure is met (blobGoalReached)
  target_within,  // distance centroid -> target < value
  target_beyond,  // distance centroid -> target > value
  blasted,        // a blast reached the body during this step
  event,          // the game raised `event` (a name, e.g. from the F1 overlay)
};
bool parseBlobTrigger(const std::string& name, BlobTriggerKind& out);
const char* blobTriggerName(BlobTriggerKind kind);

struct BlobTrigger {
  BlobTriggerKind kind = BlobTriggerKind::after_seconds;
  float value = 0.0f;
  std::string event;
  std::string next;
  int next_index = -1;
};

struct BlobState {
  std::string name;
  BlobBehaviour behaviour;
  std::vector<BlobTrigger> triggers;  // checked in order; the first that fires wins
};

struct BlobProgram {
  std::vector<BlobState> states;
  std::string initial;  // state name (empty = the first state)
  int initial_index = -1;
};

// Checks ranges, unique state names and that every trigger names an existing state; resolves the
// indices. The error names the state, the key and the value (the game prefixes the file).
BlobStatus validateBlobProgram(BlobProgram& program, const BlobParams& params);

// A tentacle's axis (base to tip, from the particles) and the direction from its base to `target`:
// the angle (rad) between them, per tentacle of the current target (empty when none).
std::vector<float> blobTentacleAimAngles(const BlobWorld& world, glm::vec3 target);
// Distance (m) from each tentacle's tip particle to `target` (empty when none).
std::vector<float> blobTentacleTipDistances(const BlobWorld& world, glm::vec3 target);
// The core's (particles in no tentacle) aspect ratio: RMS extent along the horizontal unit
// `heading` over the RMS extent along y, both about the core's centroid. A body stretched along
// its motion reads above its rest value.
float blobCoreAspect(const BlobWorld& world, glm::vec3 heading);

// What the game feeds the machine each step.
struct BlobInputs {
  glm::vec3 target{0.0f};  // the player (or an object) the tentacles reach for / the chase follows
  bool blasted = false;    // a blast reached the body this step (blastBlob returned > 0)
  std::span<const std::string> events;
};

struct BlobMachine {
  int state = -1;  // index into program.states (-1 = not started)
  float time_in_state = 0.0f;
  int transitions = 0;
};

// Starts behaviour `b`: sets world.target from the current particles (assignment of particles to
// goal slots, tentacle order and texturing data). Deterministic.
void startBlobBehaviour(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target);
// Per step, before stepBlob: moves the anchor, re-aims tentacles, updates tentacle frames.
void updateBlobBehaviour(BlobWorld& world, const BlobBehaviour& b, glm::vec3 target, float dt);
// The behaviour's goal measure (the numbers the tests assert): emerge: centroid height above the
// grate >= height; ball: sphericity >= 0.9; tentacles: every tentacle reaches >= 0.8 of its
// length; coat_wall: >= 80 % of particles within 2 particle radii of the wall; chase: target within
// catch_distance; reassemble: shape error against the rest shape (its slots as matched at the start,
// world.target.offset) <= 0.1 body radius; idle: never.
bool blobGoalReached(const BlobWorld& world, const BlobBehaviour& b, glm::vec3 target);

// One machine step: starts the initial state if needed, fires the first matching trigger (entering
// the next state), then updateBlobBehaviour. Call before stepBlob. `program` must be validated.
void stepBlobMachine(const BlobProgram& program, BlobMachine& machine, BlobWorld& world, const BlobInputs& inputs);

// Enters state `index` now (the F1 overlay's "trigger this behaviour"): as a trigger firing into it.
void enterBlobState(const BlobProgram& program, BlobMachine& machine, BlobWorld& world, int index, glm::vec3 target);

// ---- Measures ----------------------------------------------------------------------------------

// Distance from the base of tentacle k (its first particle's goal base on the core) to its tip
// particle, for every tentacle of the current target (empty when none).
std::vector<float> blobTentacleReach(const BlobWorld& world);
// Fraction of particles whose distance to the wall collider(s) is within `band` (m).
float blobFractionNearWall(const BlobWorld& world, int wall_collider, float band);

}  // namespace fluid
