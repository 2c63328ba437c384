#pragma once
// fluid/blob: the blob monster's particle body (no GL, no Bullet). Marching slices paper
// (Rosenberg & Birdwell 2008, §7 and Figure 8): an amorphous monster of particles that emerges from
// a sewer, forms a ball, grows tentacles, coats a wall, chases the player, and reassembles into its
// original shape after being blown apart. The paper gives no body model; ours combines two:
//
//  - Shape matching (Müller, Heidelberger, Teschner & Gross 2005, "Meshless deformations based on
//    shape matching", its rigid shape matching section): every behaviour is a target shape (one goal offset per
//    particle); the goal of particle i is g_i = c + R q_i with R the rotation of the best rigid fit
//    of the target to the current positions (polar part of A_pq = sum m p_i q_i^T) when the
//    behaviour lets the body turn, and c the behaviour's anchor (or the centroid, as in the paper).
//    Why: the issue asks for behaviours that *reach* measurable shapes (a sphere, N tentacles, a
//    layer on a wall) and for reassembly into the original shape — shape matching gives exactly
//    "this particle belongs there" with an unconditionally meaningful goal, and separated droplets
//    keep their slot, so they find their way back. We apply it as a force (a damped spring toward
//    g_i, saturated far away) rather than Müller's position projection, so behaviours drive the
//    body by forces and never teleport particles, and the body stays soft and sloshy.
//  - Pairwise cohesion (Akinci, Akinci & Teschner 2013, "Versatile surface tension and adhesion for
//    SPH fluids": the cohesion force with its spline kernel C(r)) plus a short-range contact
//    repulsion: C(r) attracts neighbours up to the support h and makes the body behave like a goo
//    that keeps one skin. Akinci's curvature (surface area minimisation) term is left out: shape matching already
//    removes the surface wrinkles it would flatten, and it needs per-particle normals every step.
//
// Collisions: each collider is a fluid::SignedDistanceShape (analytic or baked depth maps from
// fluid/collide) with a pose; the Kolb et al. 2004 §3.3.2 double check (fluid::collideParticles)
// with swept sampling, so a particle flung at 100 m/s does not cross a thin wall. Colliders may
// move (a crate thrown by Bullet): particles are pushed with the collider's velocity, and the
// momentum each collider gave the particles is reported back (BlobCollider::impulse) so the game
// applies the opposite to its rigid body: the blob shoves crates, thrown crates dent the blob.
//
// Determinism: fixed sub-steps; the per-particle passes run on oneTBB and write only their own
// particle; every reduction (centroid, A_pq, impulses) is a serial loop in index order, so results
// are bit-identical for any thread count. Randomness (the initial jitter) comes from a seeded
// counter-based hash.
//
// Units: SI (m, s, kg). Gravity defaults to -y. Particle index order never changes (tentacle order
// and the rest shape are by index).

#include "fluid/collide/collide.hpp"
#include "fluid/core/blast.hpp"
#include "fluid/core/collider.hpp"
#include "fluid/sph/neighbor_grid.hpp"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace fluid {

struct BlobParams {
  std::size_t particle_count = 1000;  // N in [1, 65536]
  float spacing = 0.08f;              // d (m) in [0.005, 1]: rest distance; particle radius r = d/2
  float density = 1000.0f;            // kg/m^3 > 0: particle mass m = density d^3
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};
  float step = 1.0f / 60.0f;  // s in [1e-4, 0.1]: one stepBlob call
  int substeps = 4;           // in [1, 64]: explicit sub-steps per step (stability: omega dt < 1)
  // Akinci 2013 cohesion: peak attraction (m/s^2) between two particles at h/2; h = cohesion_radius d.
  // 4: at rest the body keeps its shape within 0.03 body radii; 12 squeezed it to 0.09 (the
  // surface pull compresses every contact below it; tests/blob prints the idle shape error).
  float cohesion = 4.0f;  // >= 0
  float cohesion_radius =
      1.5f;  // h / d in [1.1, 3]: 1.5 reaches the 18 nearest lattice neighbours (2: 32, twice the pair work)
  float repulsion = 3000.0f;  // 1/s^2 >= 0: contact spring for r < d (keeps the spacing)
  float pair_damping = 3.0f;  // 1/s >= 0: damping of the relative normal velocity of neighbours
  // Müller 2005 goal springs, scaled per particle by the behaviour's weight.
  float goal_stiffness = 500.0f;  // 1/s^2 >= 0 (omega^2)
  float goal_damping = 20.0f;     // 1/s >= 0, relative to the goal's velocity; fades out beyond 1-2 x goal_reach
  float goal_reach = 0.1f;        // m > 0: the goal pull is constant beyond this distance (droplets fly free)
  // Fraction of gravity the monster "holds up" where it follows a goal (its muscles): without it a
  // goal spring sags by g / goal_stiffness. In [0, 1].
  float support = 0.9f;
  float drag = 0.3f;                               // 1/s >= 0: air drag
  float max_speed = 150.0f;                        // m/s > 0: speeds are clamped to this (blasts, collisions)
  CollisionMaterial material{0.1f, 0.05f, 0.05f};  // slime slides: low friction, no bounce
  std::uint64_t seed = 1;
};

