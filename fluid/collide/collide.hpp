#pragma once
// fluid/collide: depth-map colliders with L1 (octahedral) normal indexing.
//
// Spec: Kolb, Latta & Rezk-Salama 2004, "Hardware-based Simulation and Collision Detection
// for Large Particle Systems" (shared/papers/gpu-particles-depthmap-collision_kolb-latta-2004.txt):
//   §4.1 implicit model = k depth maps, eq. (1) per-map distance, rule (2) combination,
//        invalid votes and the one-texel background border;
//   §4.2 eq. (3) L1 parametrization of the unit sphere used as a normal index texture;
//   §4.3 formats: float, 8-bit fixed, 16-bit front-back, perspective depth cube;
//   §3.3.2 reaction (fluid/core/collider.hpp, reused here for the batch particle step).
//
// The same texels are uploaded to GL by the GPU sprite code and decoded in GLSL, so every
// encoding below is specified to the bit. All multi-byte values are little-endian in files.
//
// ---------------------------------------------------------------------------------------
// ENCODINGS (normative; the GLSL decoder must follow them exactly)
//
// L1 normal index, resolution R (1 <= R <= 65535; default 256):
//   encode: p = n / (|nx|+|ny|+|nz|); if p.z >= 0: (a,b) = (p.x, p.y)
//           else (a,b) = (sgnp(p.x)·(1−|p.y|), sgnp(p.y)·(1−|p.x|))   [inverse of eq. (3)]
//           with sgnp(x) = x >= 0 ? +1 : −1 (so −z maps to the corner (1,1));
//           (s,t) = (a,b)·0.5 + 0.5 in [0,1]²;
//           i = min(floor(s·R), R−1), j = min(floor(t·R), R−1)  (float math, then int);
//           texel index = j·R + i.
//   decode texel (i,j): (s,t) = ((i+0.5)/R, (j+0.5)/R) (the texel centre, computed in
//           double then rounded to float), then eq. (3) with (a,b) = 2(s,t)−1, normalised.
//   The normal index texture is l1NormalTexture(R): R×R texels, row j, column i, RGB float32
//   = the decoded unit vector. The GPU uploads this array; it never recomputes it, so the
//   lookup is bit-identical by construction. Fetch with texelFetch(tex, ivec2(i, j), 0).
//
// Per-texel formats (DepthMapFormat). "depth" is the depth-map coordinate z' in [0,1]
// (ortho) or the normalised radial distance r/sqrt(3) in [0,1] (cube):
//   float32      4 × float32: (nx, ny, nz, depth). Normal is the unit outward normal in
//                collider space. Background (no surface): depth = −1.0f (any depth < 0).
//   fixed8       4 × uint8 (RGBA8): R = i, G = j (normal index at R_n <= 256),
//                B = high byte, A = low byte of q (uint16). depth = float(q) * kFixedDepthStep,
//                kFixedDepthStep = 1.52590219e-05f (= float(1/65535), bits 0x37800080);
//                encode q = round-half-away(depth·65535) clamped to [0, 65534].
//                Background: q = 65535 (R = G = 0xFF, B = A = 0xFF).
//   front_back16 4 × uint16 (RGBA16UI): R = front normal index, G = back normal index, each
//                i | (j << 8) (R_n <= 256); B = front depth, A = back depth as IEEE binary16
//                bits (decode with unpackHalf2x16, exact), encoded round-to-nearest-even.
//                Background: half −1.0 (0xBC00) in B resp. A; its index is 0xFFFF.
//   cube8        six faces of fixed8 texels (same bytes as fixed8), face order +X,−X,+Y,−Y,+Z,−Z,
//                face-local (s,t) as in the OpenGL cube-map table (sc,tc,ma):
//                +X(−z,−y,x) −X(z,−y,x) +Y(x,z,y) −Y(x,−z,y) +Z(x,−y,z) −Z(−x,−y,z),
//                s = (sc/|ma| + 1)/2, t = (tc/|ma| + 1)/2, ties pick x before y before z.
//                depth = r/sqrt(3), r = |P'| of the surface hit in the normalised volume;
//                decode r = float(q) * kCubeRadiusStep, kCubeRadiusStep = float(sqrt(3)/65535).
//   Texel (i,j) of an N×N map is stored at index j·N + i (cube: face·N·N + j·N + i).
//   Texel lookup is nearest: ortho i = floor(u·N) in float, valid iff 0 <= i < N (u = P'x,
//   v = P'y); cube i = clamp(floor(s·N), 0, N−1). Upload without filtering (texelFetch).
//
// Baking (what the texels mean): ortho maps are rasterized conservatively: a texel holds the
// nearest (LESS) / farthest (GREATER) depth over every triangle whose projection touches the
// texel square, taken at the texel centre when it lies inside the triangle and at the
// nearest point of the triangle's outline otherwise. So a point inside the collider never
// reads a background texel, which is what makes "invalid = far outside" safe. Cube texels
// hold the hit of the ray through the texel centre (no conservative cover). Stored normals
// are the outward face normals of the winning triangles.
//
// Map coordinates (§4.1, item 3 and 4): collider_to_map = T_OC→DC (affine, column-major).
//   ortho: P' = T·P with (P'x, P'y) texture coordinates in [0,1]², P'z the depth in [0,1]
//          (0 = near plane, increasing along the view direction); z_scale = depth range in
//          collider units, so eq. (1) gives collider units:
//            front (LESS):    f = z_scale·(depth − P'z)
//            back  (GREATER): f = z_scale·(P'z − depth)      (the negation of eq. (1))
//          A one-texel border of every ortho map stays background (§4.1).
//   cube:  P' = T·P in the normalised view volume [−1,1]³ (no projection in T, §4.3);
//          cube_scale = (s_x, s_y, s_z) maps it back to collider units. With L = |P'|,
//          r = dist(P'), the §4.3 distance along the ray from the centre is
//            LESS    (centre outside the collider): f = (r − L)·|S·P'| / L
//            GREATER (centre inside, or the far wall wanted): f = (L − r)·|S·P'| / L
//          This is the paper's (1 − r/L)|S·P'| with the sign chosen so that points between
//          the centre and a LESS surface are outside (the paper's "negate" remark, §4.3).
//
// Votes (rule (2)): a map votes invalid when P' is outside its view volume or the texel is
// background. View volume: cube [−1,1]³; ortho (P'x, P'y) in [0,1)², and along z a LESS map
// up to its far plane (P'z <= 1), a GREATER map from its near plane (P'z >= 0) — the part in
// front of the near plane is kept because eq. (1) still holds there. An invalid vote is
// ignored, except for maps whose view volume encloses the whole collider (encloses_collider,
// set by the baker): there it is "far outside" (+FLT_MAX), as §4.1 allows.
// Rule (2) is evaluated order-independently: f = min of the votes >= 0 if any, else the max
// of the negative votes; the normal is that of the winning texel (first map wins ties).
// Measured L1 index error (docs/collide.md): max 0.94°, mean 0.33° at 256²; max ≈ 241°/R.
// ---------------------------------------------------------------------------------------

