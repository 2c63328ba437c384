#pragma once
// GPU state-preserving sprite particles: Kolb, Latta & Rezk-Salama 2004, "Hardware-based
// Simulation and Collision Detection for Large Particle Systems", §3 (shared/papers/
// gpu-particles-depthmap-collision_kolb-latta-2004.txt).
//
//   §3.2   positions and velocities in double-buffered RGBA32F textures that are also render
//          targets; a third texture holds birth time, lifetime, type index and spin.
//   §3.3.1 birth on the CPU through an index allocator (the heap that keeps live particles
//          packed in the first texels), new particles uploaded in small batches; death
//          detected independently on the CPU (death-time queue) and on the GPU (age pass).
//   §3.3.2 Euler (velocity texture) or Verlet (no velocity texture: the previous position is
//          kept instead); gravity, wind, attractors, a flow-field texture with Stokes drag;
//          collisions against depth-map colliders (§4.1 rule (2), §4.2 L1 normal index, §4.3
//          formats) with the double check and the friction/resilience reaction.
//   §3.3.3 odd-even merge sort (Batcher) of (viewer distance, index) pairs, spread over frames.
//   §3.3.4 point sprites, positions fetched in the vertex shader, 2D rotation in the fragment
//          shader, size/colour/opacity over age by key-frames per type.
//
// All passes are fragment passes into float FBOs (as in the paper) plus point draws; see
// docs/gpu.md for why no compute shader is used. Every function here needs the GL context that
// created the system to be current. A system whose shaders failed to build is `ready == false`
// and all per-frame calls on it are no-ops: the game keeps running without the effect.

#include "fluid/collide/collide.hpp"
#include "fluid/core/blast.hpp"
#include "fluid/core/collider.hpp"

#include <GL/gl.h>
#include <GL/glext.h>
#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace engine {

// ---- §3.3.1 CPU index allocator -------------------------------------------------------

// Min-heap of free indices: allocation always returns the smallest free index, so live
// particles stay packed in the first texels and the passes only touch activeRange() texels.
struct IndexAllocator {
  std::vector<std::uint32_t> free_heap;  // min-heap (std::greater)
  std::vector<std::uint8_t> live;        // live[i] != 0 while index i is handed out
  std::uint32_t live_count = 0;
  std::uint32_t active_range = 0;  // 1 + highest live index (0 when none is live)
};

// Resets to `budget` free indices 0..budget-1 of `capacity` texels (budget 0 or above capacity:
// all of them). A budget below the texture's size keeps the live count exact when the texture is
// rounded up to a power of two for the sort.
void initAllocator(IndexAllocator& allocator, std::uint32_t capacity, std::uint32_t budget = 0);
// Smallest free index into `out`; false (out untouched) when all are live. O(log n).
bool allocateIndex(IndexAllocator& allocator, std::uint32_t& out);
// Returns a live index to the pool. Releasing a free or out-of-range index is a programmer error (assert).
void releaseIndex(IndexAllocator& allocator, std::uint32_t index);

// ---- particle types: key-frames over normalised age (§3.2) ----------------------------

inline constexpr int kParticleKeyframes = 4;  // at normalised ages 0, 1/3, 2/3, 1
inline constexpr int kMaxParticleTypes = 16;

struct ParticleKeyframe {
  glm::vec4 colour{1.0f};  // linear RGB + opacity, each in [0, 1]
  float size = 0.05f;      // sprite diameter in world units (metres)
};

struct ParticleTypeDesc {
  std::array<ParticleKeyframe, kParticleKeyframes> keys{};
  // How the type moves, on top of the step's forces: gravity scaled by gravity_scale (1 falls, a
  // negative value rises like hot gas or smoke), and a velocity damping a = -damping v (1/s) for
  // what the air holds back (smoke, fire), so it drifts rather than flies.
  float gravity_scale = 1.0f;
  float damping = 0.0f;  // 1/s, >= 0
  // Diffuse material (Ihmsen et al. 2012 §4.2): a diffuse sprite is classified every step by the
  // fluid-neighbour count at its position (setFluidGrid) into spray, foam or bubble, moves as its
  // class does (GpuStepParams::diffuse) and is drawn with the key-frames of
  // GpuParticlesDesc::class_types[class]. Without a fluid grid it is spray.
  bool diffuse = false;
};

