#pragma once
// fluid/surface: particles -> indexed triangle mesh by marching slices
// (Rosenberg & Birdwell 2008, "Real-time particle isosurface extraction"; Algorithm 1 restated
// in DESIGN.md), with block subdivision (§3), the 2D-projection 1D-lookup particle cache (§6),
// back-to-front output (§5) and one oneTBB task per block (Janisz thesis §3.2.6).
//
// Field (paper §2): f(r) = s_i * ((r/(sqrt2 Rc_i))^4 - (r/(sqrt2 Rc_i))^2 + 1/4) for r < Rc_i,
// 0 otherwise, with Rc_i = Rc * radiusScale_i and s_i = strength_i. The surface is f = T; a
// corner is inside when f > T (strictly). Corners lie on the global lattice at integer
// multiples of S on every axis, so any block size gives the same triangles.
//
// Usage (one extractor per caller, reused every frame; it and the mesh keep their capacity, so
// after the first frames nothing is allocated):
//   fluid::SurfaceExtractor extractor;
//   fluid::SurfaceMesh mesh;
//   fluid::SurfaceStatus st = extractor.extract({fluid::pointView(positions)}, params, mesh);
//
// Custom field/vertex routines (paper §7, tentacle texturing) are compile-time policies: see
// fluid/surface/marching_slices_policy.hpp. The built-in one interpolates a per-particle vec4
// (colour, uv, ...) weighted by each particle's field contribution when `user` is given.

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace fluid {

// Particle positions read in place, meshoptimizer's convention (vertex_positions, vertex_count,
// vertex_positions_stride): point i's x, y, z are the three floats at byte offset i * stride from
// `data`. Borrowed, never copied by extract(); the caller's store (the SPH's vec3 positions, the
// goo's, a NumPy (n, 3) array) is the one layout. stride: bytes, >= 12 and a multiple of 4.
struct PointView {
  const float* data = nullptr;  // x of point 0; may be null when count == 0
  std::size_t count = 0;
  std::size_t stride = sizeof(float) * 3;

  std::size_t size() const { return count; }
  bool empty() const { return count == 0; }
  // Point i's coordinate on axis a (0 x, 1 y, 2 z). No checks: i < count, a < 3.
  float at(std::size_t i, int a) const {
    return reinterpret_cast<const float*>(reinterpret_cast<const char*>(data) + i * stride)[a];
  }
  glm::vec3 operator[](std::size_t i) const { return {at(i, 0), at(i, 1), at(i, 2)}; }
};

// A view of packed vec3 positions (glm::vec3 is three floats, stride 12).
inline PointView pointView(std::span<const glm::vec3> points) {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
  return {points.empty() ? nullptr : &points.data()->x, points.size(), sizeof(glm::vec3)};
}

// Particle input, borrowed for the duration of one extract() call. positions: world units, finite.
// Optional arrays are empty or have positions.count entries.
struct SurfaceInput {
  PointView positions{};
  std::span<const float> strength{};     // s_i > 0, finite; default 1
  std::span<const float> radiusScale{};  // Rc_i = Rc * scale_i, scale_i > 0, finite; default 1
  std::span<const glm::vec4> user{};     // interpolated onto vertices (SurfaceMesh::attributes)
  // Anisotropic kernels (Yu & Turk 2013, §5; fluid/sph/anisotropy.hpp's `g`, with `positions` its
  // smoothed centres x̄): particle i's term becomes f(|g_i (c - x_i)|), i.e. u = |g_i d|^2 / (2 Rc_i^2)
  // in the header's f, and 0 where |g_i d| >= Rc_i, an ellipsoid of semi-axes Rc_i a_k for
  // g_i = R diag(1/a_k) R^T. Empty: spheres. Each g_i symmetric, finite, its smallest eigenvalue
  // >= 1/64 (no semi-axis longer than 64 Rc_i). The §6 particle cache and the blocks' margins
  // are sized by each ellipsoid's bounding sphere (Rc_i / smallest eigenvalue); the field is summed
  // through the cache (SurfaceFieldRoute is not consulted) and the outputs stay closed, oriented
  // and thread-count invariant. Marching slices only (the baselines refuse it).
  std::span<const glm::mat3> stretch{};
};

enum class SurfaceOrder : std::uint8_t {
  none,         // sweep +z, blocks in lattice order
  backToFront,  // sweep along the axis nearest the view, farthest first (paper §5)
  frontToBack,  // the reverse, for early-z with opaque surfaces
};

// How a corner's field is summed and which cubes are visited. The first three routes are exact
// (every particle within Rc_i by influences()'s double predicate, summed in (z, index) order with
// the same float expressions, gradient included), so the corner values and every vertex's bits are
// the same (tests compare them); they differ in cost and, for the dense scan, in the order of
// triangles within a slab and in the components §4 seeding cannot reach. valueScan trades that
// for speed: the field's value alone, by a float predicate, and normals from central differences
// of it (what the dense-lattice peer and Flying Edges do). docs/surface.md ("Field routes") has
// the measurements.
enum class SurfaceFieldRoute : std::uint8_t {
  // denseScan. (Policies with per-corner data, Policy::kHasUser or SurfaceInput::user, and
  // anisotropic kernels take particleCache whatever this says.)
  automatic,
  // The paper's §6 2D-projection 1D-lookup cache, walked per corner the sweep needs (Figure 7),
  // from §4's seeds (Alg. 1).
  particleCache,
  // Per slice, the block's particles in (z, index) order each add their term to the corners of
  // their disc in that slice (8 corners of a row at once), then Alg. 1's walk from §4's seeds; the
  // whole block's field is summed up front when it fits 8 MB per worker, else each slice as the
  // walk takes it up (and value-only slices for seeding).
  sliceSplat,
  // The slice splat, one slice at a time in sweep order, and no seeding and no walk: every
  // interior cube is classified from bit masks of each row's inside corners (the row idea of
  // Flying Edges) and only the crossed ones are polygonized. The walk's triangles and vertex bits,
  // in row order within each slab; and, unlike the walk, also the components where several
  // particles' fields exceed T away from each one's nearest corner (the dense oracle's
  // triangles). Two slices alive per worker.
  denseScan,
  // The dense scan over a value-only splat: each term added where its float r^2 < float(Rc_i^2)
  // (not influences()'s double predicate), no gradient planes, and each vertex's normal
  // interpolated from central differences of the value at its edge's two corners (so the splat
  // also sums one corner around the interior, and the blocks' margins and particle lists grow by
  // one cube). The dense oracle's triangles wherever no corner lies within float rounding of T;
  // normals within a few degrees of the analytic ones (tests measure both). Four value slices
  // alive per worker.
  valueScan,
};

struct SurfaceParams {
  float rc = 3.0f;         // cutoff radius Rc, world units, > 0
  float threshold = 0.2f;  // T, in (0, 0.25 * max strength); 0.2 gives radius 0.975 Rc/3
  float cube = 1.0f;       // cube edge S, world units, > 0
  // Largest interior cubes per block edge, else [4, 1024]; 0 = auto: max(128, 12 ceil(Rc/S)),
  // so the margins (about ceil(Rc/S) cubes) stay a modest share of each block, and a set fitting one
  // block is halved when the halves stay >= 5 margins wide: along its longest axis for the walking
  // routes, for the dense scan along the first wide enough of the sweep axis, y, x. The
  // particles' lattice extent is cut into equal blocks no larger than this. Never depends on
  // `threads`, so the output does not either.
  int blockCubes = 0;
  // 0 = as many as the calling thread's oneTBB task arena has slots (outside one: all the cores the
  // process may run on, its CPU affinity, as tbb::parallel_for would use), else 1..256
  int threads = 0;
  SurfaceOrder order = SurfaceOrder::none;
  glm::vec3 eye{0.0f};                   // for ordering: eye position (blocks sorted by distance)
  glm::vec3 viewDir{0.0f, 0.0f, -1.0f};  // for ordering: view direction (need not be unit)
  // With an order: one index range per slab per block, slabs in sweep order, and triangles
  // within a slab sorted by centroid depth along viewDir (farthest first for backToFront).
  bool exactSlabOrder = false;
  // Output positions are written as float(p - origin); put it near the particles when they sit
  // far from zero (e.g. 1e5) so float vertices keep their precision. Double precision inside.
  double originX = 0.0, originY = 0.0, originZ = 0.0;
  // Testing aid: run the portable (SSE2) copy of the block mesher even where the CPU has AVX2
  // (with BMI1/BMI2/POPCNT): particle-cache fill, triangle index writes and vertex interpolation.
  // Both copies give the same bits (a test checks it); the AVX2 one does fewer instructions.
  bool portableKernels = false;
  SurfaceFieldRoute fieldRoute = SurfaceFieldRoute::automatic;
};

// Index range [first, first + count) into SurfaceMesh::indices.
struct IndexRange {
  std::uint32_t first = 0;
  std::uint32_t count = 0;
};

struct SurfaceBlockRange {
  int bx = 0, by = 0, bz = 0;                  // block index in the block grid (sweep frame)
  glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};  // interior box, world units minus origin (for culling)
  IndexRange indices;                          // its triangles
  std::uint32_t firstVertex = 0, vertexCount = 0;
  std::uint32_t firstSlabRun = 0, slabRunCount = 0;  // into SurfaceMesh::slabRuns
};