#include "fluid/core/collider.hpp"

#include <glm/glm.hpp>

#include <array>
#include <cfloat>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace fluid {

// ---- §4.2, eq. (3): L1 (octahedral) parametrization ----------------------------------

// Unit (or any non-zero) vector -> (s,t) in [0,1]². A zero or non-finite vector gives (0.5,0.5) (+z).
glm::vec2 l1Encode(glm::vec3 direction);
// (s,t) in [0,1]² (clamped) -> unit vector (eq. (3) after the affine map, then normalised).
glm::vec3 l1Decode(glm::vec2 st);
// Texel (i,j) holding `direction` in an R×R normal index texture (encoding above).
glm::ivec2 l1Texel(glm::vec3 direction, int resolution);
// j·R + i.
std::uint32_t l1TexelIndex(glm::vec3 direction, int resolution);
// Unit vector stored in texel (i,j): decode of the texel centre.
glm::vec3 l1TexelNormal(glm::ivec2 texel, int resolution);
// The whole R×R normal index texture, RGB float32 interleaved, row-major (3·R·R floats).
std::vector<float> l1NormalTexture(int resolution = 256);

// ---- §4.3 texel encodings (exposed for the GPU upload and its tests) -----------------

inline constexpr float kFixedDepthStep = static_cast<float>(1.0 / 65535.0);
inline constexpr float kCubeRadiusStep = static_cast<float>(1.7320508075688772 / 65535.0);
inline constexpr std::uint16_t kFixedBackground = 0xFFFF;
inline constexpr std::uint16_t kHalfBackground = 0xBC00;  // binary16 −1.0