// ---- births (uploaded in small batches) -----------------------------------------------

// Caller-owned SoA batch of new particles, reused across frames. All vectors have equal size.
struct BirthBatch {
  std::vector<glm::vec3> positions;   // world, m
  std::vector<glm::vec3> velocities;  // world, m/s
  std::vector<float> lifetimes;       // s, > 0
  std::vector<std::uint32_t> types;   // < type count given at creation (larger: the last type)
  std::vector<float> spins;           // sprite rotation speed, rad/s
  void clear();
  std::size_t size() const { return positions.size(); }
  void push(glm::vec3 position, glm::vec3 velocity, float lifetime, std::uint32_t type, float spin);
};

// ---- emitters: spray, mist, splashes, explosion debris ---------------------------------

enum class EmitterKind { spray, mist, splash, debris };

// One burst the game can fire at any point. Randomness comes from `seed` only (deterministic).
struct EmitterDesc {
  EmitterKind kind = EmitterKind::spray;
  glm::vec3 position{0.0f};               // world, m
  glm::vec3 direction{0.0f, 1.0f, 0.0f};  // main direction (normalised inside; zero = up)
  float speed = 3.0f;                     // mean launch speed, m/s
  float spread = 0.3f;                    // cone half-angle, rad (splash: ring tilt; debris/mist: ignored)
  float radius = 0.05f;                   // launch volume radius, m
  std::uint32_t count = 64;
  float lifetime = 1.5f;  // mean lifetime, s (±25% jitter)
  std::uint32_t type = 0;
  std::uint64_t seed = 1;
};
// Appends desc.count births to `batch`.
void emit(const EmitterDesc& desc, BirthBatch& batch);

// Fluid coupling: every fluid particle faster than `min_speed` (m/s) spawns one spray particle
// at its position, with its velocity plus up to `jitter` m/s of seeded noise; at most `max_count`.
// Returns the number appended.
std::size_t emitSprayFromFluid(std::span<const glm::vec3> positions, std::span<const glm::vec3> velocities,
                               float min_speed, float jitter, float lifetime, std::uint32_t type,
                               std::uint32_t max_count, std::uint64_t seed, BirthBatch& batch);

// ---- depth-map colliders on the GPU ---------------------------------------------------

// View of one depth map, field for field the `fluid::DepthMap` of fluid/collide/collide.hpp
// (the collide module's normative encodings; the shader decodes its texel bytes as they are).
// format: 1 float32, 2 fixed8, 3 front_back16, 4 cube8. compare: 0 LESS, 1 GREATER.
struct GpuDepthMapView {
  std::uint32_t format = 1;
  std::uint32_t compare = 0;
  std::uint32_t resolution = 0;          // N texels per side (per face for cube8)
  glm::mat4 collider_to_map{1.0f};       // T_OC→DC
  float z_scale = 1.0f;                  // ortho
  glm::vec3 cube_scale{1.0f};            // cube
  bool encloses_collider = false;        // invalid votes count as far outside
  std::span<const std::uint8_t> texels;  // N·N (·6 for cube8) texels of 16/4/8/4 bytes
};

// The view of one fluid::DepthMap (no copy: the map must outlive the upload call).
GpuDepthMapView gpuDepthMapView(const fluid::DepthMap& map);

// A level of a few models each seen along three axes (the blob's street with its four building
// fronts: 7 colliders, 22 maps). The maps' matrices are uniforms: 32 of them and the rest stay
// within GL 3.3's 1024 fragment uniform components' order (llvmpipe allows far more).
inline constexpr int kMaxGpuColliders = 8;
inline constexpr int kMaxGpuDepthMaps = 32;  // over all colliders