// A run of consecutive triangles of one slab (global slab coordinate along the sweep axis).
// With exactSlabOrder each block has one run per non-empty slab, in sweep order.
struct SurfaceSlabRun {
  std::int32_t slab = 0;
  IndexRange indices;
};

struct SurfaceStats {
  std::uint64_t cubesVisited = 0;       // cubes popped and marked done (margin included); scanned: interior cubes
  std::uint64_t cornersEvaluated = 0;   // field evaluations stored in corner caches; scanned: interior corners
  std::uint64_t seedEvaluations = 0;    // field evaluations while seeding (not cached)
  std::uint64_t particlesLookedUp = 0;  // particle contributions summed (exact lookups)
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::uint32_t blocks = 0;
  std::uint32_t splatBlocks = 0;      // blocks whose field was summed by slice splat (SurfaceFieldRoute)
  std::uint32_t scannedBlocks = 0;    // blocks whose interior cubes were all scanned (SurfaceFieldRoute::denseScan, valueScan)
  std::uint32_t maxActiveSlices = 0;  // most slice caches alive at once in one block
  std::uint64_t slabReversals = 0;    // times the sweep stepped down to a slab below (§4, Fig. 4)
  // Working memory, bytes actually touched: largest single block, and summed over all blocks
  // processed concurrently (one per worker).
  std::uint64_t cornerCacheBytesPeakBlock = 0;    // slice caches (index arrays, corner caches, z offsets)
  std::uint64_t particleCacheBytesPeakBlock = 0;  // projection slice + column lists + block particles
  std::uint64_t workingBytesAllWorkers = 0;       // sum over workers of their peak (both caches)
  // Where the time went, ms of steady clock. The block phases are filled by approach 1 (this
  // extractor's marching slices; 0 for the approach-2 baseline) and summed over blocks, so on
  // several threads they add up to more than the call's wall time.
  double prepareMs = 0;     // checks, sweep frame, particles sorted into (z, index) order, block lists (§3)
  double cacheBuildMs = 0;  // §6 particle caches of all blocks (slice splat: block setup and up-front fields)
  double seedMs = 0;        // §4 seeding
  double marchMs = 0;       // Alg. 1 sweeps: corner evaluations (§6 lookups), cubes, triangles, slab order
  double gatherMs = 0;      // block outputs joined into the mesh
};