std::uint16_t encodeFixedDepth(float depth01);  // round(depth·65535) in [0, 65534]
float decodeFixedDepth(std::uint16_t q);        // q·kFixedDepthStep (q != background)
std::uint16_t floatToHalf(float value);         // IEEE binary16, round to nearest even
float halfToFloat(std::uint16_t bits);          // exact

// ---- §4.1 / §4.3 depth maps -----------------------------------------------------------

enum class DepthMapFormat : std::uint32_t { float32 = 1, fixed8 = 2, front_back16 = 3, cube8 = 4 };
// LESS keeps the nearest surface (front map, or cube whose centre is outside the collider);
// GREATER the farthest (back map, or cube whose centre is inside). front_back16 holds both.
enum class DepthCompare : std::uint32_t { less = 0, greater = 1 };

const char* formatName(DepthMapFormat format);
// "float", "fixed8", "front-back16", "cube8"; false when unknown.
bool parseFormat(const std::string& name, DepthMapFormat& out);

// Bytes per texel of one map layer (cube8: per face texel).
constexpr std::size_t texelBytes(DepthMapFormat format) {
  return format == DepthMapFormat::float32 ? 16 : format == DepthMapFormat::front_back16 ? 8 : 4;
}

struct DepthMap {
  DepthMapFormat format = DepthMapFormat::float32;
  DepthCompare compare = DepthCompare::less;  // ignored for front_back16 (front = less, back = greater)
  std::uint32_t resolution = 0;               // N: texels per side (per face for cube8)
  glm::mat4 collider_to_map{1.0f};            // T_OC→DC, see "Map coordinates"
  float z_scale = 1.0f;                       // ortho only: collider units per unit of P'z
  glm::vec3 cube_scale{1.0f};                 // cube only: s_x, s_y, s_z
  bool encloses_collider = false;             // invalid votes count as far outside
  // front_back16 baked with MapSpec::margin > 0: texels whose front and back depth bits are equal
  // are margin-ring texels, whose votes count only where no other vote says outside (sample).
  // File: bit 1 of the map's flags word (version 2). The GLSL decoder may ignore it: ring votes
  // then compete like the others (finite, never inside, shorter than the true distance).
  bool margin_ring = false;
  std::vector<std::uint8_t> texels;  // N·N (·6 for cube8) texels of texelBytes(format)
};

// A collider: k depth maps in collider space, plus the normal index resolution R_n used by
// the fixed8/front_back16/cube8 maps (and the decoded texture, rebuilt on load).
class DepthMapCollider final : public SignedDistanceShape {
 public:
  DepthMapCollider() = default;
  DepthMapCollider(std::vector<DepthMap> maps, int normal_resolution = 256);

  // Rule (2) over all maps, serial (thread-safe: const and allocation-free). Non-finite
  // points give {distance = FLT_MAX, valid = false}; points no map has an opinion about give
  // valid = false with distance FLT_MAX; a point that only "far outside" votes claim gives
  // valid = false too (it is outside and far). Returned normals are unit, collider space.
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;
  ColliderSample sample(glm::vec3 local_point) const;

  // Which vote decides sample(p): a map's own vote (eq. (1) or the §4.3 cube distance), a
  // margin-ring vote (MapSpec::margin: a guess from the nearest silhouette point, taken only where
  // no map sees the point outside), or none (no finite answer). The coverage check (coverage.hpp)
  // holds ring answers to a stricter standard.
  enum class Decider { map, ring, none };
  Decider decider(glm::vec3 local_point) const;