// SoA particle data. Per-particle texturing data for the tentacles (paper §7): a basis (tangent
// along the tentacle, and a normal that fixes u = 0 around it), a length coordinate (0 at the base,
// 1 at the tip; -1 for particles not in a tentacle), and the field strength and radius scale that
// taper the tentacle's radius (fluid/surface SurfaceInput::strength / radiusScale).
struct BlobParticles {
  std::vector<glm::vec3> position;  // m
  std::vector<glm::vec3> velocity;  // m/s
  std::vector<glm::vec3> rest;      // the original shape: offset from its centroid (m)
  std::vector<glm::vec3> tangent, normal;
  std::vector<float> length_coord;
  std::vector<float> strength, radius_scale;
  std::vector<std::int32_t> tentacle;  // tentacle index, -1 for the core
  std::size_t size() const { return position.size(); }
};

// What the current behaviour asks of each particle (set by fluid/blob/behaviour.hpp).
// Goal of i: anchor + R offset[i] (R = identity unless rotate), pulled with weight[i].
struct BlobTarget {
  std::vector<glm::vec3> offset;    // m, per particle
  std::vector<float> weight;        // in [0, 4], per particle
  glm::vec3 anchor{0.0f};           // m, world
  glm::vec3 anchor_velocity{0.0f};  // m/s: the goal's velocity (damping is relative to it)
  bool anchor_at_centroid = true;   // Müller 2005: c = current centroid (anchor ignored)
  bool rotate = true;               // best-fit rotation of the offsets (Müller 2005: the rotational part of A_pq)
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // last R (warm start of the polar decomposition)
  // Tentacles of the current behaviour (empty otherwise): base on the core surface, unit direction
  // and reach (m), and the particles of each from base to tip.
  std::vector<glm::vec3> tentacle_base, tentacle_dir;
  std::vector<float> tentacle_length;
  std::vector<std::vector<std::uint32_t>> tentacle_particles;
  float steer_side = 0.0f;  // chase: side (+1/-1) it slides along walls in its way; 0 = none met yet
  // Hunting tentacles: each one's visible length now (m), grown and retracted at grow_speed.
  std::vector<float> tentacle_extent;
  // chase squash and stretch: the core's unstretched offsets (offset = S shape_offset), the
  // smoothed stretch factor along stretch_dir (horizontal unit).
  std::vector<glm::vec3> shape_offset;
  float stretch = 1.0f;
  glm::vec3 stretch_dir{1.0f, 0.0f, 0.0f};
};

// A level collider or a rigid body (crate). Moving colliders (pose velocities, integrated over the
// sub-steps; the game resets the pose from Bullet every step) push particles. Colliders are
// resolved one after the other, each against the result of the previous: those not marked
// `level` first, in list order, then the `level` ones in list order, so where a crate presses
// into a wall the particle ends outside the wall (the crate's overlap with the wall is Bullet's
// to resolve, not the particle's). Indices into the list (BlobBehaviour::wall_collider) are not
// affected by that order.
struct BlobCollider {
  std::shared_ptr<const SignedDistanceShape> shape;  // non-null, read-only, shared
  ColliderPose pose;
  CollisionMaterial material;
  bool level = false;             // part of the fixed level: resolved after every collider that is not
                                  // (a crate pressing a particle into a wall leaves it outside the wall)
  bool use_blob_material = true;  // use BlobParams::material instead of `material`
  // Optional: a collider-space box outside which `shape` never reports a point inside (distance
  // < 0). A particle whose sub-step path lies wholly outside it skips the shape's queries: the
  // same result for less work (most particles are nowhere near most of the level's colliders).
  // blobDepthMapBounds gives the box of a baked collider; stepBlob hands it to fluid::collideParticles
  // (CollideDesc::bounded, inside). bounded = false: query every particle.
  bool bounded = false;
  glm::vec3 inside_lo{0.0f}, inside_hi{0.0f};
  // Output of the last stepBlob: momentum (N s) and angular momentum about pose.translation
  // (N m s) the particles lost to this collider, i.e. what the game applies to the rigid body.
  glm::vec3 impulse{0.0f};
  glm::vec3 angular_impulse{0.0f};
};

struct BlobScratch {
  NeighborGrid grid;
  NeighborLists neighbors;  // Verlet lists: candidates within h + skin of the positions below
  std::vector<glm::vec3> verlet_position;
  bool verlet_valid = false;
  std::vector<glm::vec3> accel, previous, before, goal;
  std::vector<glm::vec4> pos4, vel4;  // pair loop: position + radius scale, velocity
  CollideScratch collide;             // fluid::collideParticles' per-particle outcomes
};

struct BlobStepStats {
  std::size_t collisions = 0;  // particle-collider reactions (Kolb 2004 §3.3.2), all sub-steps
  std::size_t swept = 0;       // of those, found only by the swept sampling (fast particles)
  std::size_t clamped = 0;     // particle speeds clamped to max_speed
  float max_speed = 0.0f;      // m/s after the step
  float step_ms = 0.0f;
};