struct SurfaceMesh {
  std::vector<glm::vec3> positions;   // float(p - origin)
  std::vector<glm::vec3> normals;     // unit, outward (down the field gradient)
  std::vector<glm::vec4> attributes;  // one per vertex when SurfaceInput::user was given, else empty
  // Global lattice edge of each vertex: equal keys are the same point (blocks duplicate the
  // vertices on their seams). Packs corner (i, j, k) mod 2^20 and axis; for welding.
  std::vector<std::uint64_t> edgeKeys;
  std::vector<std::uint32_t> indices;     // triangles, counter-clockwise seen from outside
  std::vector<SurfaceBlockRange> blocks;  // in emission order
  std::vector<SurfaceSlabRun> slabRuns;
  SurfaceStats stats;
  void clear();
};

// Empty error == success; otherwise a complete message naming the field and value.
struct SurfaceStatus {
  std::string error;
  bool ok() const { return error.empty(); }
};

// Checks params and input (lengths, NaN/inf, ranges). extract() calls it too.
SurfaceStatus validateSurface(const SurfaceInput& input, const SurfaceParams& params);

// The worker count an extraction with `params` uses when called from this thread: params.threads,
// or for 0 the slots of the calling thread's oneTBB arena (the rule on SurfaceParams::threads). It
// sizes the extraction's arena and does not read tbb::global_control: under a cap of N (fluiddemo
// --threads N) oneTBB still runs at most N threads in it.
int surfaceThreads(const SurfaceParams& params);

namespace detail {
struct ExtractorState;
}

// Owns all scratch (block lists, per-worker slice pools and particle caches, per-block outputs,
// the oneTBB arena). Not thread-safe: one extract() at a time per extractor.
class SurfaceExtractor {
 public:
  SurfaceExtractor();
  ~SurfaceExtractor();
  SurfaceExtractor(SurfaceExtractor&&) noexcept;
  SurfaceExtractor& operator=(SurfaceExtractor&&) noexcept;

  // Replaces `out`'s contents (keeping its capacity). On error `out` is cleared. The output is
  // identical for every thread count; for other block sizes it is the same triangle set.
  SurfaceStatus extract(const SurfaceInput& input, const SurfaceParams& params, SurfaceMesh& out);

  // Internal scratch (public only so extractWithPolicy<Policy>() can reach it); do not touch.
  std::unique_ptr<detail::ExtractorState> state;
};

// Field at lattice corner (i, j, k), i.e. at (i S, j S, k S): the paper's f summed over all
// particles by brute force, with the same arithmetic as the extractors (for tests and tools).
float surfaceFieldAtCorner(const SurfaceInput& input, const SurfaceParams& params, std::int64_t i, std::int64_t j,
                           std::int64_t k);

}  // namespace fluid