  const std::vector<DepthMap>& maps() const { return maps_; }
  int normalResolution() const { return normal_resolution_; }
  // Number of single depth maps in the paper's sense (front_back16 = 2, cube8 = 6).
  int depthMapCount() const;
  // Texel bytes of all maps. The normal index texture (12·R_n² bytes as RGB float32, 768 KiB
  // at 256²) is shared by every collider with the same R_n and is not counted.
  std::size_t bytes() const;

 private:
  std::vector<DepthMap> maps_;
  int normal_resolution_ = 256;
  std::vector<glm::vec3> normal_table_;  // l1NormalTexture(normal_resolution_)
  // Per map, per texel: the depth bits its votes read (depth_map.cpp, voteWord), a dense copy
  // that the lookups read instead of the whole texels.
  std::vector<std::vector<std::uint32_t>> vote_words_;
};

// ---- Baking (§4.1, §4.3): CPU rasterizer ----------------------------------------------

// Triangle mesh as plain arrays (no assimp here): positions and 3 indices per triangle.
// Closed meshes with consistent winding; outward is counter-clockwise, and a mesh wound
// the other way round throughout (negative signed volume) is detected and flipped.
struct MeshView {
  std::span<const glm::vec3> positions;
  std::span<const std::uint32_t> indices;  // size multiple of 3, each < positions.size()
};