struct GpuColliderDesc {
  std::span<const GpuDepthMapView> maps;
  int normal_resolution = 256;          // R_n of the normal index texture
  std::span<const float> normal_table;  // 3·R_n·R_n floats: l1NormalTexture(R_n), uploaded as is
  fluid::ColliderPose pose{};
};

// Describes a fluid/collide collider for setColliders. `views` and `normal_table` are
// caller-owned storage the description points into (normal_table receives
// fluid::l1NormalTexture(R_n), the array the collide module decodes with).
void describeCollider(const fluid::DepthMapCollider& collider, const fluid::ColliderPose& pose,
                      std::vector<GpuDepthMapView>& views, std::vector<float>& normal_table, GpuColliderDesc& out);

// ---- the system -------------------------------------------------------------------------

enum class Integrator { euler, verlet };

struct GpuParticlesDesc {
  std::uint32_t width = 256, height = 256;  // texture size: capacity = width·height; powers of two (sort)
  Integrator integrator = Integrator::euler;
  std::vector<ParticleTypeDesc> types = std::vector<ParticleTypeDesc>(1);  // 1..kMaxParticleTypes
  std::filesystem::path shader_dir;         // folder holding gpu_particles/*.glsl, *.vert, *.frag
  std::uint32_t sort_passes_per_frame = 5;  // §3.3.3: 4–5 per frame for 1024² in the paper
  float dt = 1.0f / 60.0f;                  // fixed step, s (Verlet needs it at birth: P_{i-2} = P − v·dt)
  std::uint32_t budget = 0;                 // live particles at most; 0 = width·height (initAllocator)
  // The types whose key-frames draw a diffuse sprite of class spray, foam, bubble (types[k].diffuse).
  std::array<std::uint32_t, 3> class_types{0, 0, 0};
};

inline constexpr int kMaxAttractors = 4;
inline constexpr int kMaxBlasts = 4;  // explosions applied in one step

// Softened point attractor: a = strength·(c − p)/(|c − p|² + softening²)^{3/2}; strength < 0 repels.
struct Attractor {
  glm::vec3 position{0.0f};
  float strength = 0.0f;   // m³/s²
  float softening = 0.1f;  // m
};

struct GpuStepParams {
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};  // m/s²
  glm::vec3 wind{0.0f};                   // global acceleration, m/s²
  std::array<Attractor, kMaxAttractors> attractors{};
  int attractor_count = 0;
  // Stokes drag (§3.3.2): F = 6πηr(v − v_flow); a = −(6πηr/m)(v − v_flow). 0 disables it.
  float viscosity = 0.0f;         // η, Pa·s
  float particle_radius = 0.01f;  // r, m
  float particle_mass = 1e-3f;    // m, kg
  fluid::CollisionMaterial material{};
  float skin = 1e-3f;  // m pushed beyond a collider surface
  // After the §3.3.2 reaction, re-sample the collider at the new position and project again
  // while still inside (at most this many times; 0 = exactly fluid::collideParticles). Needed
  // because a nearest-texel depth map is piecewise constant: the push along one texel's normal
  // can land over a neighbouring texel whose surface is higher. Clamped to [0, 8].
  int push_out_iterations = 4;
  // Explosions this step (fluid/core/blast.hpp, the model the SPH water and the crates use): each
  // live sprite gains dv = I(r) * (pi r^2 / m), capped at blast_max_speed_change. Set them for one
  // step only; blasts past kMaxBlasts are ignored.
  std::array<fluid::Blast, kMaxBlasts> blasts{};
  int blast_count = 0;
  float blast_max_speed_change = 40.0f;  // m/s
  // Diffuse sprites (ParticleTypeDesc::diffuse; Ihmsen et al. 2012 §4.2), by the fluid-neighbour
  // count n at the sprite, estimated from the fluid grid (setFluidGrid):
  //   spray  (n < spray_below): the type's own motion (gravity, damping) and collisions;
  //   foam   (spray_below <= n <= bubble_above): advected with the fluid velocity, x += dt v_f (eq. 7);
  //   bubble (n > bubble_above): v += dt (-k_b g + k_d (v_f - v) / dt) (eq. 8), buoyancy and drag.
  // A bubble that reaches the surface (fewer neighbours) turns into foam, spray landing in the water
  // too. The class is kept in state1.w (Euler), where the sprite shader reads it.
  struct Diffuse {
    float spray_below = 6.0f, bubble_above = 20.0f;
    float buoyancy = 2.0f;  // k_b (the paper's example value)
    float drag = 0.5f;      // k_d in [0, 1]: the fraction of the velocity difference removed per step
  } diffuse;
};