struct BlobStatus {
  std::string error;  // empty == success; otherwise names the field/value
  bool ok() const { return error.empty(); }
};

struct BlobWorld {
  BlobParams params;
  // The box (m, world) the behaviours keep the body's anchor in, shrunk by the body radius in x and
  // z: the street the monster hunts in (the game sets it to the player's bounds). Unbounded by default.
  glm::vec3 keep_min{-1e30f}, keep_max{1e30f};
  BlobParticles particles;
  BlobTarget target;
  std::vector<BlobCollider> colliders;
  double time = 0.0;  // s
  std::uint64_t steps = 0;
  BlobScratch scratch;
};

inline float blobParticleRadius(const BlobParams& p) { return 0.5f * p.spacing; }
inline float blobParticleMass(const BlobParams& p) { return p.density * p.spacing * p.spacing * p.spacing; }
// Radius (m) of a ball holding the particles at the rest spacing: (3 N / (4 pi))^(1/3) d.
float blobBodyRadius(const BlobParams& p);

// Checks every parameter (finite, in range); the message names the field and value.
BlobStatus validateBlobParams(const BlobParams& params);

// (Re)creates the particles: the original (rest) shape is the N points of a cubic lattice of
// spacing d nearest the centre of an ellipsoid with the given radii ratios (the blob's lazy
// puddle-ish shape; (1,1,1) a ball), jittered by 1 % of d (seeded). Particles start at
// centre + rest, at rest; the target becomes "hold the rest shape" (idle).
BlobStatus initBlob(BlobWorld& world, glm::vec3 centre, glm::vec3 shape = glm::vec3(1.2f, 0.75f, 1.2f));
// The `count` points of a cubic lattice of `spacing` nearest the centre of an ellipsoid with radii
// ratios `shape` (> 0) and the volume of `count` particles, centred on their centroid. Sorted from
// the centre out (ties in a fixed order).
std::vector<glm::vec3> blobLatticeShape(std::size_t count, float spacing, glm::vec3 shape);
// Places the particles at `positions` (size N, finite), velocities zero, keeping the rest shape
// (e.g. a column inside a sewer pipe before `emerge`).
BlobStatus placeBlob(BlobWorld& world, std::span<const glm::vec3> positions);
// The N points of a cubic lattice of spacing d inside a vertical cylinder of `radius` (x-z) whose
// axis passes through `top` and that extends downward (a column in a pipe), top layer first.
std::vector<glm::vec3> blobColumn(const BlobParams& params, glm::vec3 top, float radius);

// The collider-space box that holds every point a baked depth-map collider (fluid/collide) can
// report inside. Inside needs at least one vote and every vote negative (rule (2)), so some map
// cast a negative vote there: the union over the maps of where each can. A front_back16 map only
// at texels that vote (not background, not margin ring) and between their front and back depths
// (its surfaces' bounding box, seen from that side); other ortho maps anywhere in their volume
// [0, 1]^3, cube maps in [-1, 1]^3 (collide.hpp "Map coordinates"). Widened by 1 mm and 1e-4 of
// its size against rounding. Sets c.bounded, c.inside_lo/hi; a collider without maps stays unbounded.
void blobDepthMapBounds(BlobCollider& c, const DepthMapCollider& shape);

// Advances params.step seconds (params.substeps sub-steps). The world is left untouched when a
// position or velocity is not finite (the error names the particle).
BlobStatus stepBlob(BlobWorld& world, BlobStepStats* stats = nullptr);

// The game's blast (fluid/core/blast.hpp), by the law the water, crates and sprites obey: particle i
// gains fluid::blastVelocityChange with its cross-section over mass pi r^2 / (rho d^3), the change
// capped at max_speed (and the speed clamped to it). Returns how many particles it reached; a blast
// validateBlast rejects does nothing.
std::size_t blastBlob(BlobWorld& world, const Blast& blast);

// ---- Measurements (the behaviour tests and the game's overlay) --------------------------------

glm::vec3 blobCentroid(std::span<const glm::vec3> positions);
// Rotation of the best rigid fit of `rest` (offsets from their centroid) onto `positions` (Müller
// 2005: the rotational part of A_pq), by the iterative method of Müller, Bender, Chentanez &
// Macklin 2016 ("A robust method to extract the rotational part of deformations"), warm-started.
glm::quat blobBestRotation(std::span<const glm::vec3> positions, std::span<const glm::vec3> rest,
                           glm::quat warm = glm::quat(1.0f, 0.0f, 0.0f, 0.0f), int iterations = 30);
// RMS distance (m) between the positions and the rest shape after the best rigid alignment
// (translation to the centroid, rotation as above).
float blobShapeError(std::span<const glm::vec3> positions, std::span<const glm::vec3> rest);
// sqrt(smallest / largest eigenvalue) of the positions' covariance: 1 for a ball (or any shape
// with isotropic second moments), 0 for a line or a flat sheet.
float blobSphericity(std::span<const glm::vec3> positions);
float blobMaxSpeed(std::span<const glm::vec3> velocities);
bool blobAllFinite(const BlobParticles& particles);

}  // namespace fluid