// Orthographic view volume: a box with centre, view direction `forward` (depth grows along
// it) and `up` (re-orthogonalised); half_extent = (right, up, depth) half sizes, collider units.
struct OrthoView {
  glm::vec3 center{0.0f};
  glm::vec3 forward{0.0f, 0.0f, 1.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  glm::vec3 half_extent{1.0f};
};

// Depth cube volume: box centre and half sizes (s_x, s_y, s_z).
struct CubeView {
  glm::vec3 center{0.0f};
  glm::vec3 half_extent{1.0f};
};

enum class MapKind : std::uint32_t { ortho = 0, cube = 1 };

struct MapSpec {
  MapKind kind = MapKind::ortho;
  DepthMapFormat format = DepthMapFormat::front_back16;  // cube: always cube8
  DepthCompare compare = DepthCompare::less;             // ignored for front_back16
  OrthoView ortho{};
  CubeView cube{};
  int resolution = 256;  // texels per side, 4..4096
  // Ortho maps: collider units by which every triangle's texel cover is widened (0 = the
  // conservative cover alone). A texel within `margin` of the silhouette then holds the depth of
  // the nearest silhouette point instead of background, so a point outside the collider but
  // within `margin` of it gets a finite distance (the depth difference along the map's axis to
  // that silhouette point) instead of "beyond reach": a projection shortens distances, so a ray
  // passing farther than `margin` from the collider's silhouette still means the point is
  // farther than `margin` from the collider, and "invalid = far outside" stays true. Give it the
  // SPH support radius. Cubes ignore it (their rays start inside the volume).
  float margin = 0.0f;
};

struct BakeDesc {
  int normal_resolution = 256;  // R_n for indexed formats, 2..256
  int threads = 0;              // 0 = all hardware threads
};

struct BakeStatus {
  std::string error;                     // empty = success; names the bad field/value/triangle
  std::size_t degenerate_triangles = 0;  // zero-area triangles skipped
  bool ok() const { return error.empty(); }
};

// Renders `mesh` into every map of `specs`. Errors (empty mesh, index out of range,
// non-finite position, bad spec) leave `out` untouched. encloses_collider is set when the
// map's view volume contains the mesh bounds.
BakeStatus bakeDepthMaps(const MeshView& mesh, std::span<const MapSpec> specs, const BakeDesc& desc,
                         DepthMapCollider& out);

// Axis-aligned bounds of the mesh (vertices referenced by indices).
struct Bounds {
  glm::vec3 lo{0.0f}, hi{0.0f};
};
Bounds meshBounds(const MeshView& mesh);

// One depth cube (Kolb §4.1, format cube8) centred at `center` over the box of `half_extent`.
// GREATER when the centre is inside the collider, LESS when it is outside (a concave region's
// cavity, seen from within).
MapSpec cubeMapSpec(glm::vec3 center, glm::vec3 half_extent, int resolution, DepthCompare compare);

// Default set, §5.2: three front-back pairs along x, y, z in `format` (float32/fixed8 give a
// LESS and a GREATER map per axis) plus, when with_cube, one depth cube at the bounds centre
// (GREATER: the centre is assumed inside; pass with_cube = false for shapes where it is not).
// Volumes are the bounds padded by `padding` (fraction of the largest extent) plus two texels.
std::vector<MapSpec> defaultMapSpecs(const Bounds& bounds, int resolution,
                                     DepthMapFormat format = DepthMapFormat::front_back16, bool with_cube = false,
                                     float padding = 0.05f);

// Parses a --maps SPEC: comma-separated items, each one of
//   "axes"          three front-back pairs along x,y,z (in the chosen --format)
//   "x","y","z"     one front-back pair along that axis
//   "cube"          a GREATER depth cube at the bounds centre over the padded bounds
//   "cube-less"     a LESS depth cube at the bounds centre
//   "cube@X:Y:Z:H"  a LESS depth cube centred at (X,Y,Z) with half size H (concave regions)
//   "cube@X:Y:Z:H:N" the same with its own resolution N (4..4096) instead of `resolution`
// ("auto", the bake-collider default, is resolved by chooseConcaveCubes in coverage.hpp first: it
// needs the mesh, not only its bounds.)
// Error names the bad item.
bool parseMapSpec(const std::string& spec, const Bounds& bounds, int resolution, DepthMapFormat format,
                  std::vector<MapSpec>& out, std::string& error);

// ---- Files: "FLDMAPS\0", version, maps, source record, FNV-1a checksum ----------------

// Version 2 adds the source record after the maps (version 1 files, without it, still load).
inline constexpr std::uint32_t kColliderFileVersion = 2;

// Where a baked collider came from, so a changed model or changed bake parameters are detected
// (fluid/collide/collider_cache.hpp). Empty for colliders baked without a record.
struct ColliderSource {
  std::string model;                // the model file's name as the baker was given it
  std::uint64_t model_fnv1a64 = 0;  // FNV-1a 64 of the model file's bytes
  std::string recipe;               // bake parameters, canonical text (bakeRecipeText)
  bool empty() const { return model.empty() && model_fnv1a64 == 0 && recipe.empty(); }
};

struct FileStatus {
  std::string error;  // empty = success; names file and field
  bool ok() const { return error.empty(); }
};
enum class Overwrite { refuse, replace };

FileStatus saveCollider(const std::filesystem::path& path, const DepthMapCollider& collider,
                        Overwrite overwrite = Overwrite::refuse, const ColliderSource& source = {});
// Rejects wrong magic, version, sizes, truncation, trailing bytes, a malformed source record and
// checksum mismatch. `source` (optional) receives the source record (empty for version 1 files).
FileStatus loadCollider(const std::filesystem::path& path, DepthMapCollider& out, ColliderSource* source = nullptr);
// In-memory forms used by the file functions (and the truncation/garbage tests).
std::vector<std::uint8_t> serializeCollider(const DepthMapCollider& collider, const ColliderSource& source = {});
FileStatus deserializeCollider(std::span<const std::uint8_t> bytes, const std::string& name, DepthMapCollider& out,
                               ColliderSource* source = nullptr);

// ---- Batch queries and the particle step ----------------------------------------------

struct ParallelDesc {
  int threads = 0;           // 0 = the calling TBB arena (all threads by default); n > 0: an arena of n threads
  std::size_t grain = 4096;  // points per task
};

// Splits the span into chunks and calls shape.query on each, on up to `threads` threads.
// Results do not depend on the thread count. Returns the number of non-finite input points
// (their samples are invalid; nothing NaN is written).
std::size_t queryParallel(const SignedDistanceShape& shape, std::span<const glm::vec3> local_points,
                          std::span<ColliderSample> out, const ParallelDesc& desc = {});

// World-space query of a posed collider: points go to collider space (scratch, caller-owned,
// resized once), normals come back in world space. Returns the non-finite count.
std::size_t queryWorld(const SignedDistanceShape& shape, const ColliderPose& pose,
                       std::span<const glm::vec3> world_points, std::span<ColliderSample> out,
                       std::vector<glm::vec3>& scratch, const ParallelDesc& desc = {});

// Caller-owned scratch for collideParticles (grows once, reused every step).
struct CollideScratch {
  // Per particle, what the last call decided (none where nothing happened or the particle was
  // culled): lets a caller sum what each reaction took from the particles, serially in index order
  // (fluid/blob reports that momentum to the rigid body behind the collider).
  std::vector<CollisionOutcome> outcome;
};

struct CollideDesc {
  CollisionMaterial material{};
  float dt = 1.0f / 60.0f;  // s
  float skin = 1e-3f;       // collider units pushed beyond the surface
  // Beyond the paper: when > 0, a particle whose step is longer than max_step is also sampled
  // along the step every max_step (at most 4096 samples), and the first inside sample is used as
  // the predicted one, whether or not the end point is inside: so it cannot tunnel through walls
  // thinner than its step, neither with both ends outside nor with its end point past the middle
  // of the wall (there the end sample's normal points out of the far face). 0 = the paper's two
  // samples only.
  float max_step = 0.0f;
  // Optional cull (beyond the paper): a collider-space box outside which `shape` never reports a
  // point inside (distance < 0), e.g. blobDepthMapBounds. Every sample of a particle lies on its
  // step, so a step that misses the box cannot collide and is skipped without a query: the same
  // results for less work where most particles are far from the collider. An empty box (lo > hi on
  // some axis) culls every step. Ignored unless `bounded`.
  bool bounded = false;
  Bounds inside{};
  ParallelDesc parallel{};
};

struct CollideCounts {
  std::size_t reacted = 0, pushed_out = 0;
  // Previous and predicted positions with an inf or NaN coordinate (none counted in culled steps).
  std::size_t non_finite = 0;
  std::size_t swept = 0;  // collisions found only by the max_step sampling
};

// §3.3.2 double check for a batch: samples the collider at previous and predicted world
// positions (moving collider: the pose is applied before the lookup, its velocity is the
// rest frame of the reaction) and calls resolveCollision; positions/velocities are updated
// in place. Spans must have equal sizes. The previous position is sampled only where the
// predicted one (or a swept sample) is inside: elsewhere resolveCollision does not read it.
// Particles are independent: the results do not depend on desc.parallel.
CollideCounts collideParticles(const SignedDistanceShape& shape, const ColliderPose& pose,
                               std::span<const glm::vec3> previous_positions, std::span<glm::vec3> predicted_positions,
                               std::span<glm::vec3> predicted_velocities, const CollideDesc& desc,
                               CollideScratch& scratch);

// ---- Reach culling: a coarse grid of cells the maps place beyond reach -----------------

struct ReachGridDesc {
  float reach = 0.0f;                // distances >= reach are "beyond reach" for the caller (SPH: the support H)
  float cell = 0.0f;                 // cell edge (collider units); 0 = reach / 4
  std::size_t max_cells = 1u << 21;  // beyond it the edge along the axis with the most cells grows
};

// A static depth-map collider answered only where its answer can matter to a caller that treats
// every distance >= reach like "beyond reach" (the SPH boundary: no boundary volume, no collision,
// no tunnelling test beyond the support). Points outside `box` answer {FLT_MAX, invalid} without a
// lookup (the caller promises every point outside is beyond reach, e.g. the intersection of the
// ortho maps' view volumes grown by reach - margin), as do points in a grid cell that the maps
// themselves place at distance >= reach: at construction each cell's image in every map (its texel
// rectangle and depth range, or the cube texels its directions reach) bounds every vote rule (2)
// can take there, and a cell is "far" when one vote that is never invalid and never a margin-ring
// vote is >= reach everywhere in it and every vote that can be >= 0 there is >= reach (so rule (2)'s
// winner is, and DepthMapCollider::sample would answer a distance >= reach). Everywhere else the
// full sample. So for such a caller the answers equal the collider's, at a fraction of the lookups:
// water far from a surface (most of a jet, the upper layers in a basin) costs one cell test.
class ReachCulledCollider final : public SignedDistanceShape {
 public:
  ReachCulledCollider(std::shared_ptr<const DepthMapCollider> inner, Bounds box, const ReachGridDesc& desc);
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;
  // The answer for one point: the collider's sample, or {FLT_MAX, invalid} when culled.
  ColliderSample sample(glm::vec3 local_point) const;
  // True when `local_point` is culled (outside the box or in a far cell).
  bool culled(glm::vec3 local_point) const;
  const Bounds& box() const { return box_; }
  glm::vec3 cell() const { return cell_; }
  glm::ivec3 cells() const { return dims_; }
  // Fraction of the grid's cells that are far (the rest query the maps).
  double farFraction() const;