// The fluid grid of the diffuse sprites: per cell the sum of fluid velocities (xyz, m/s) and the
// particle count (w), over an axis-aligned box of size·cell (fluid::FluidCellGrid). The shader
// interpolates both trilinearly between cell centres: v_f = xyz / w, and the neighbour count
// estimate n = w · neighbour_scale. Recorded (the upload runs with the frame's GPU work, in order).
struct FluidGridDesc {
  glm::ivec3 size{0};
  glm::vec3 origin{0.0f};
  float cell = 1.0f;                 // m
  float neighbour_scale = 1.0f;      // (4/3 π h³) / cell³
  std::span<const glm::vec4> cells;  // size.x·size.y·size.z, x fastest
};

// Flow field for the Stokes drag: a W×H×D grid of velocities (m/s) over an axis-aligned box;
// sampled trilinearly at cell centres, clamped at the border.
struct FlowFieldDesc {
  glm::ivec3 size{0};
  glm::vec3 origin{0.0f};
  glm::vec3 extent{1.0f};
  std::span<const glm::vec3> velocities;  // size.x·size.y·size.z, x fastest
};

struct GpuProgram {
  GLuint id = 0;
};

// ---- the GPU half of a fixed step, run by the frame ----------------------------------------
// spawn() and step() do their CPU half at once (index allocation, the death queue, the clock:
// §3.3.1) and record their GPU half; the frame's sprite pass runs the records in order
// (runPendingWork) before it sorts and draws, so a fixed-step loop issues no GL of its own.
// Everything that reads the textures (read-backs, the sort, the draw) runs the records first.
struct GpuWorkRecord {
  enum class Kind : std::uint8_t { births, step, readback, fluid_grid };
  Kind kind = Kind::step;
  std::uint32_t first = 0, count = 0;  // births: vertices [first, first + count) of pending_births;
                                       // fluid_grid: vec4s [first, first + count) of pending_grid
  glm::ivec3 grid_size{0};             // fluid_grid
  glm::vec4 grid_box{0.0f};            // fluid_grid: origin xyz, cell
  float grid_scale = 0.0f;             // fluid_grid: neighbour_scale
  float time = 0.0f;                   // step: the clock after it (u_time)
  std::int32_t rows = 0;               // step: texture rows holding the live range when recorded
  std::uint64_t step_index = 0;        // readback: GpuParticles::steps when it was asked for
  GpuStepParams params;                // step
  std::array<fluid::ColliderPose, kMaxGpuColliders> poses{};  // step: collider poses when recorded
};

// What the last read-back saw: the live sprites (in index order) after step `step`.
struct GpuReadback {
  std::vector<glm::vec4> positions, velocities;  // xyz; velocities: Euler state1 (Verlet: P_{i-2})
  std::uint64_t step = 0;                        // 0: none yet
};

