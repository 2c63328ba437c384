#pragma once
// Coverage of a depth-map collider's near-surface band, and the automatic choice of the extra depth
// cubes that cover the concave regions the axis maps cannot see (Kolb et al. 2004 §4.1: "problems
// can also be caused by local surface concavities. In many cases, these local concavities can be
// reconstructed with properly placed depth map view volumes").
//
// A caller such as the SPH boundary reads a collider only within its reach (the kernel support
// H = 4r): every point that close to the surface must answer a finite distance with the right sign,
// near the true one. Six axis maps leave holes there: in a torus's hole the axial map sees no
// surface (background: "far outside") while the two others see the point between their surfaces, so
// rule (2) answers "beyond reach", or, with a margin ring, the ring's guess (the depth offset to the
// nearest silhouette point, not a distance to the surface). A LESS depth cube centred in the cavity
// measures along its rays (§4.3) from a point that sees the cavity's walls, so its votes there are
// the distances to the walls, and rule (2) takes them (the smallest vote >= 0 wins).
//
// Everything here is deterministic (seeded lattice, serial choices) and independent of the thread
// count; it needs the mesh (the exact distance, MeshDistance), so it runs at bake time only.

#include "fluid/collide/collide.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace fluid {

struct CoverageDesc {
  float reach = 0.16f;              // the band |d| < reach, collider units (bake-collider: the SPH support 4r)
  float tolerance = 0.0f;           // collider units; 0 = coverageTolerance(specs) of the maps measured
  std::size_t max_points = 120000;  // lattice points over the bounds padded by reach, at most (about)
  std::uint32_t seed = 1;           // lattice jitter (std::mt19937)
  int threads = 0;                  // 0 = all hardware threads
};

// Seeded jittered lattice points within `reach` of the surface and their exact signed distances
// (MeshDistance: the normal is the outward direction of the distance gradient). The lattice spacing
// is the larger of reach / 4 and what max_points over the padded bounds allows.
struct NearSurfaceSamples {
  std::vector<glm::vec3> points;
  std::vector<ColliderSample> exact;
  float reach = 0.0f;
  float spacing = 0.0f;
  std::size_t lattice = 0;  // lattice points tried
};
NearSurfaceSamples nearSurfaceSamples(const MeshDistance& exact, const Bounds& bounds, const CoverageDesc& desc);

// A near point is covered when the collider answers a finite distance of the exact distance's sign
// (either sign within `tolerance` of the surface: texel quantisation). `bake-collider --strict`
// demands that of every near point.
//
// It is measured when, besides, the answer is a distance a caller with this reach can use:
//  - a map's own vote (eq. (1), a cube ray) is a distance along its axis or ray: at least the true
//    distance, within √3 of it for a plane seen by the best of three axes. It fails only when it
//    puts the point beyond reach and is more than twice its distance (plus tolerance): then no map
//    sees the surface near the point (a cavity floor seen past its wall, a grazing ray), and for the
//    SPH that is a hole as much as "inf" is;
//  - a margin-ring vote (DepthMapCollider::Decider::ring) is a guess from the nearest silhouette
//    point, which in a torus's hole reads about 0 for every point: it must be within a factor of
//    two of the true distance (up to tolerance) either way.
// The automatic cubes aim at the points that are not measured (a cube's votes there are measured).
bool coveredSample(const ColliderSample& got, const ColliderSample& exact, float tolerance);
bool measuredSample(const ColliderSample& got, const ColliderSample& exact, float tolerance, float reach, bool ring);

struct CoverageReport {
  std::size_t near = 0;          // near-surface points measured
  std::size_t beyond_reach = 0;  // not covered: no finite distance ("inf")
  std::size_t wrong_sign = 0;    // not covered: finite, the other sign, |exact| >= tolerance
  std::size_t off_distance = 0;  // covered, not measured: a map's vote beyond reach and over twice the distance
  std::size_t ring_guess = 0;    // covered, not measured: a margin-ring vote off by more than a factor of two
  double mean_abs_error = 0.0;   // |answer − exact| over the finite answers
  double max_abs_error = 0.0;
  std::vector<std::uint32_t> unmeasured;  // indices into the samples of every point not measured, in order
  std::uint32_t first_uncovered = 0;      // index of the first point not covered (when there is one)
  std::size_t uncovered() const { return beyond_reach + wrong_sign; }
  double coveredShare() const { return near == 0 ? 1.0 : 1.0 - static_cast<double>(uncovered()) / near; }
  double measuredShare() const { return near == 0 ? 1.0 : 1.0 - static_cast<double>(unmeasured.size()) / near; }
};
// `maps`: the depth maps behind `shape`, which tell ring answers (default: `shape` itself when it is
// a DepthMapCollider; none otherwise, every answer judged as a map's).
CoverageReport measureCoverage(const SignedDistanceShape& shape, const NearSurfaceSamples& samples, float tolerance,
                               int threads = 0, const DepthMapCollider* maps = nullptr);

// One texel of the coarsest ortho map of `specs` (collider units), the depth maps' quantisation;
// for cubes alone one texel of the first cube's face at its half size.
float coverageTolerance(std::span<const MapSpec> specs);

struct ConcaveCubesDesc {
  float tolerance = 0.0f;  // as CoverageDesc::tolerance (0 = coverageTolerance of the base specs)
  int resolution = 256;    // the largest cube resolution; a cube gets the smallest power of two whose
                           // texels at the surface it sees are no larger than the ortho maps' (>= 16)
  int max_cubes = 8;
  int normal_resolution = 256;
  int threads = 0;
};

struct ConcaveCubesResult {
  std::vector<MapSpec> cubes;    // LESS cube8 maps added, in order (parseMapSpec of `items`)
  std::vector<DepthMap> maps;    // their baked maps
  std::string items;             // their --maps items, "cube@X:Y:Z:H:N,..." ("" when none)
  CoverageReport before, after;  // the base maps alone, and with the cubes
  BakeStatus status;             // a failed cube bake (then `cubes` holds those before it)
};

// Greedy choice (§4.1): while near points stay unmeasured and fewer than max_cubes were added, march
// from a sample of them away from the surface to the point of largest clearance (the middle of the
// cavity), predict with ray casts (MeshDistance::firstHit) what a LESS cube centred there would
// answer for each such point, take the centre that covers most, size its view volume to the
// points it covers and the walls behind them (short of enclosing the collider, so that its ray-sampled,
// non-conservative background never reads "far outside"), bake it, and keep it only when the
// count of points not measured drops by 0.2 % of the near points (and no point loses its cover). `base` are the maps
// baked from `base_specs` (`mesh`'s axis maps).
ConcaveCubesResult chooseConcaveCubes(const MeshView& mesh, const MeshDistance& exact,
                                      const NearSurfaceSamples& samples, std::span<const MapSpec> base_specs,
                                      std::span<const DepthMap> base, const ConcaveCubesDesc& desc);

// "cube@X:Y:Z:H:N" with the shortest decimal text of each float that reads back as the same float.
std::string cubeItemText(glm::vec3 center, float half_extent, int resolution);

}  // namespace fluid