 private:
  static constexpr std::size_t kOutside = ~std::size_t{0};
  // The cell holding `local_point` (x fastest), kOutside outside the box (or NaN).
  std::size_t cellOf(glm::vec3 local_point) const;
  bool farCell(std::size_t cell) const;  // kOutside counts as far

  std::shared_ptr<const DepthMapCollider> inner_;
  Bounds box_;
  glm::vec3 cell_{1.0f}, inv_cell_{1.0f};
  glm::ivec3 dims_{0};
  std::vector<std::uint64_t> far_bits_;  // bit per cell, x fastest: 1 = every point beyond reach
};

// ---- Exact reference: signed distance to a closed triangle mesh (BVH) ------------------

// Unsigned distance from a BVH closest-point search; the sign from ray-crossing parity
// (majority of three fixed rays). Used by tests, the accuracy table and the benchmark.
class MeshDistance final : public SignedDistanceShape {
 public:
  explicit MeshDistance(const MeshView& mesh);
  void query(std::span<const glm::vec3> local_points, std::span<ColliderSample> out) const override;
  ColliderSample sample(glm::vec3 p) const;
  // Brute force over all triangles (no BVH), for checking the BVH and for the benchmark.
  ColliderSample sampleBruteForce(glm::vec3 p) const;
  // The first surface crossing of the ray origin + t·dir (t > 0, in units of |dir|): its t, or
  // +inf when the ray misses. What a depth cube centred at `origin` records along that ray (§4.3);
  // fluid/collide/coverage.cpp predicts the votes of a candidate cube with it.
  float firstHit(glm::vec3 origin, glm::vec3 dir) const;
  // Unsigned distance to the nearest triangle, or `limit` when none is nearer (the search prunes
  // at the limit, so far points cost little; no inside test).
  float unsignedDistance(glm::vec3 p, float limit = FLT_MAX) const;
  // Bytes the BVH and its triangles take (the exact fallback's memory, docs/collide.md).
  std::size_t bytes() const { return (a_.size() * 3) * sizeof(glm::vec3) + nodes_.size() * sizeof(Node); }

 private:
  struct Node {
    glm::vec3 lo, hi;
    std::uint32_t first, count;  // leaf: triangle range; inner: first = right child, count = 0
  };
  std::vector<glm::vec3> a_, b_, c_;  // triangles (degenerate ones kept: they still bound)
  std::vector<Node> nodes_;
  // Squared distance to the nearest triangle (closest_point set) when it is below `best`, else `best`.
  float closest(glm::vec3 p, glm::vec3& closest_point, float best = FLT_MAX) const;
  int crossings(glm::vec3 origin, glm::vec3 dir) const;
  bool inside(glm::vec3 p) const;
};

}  // namespace fluid