struct GpuParticles {
  bool ready = false;
  std::string error;  // why not ready (shader file:line, GL limits)
  GpuParticlesDesc desc;
  std::uint32_t capacity = 0;
  // §3.2 double buffers. Euler: state0 = position, state1 = velocity (xyz; w of velocity unused).
  // Verlet: state0 = P_{i-1}, state1 = P_{i-2}. Position w = 1 live, 0 dead.
  std::array<GLuint, 2> state0{}, state1{};
  GLuint attributes = 0;              // (birth time s, death time s, type, spin rad/s)
  std::array<GLuint, 2> fbo{};        // update pass: writes state0[k], state1[k]
  std::array<GLuint, 2> birth_fbo{};  // births: state0[k], state1[k], attributes
  int current = 0;
  std::array<GLuint, 2> sort_tex{}, sort_fbo{};  // (key, index) pairs
  int sort_current = 0;
  std::uint32_t sort_step = 0;  // position in the merge-sort pass sequence
  GLuint type_tex = 0, flow_tex = 0;
  GLuint collider_buffer = 0, collider_tbo = 0, normal_buffer = 0, normal_tbo = 0;
  GLuint birth_vbo = 0, birth_vao = 0, empty_vao = 0;
  GpuProgram birth, sort_key, sort_pass, sprite;
  // Update-pass variants, built on first use: bit 0 attractors, 1 drag, 2 flow field,
  // 3 colliders, 4..7 depth-map formats present (float32, fixed8, front_back16, cube8).
  // Bit 8 blasts, 9 diffuse types present (desc.types).
  std::array<GLuint, 1024> update_variants{};
  float time = 0.0f;        // s since creation, advanced by step()
  std::uint64_t steps = 0;  // step() calls since creation
  IndexAllocator allocator;
  std::vector<std::pair<float, std::uint32_t>> death_queue;  // min-heap on death time
  std::vector<std::uint32_t> sort_scratch;
  // Colliders uploaded by setColliders.
  int collider_count = 0;
  int map_count = 0;
  unsigned format_mask = 0;  // bit f-1 set when a map of format f is uploaded
  std::vector<std::uint32_t> collider_words;
  std::array<int, kMaxGpuColliders + 1> collider_first_map{};
  std::array<fluid::ColliderPose, kMaxGpuColliders> collider_poses{};
  std::array<std::int32_t, kMaxGpuDepthMaps * 4> map_info{};  // format, compare, resolution, word offset
  std::array<float, kMaxGpuDepthMaps * 4> map_params{};       // z_scale, cube scale xyz
  std::array<std::int32_t, kMaxGpuDepthMaps> map_encloses{};
  std::array<glm::mat4, kMaxGpuDepthMaps> map_matrices{};
  std::array<std::int32_t, kMaxGpuColliders> normal_res{};
  std::array<std::int32_t, kMaxGpuColliders> normal_offset{};
  bool flow_enabled = false;
  glm::vec3 flow_origin{0.0f}, flow_extent{1.0f};
  // Fluid grid of the diffuse sprites (setFluidGrid): RGBA32F 3D texture; the box and scale as
  // recorded, current once the record has run.
  GLuint fluid_tex = 0;
  bool fluid_enabled = false;  // a grid has been uploaded (set when its record runs)
  glm::vec3 fluid_origin{0.0f};
  float fluid_cell = 1.0f, fluid_neighbour_scale = 1.0f;
  std::vector<glm::vec4> pending_grid;
  // Recorded by spawn/step/requestReadback, run and cleared by runPendingWork.
  std::vector<GpuWorkRecord> pending;
  std::vector<float> pending_births;        // 11 floats per birth vertex (index bits, p, v, times, type, spin)
  std::vector<std::uint8_t> readback_live;  // allocator.live when the pending read-back was asked for
  GpuReadback readback;
  std::vector<glm::vec4> read_scratch;
};

// Builds textures, FBOs and shaders. On failure `ready` is false and `error` says why (shader
// errors name the file and line); the object can still be destroyed and its calls are no-ops.
void createGpuParticles(const GpuParticlesDesc& desc, GpuParticles& out);
void destroyGpuParticles(GpuParticles& system);

// Allocates indices (smallest first) and records the batch's upload (one point draw into the
// current textures when the work runs). Births beyond capacity are dropped; returns the number born.
std::size_t spawn(GpuParticles& system, const BirthBatch& batch);

// Replaces the colliders (at most kMaxGpuColliders, kMaxGpuDepthMaps maps in all). Returns
// false with `error` set (and keeps the previous colliders) when limits are exceeded or a map's
// texel span has the wrong size.
bool setColliders(GpuParticles& system, std::span<const GpuColliderDesc> colliders, std::string& error);
// Moves collider k (pose from the physics body each step).
void setColliderPose(GpuParticles& system, int collider, const fluid::ColliderPose& pose);
// Uploads (or with an empty span disables) the drag flow field. False + error on size mismatch.
bool setFlowField(GpuParticles& system, const FlowFieldDesc& flow, std::string& error);

// Records the upload of the diffuse sprites' fluid grid (no GL now; it runs before the steps
// recorded after it). An empty `cells` turns it off (diffuse sprites are then spray). False + error
// on a size mismatch or a non-finite value (the previous grid is kept).
bool setFluidGrid(GpuParticles& system, const FluidGridDesc& grid, std::string& error);

// One fixed step of desc.dt: the CPU retires particles whose lifetime ended (§3.3.1) at once, and
// records the fragment pass that integrates, collides and marks dead particles on the GPU (w = 0,
// moved far away), with the collider poses as they are now.
void step(GpuParticles& system, const GpuStepParams& params);
// Asks for the live sprites' positions and velocities as they are after the last recorded step;
// they land in system.readback when the work runs.
void requestReadback(GpuParticles& system);
// Runs the recorded work in order (births, update passes, read-backs) and clears it. The frame's
// sprite pass calls it; so do the read-back, sort and draw functions below. No-op when not ready.
void runPendingWork(GpuParticles& system);
// Builds now (once) the update-pass variant step() will use with these parameters and the
// colliders uploaded, so the first step does not pay for the shader compile. False when the
// system is not ready or the variant fails (then `ready` is false and `error` says why).
bool prepareStep(GpuParticles& system, const GpuStepParams& params);
// 6πηr/m of §3.3.2 in 1/s (0 when the parameters are not finite).
float stokesDragRate(const GpuStepParams& params);

// §3.3.3: refresh the keys for `eye` and run `passes` merge-sort passes (0 = desc value).
// Keys sort farthest first (back-to-front); dead slots sort to the end.
void sortStep(GpuParticles& system, glm::vec3 eye, std::uint32_t passes = 0);
// The two halves of sortStep: one key-refresh pass (the permutation is kept), and `passes`
// passes of the network, continuing where the last call stopped and restarting when done.
void refreshSortKeys(GpuParticles& system, glm::vec3 eye);
void sortPasses(GpuParticles& system, std::uint32_t passes);
// Passes of a full sort of the whole texture: ½log²n + ½log n.
std::uint32_t sortPassCount(std::uint32_t n);

// Draws live particles as rotated point sprites in sorted order into the bound framebuffer.
// Blending: premultiplied "over". `viewport_height` px and the projection scale turn the world
// size into gl_PointSize.
void drawSprites(GpuParticles& system, const glm::mat4& view_projection, float projection_scale_y, int viewport_height);

// Read-backs (tests, tools). Each returns capacity entries (or activeRange() with `active_only`).
void readPositions(GpuParticles& system, std::vector<glm::vec4>& out);
void readState1(GpuParticles& system, std::vector<glm::vec4>& out);  // velocity (Euler) / P_{i-2} (Verlet)
void readSortPairs(GpuParticles& system, std::vector<glm::vec2>& out);

}  // namespace engine
