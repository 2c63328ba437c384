#pragma once
// Randomised property checks of the mesher (issue 15, item 4), shared by the CI slice in
// tests/surface/test_random_sets.cpp and the sweep `bench_surface_seeds --from A --to B`.
//
// One seed draws one particle set and its parameters (drawRandomSet): clusters, sheets, lines,
// points on lattice corners and planes (and one float step off them), far outliers, duplicates,
// a threshold the field meets exactly at corners, and mixtures with radius scales and strengths;
// spans of 1e-3 to 1e5 world units, far from the origin or near it, Rc / S whole (as the game's
// Rc = 4 S) or not, sweep frames of every view octant. checkRandomSet() then meshes it with the
// dense oracle and with marching slices at 1, 2 and 3 threads for three block sizes, and returns
// the first broken property (empty when all hold):
//   - every call succeeds;
//   - one thread: closed and consistently oriented (each directed edge met by exactly one
//     opposite one), no degenerate triangle, one position per lattice edge, outward (signed
//     volume > 0 about a point of the mesh);
//   - the same triangles (winding included) as the oracle, with the same vertex positions bit
//     for bit, for every block size (for a view order, the oracle of the set rotated into the
//     sweep frame: see checkRandomSet), except whole oracle components with no particle's nearest
//     corner inside, which the paper's seeding (§4) cannot find (compareWithOracle; counted);
//   - 2 and 3 threads give the one-thread mesh bit for bit (positions, normals, indices, keys).
// Not a failure, counted: seeds whose block sizes left out different such components (a block
// can reach one through its margin, where its field is partial; seam propagation then completes it).
#include "fluid/sph/anisotropy.hpp"
#include "fluid/surface/baselines.hpp"
#include "fluid/surface/detail/field.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace surface_test {

struct RandomSet {
  std::vector<glm::vec3> points;
  std::vector<float> strength, scale;
  fluid::SurfaceParams params;
  int blockSizes[3] = {0, 0, 0};  // 0 = auto
  std::string what;               // the kinds drawn, for messages
  std::vector<glm::mat3> stretch;  // anisotropic kernels (withStretch), else empty
  fluid::SurfaceInput input() const { return {fluid::pointView(points), strength, scale, {}, stretch}; }
};

namespace random_detail {

inline const char* const kKinds[] = {"cluster", "sheet", "line", "lattice", "outlier", "duplicates", "exactT", "mixed"};
constexpr int kKindCount = 8;

struct Draw {
  std::mt19937_64& rng;
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  int pick(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng); }  // [a, b]
  bool coin(double p) { return uni(0.0, 1.0) < p; }
};

// Adds one group of particles of `kind` around `c` (world units); s = cube edge, span = set size.
inline void addGroup(RandomSet& r, Draw& d, int kind, const double c[3], double s, double span) {
  auto push = [&](double px, double py, double pz) { r.points.push_back({float(px), float(py), float(pz)}); };
  // A coordinate snapped to the lattice (a multiple of S), sometimes one float step off it.
  auto snap = [&](double v) {
    float f = float(std::round(v / s) * double(float(s)));
    const int nudge = d.pick(0, 3);
    if (nudge == 1) f = std::nextafter(f, INFINITY);
    if (nudge == 2) f = std::nextafter(f, -INFINITY);
    return double(f);
  };
  switch (kind) {
    case 0: {  // cluster
      const int n = d.pick(1, 120);
      std::normal_distribution<double> g(0.0, span / 6.0);
      for (int i = 0; i < n; ++i) push(c[0] + g(d.rng), c[1] + g(d.rng), c[2] + g(d.rng));
      break;
    }
    case 1: {  // sheet: a disc, axis-aligned (its plane on the lattice or not) or tilted
      const int n = d.pick(3, 150);
      const int axis = d.pick(0, 2);
      const bool tilted = d.coin(0.4);
      const double plane = d.coin(0.5) ? snap(c[axis]) : c[axis];
      glm::dvec3 nrm(d.uni(-1, 1), d.uni(-1, 1), d.uni(-1, 1));
      nrm = glm::length(nrm) > 1e-3 ? glm::normalize(nrm) : glm::dvec3(0, 0, 1);
      for (int i = 0; i < n; ++i) {
        double q[3] = {c[0] + d.uni(-0.5, 0.5) * span, c[1] + d.uni(-0.5, 0.5) * span, c[2] + d.uni(-0.5, 0.5) * span};
        if (tilted) {
          const glm::dvec3 v(q[0] - c[0], q[1] - c[1], q[2] - c[2]);
          const glm::dvec3 w = v - glm::dot(v, nrm) * nrm;
          q[0] = c[0] + w.x, q[1] = c[1] + w.y, q[2] = c[2] + w.z;
        } else {
          q[axis] = plane;
        }
        push(q[0], q[1], q[2]);
      }
      break;
    }
    case 2: {  // line, along an axis (on lattice lines or not) or any direction
      const int n = d.pick(2, 100);
      const bool axial = d.coin(0.5);
      const int axis = d.pick(0, 2);
      const glm::dvec3 dir = glm::normalize(glm::dvec3(d.uni(-1, 1), d.uni(-1, 1), d.uni(-1, 1)) + 1e-3);
      const bool onLattice = d.coin(0.5);
      double base[3] = {c[0], c[1], c[2]};
      if (onLattice)
        for (double& b : base) b = snap(b);
      for (int i = 0; i < n; ++i) {
        const double t = d.uni(-0.5, 0.5) * span;
        double q[3] = {base[0], base[1], base[2]};
        if (axial)
          q[axis] += t;
        else
          q[0] += t * dir.x, q[1] += t * dir.y, q[2] += t * dir.z;
        push(q[0], q[1], q[2]);
      }
      break;
    }
    case 3: {  // lattice corners, half-cube points and one float step off them
      const int n = d.pick(1, 120);
      const int cells = std::max(1, int(span / s));
      for (int i = 0; i < n; ++i) {
        double q[3];
        for (int a = 0; a < 3; ++a) {
          q[a] = snap(c[a] + d.pick(-cells / 2, cells / 2) * s);
          if (d.coin(0.15)) q[a] += 0.5 * s;
        }
        push(q[0], q[1], q[2]);
      }
      break;
    }
    case 4: {  // a cluster and up to 3 single particles far out along one axis
      addGroup(r, d, 0, c, s, span * 0.5);
      const int k = d.pick(1, 3);
      for (int i = 0; i < k; ++i) {
        double q[3] = {c[0], c[1], c[2]};
        q[d.pick(0, 2)] += (d.coin(0.5) ? 1 : -1) * d.uni(3.0, 150.0) * s;
        push(q[0], q[1], q[2]);
      }
      break;
    }
    case 5: {  // duplicates: a few points, each several times (coincident particles)
      const int k = d.pick(1, 12);
      for (int i = 0; i < k; ++i) {
        const double q[3] = {c[0] + d.uni(-0.5, 0.5) * span, c[1] + d.uni(-0.5, 0.5) * span,
                             c[2] + d.uni(-0.5, 0.5) * span};
        const int times = d.pick(2, 9);
        for (int t = 0; t < times; ++t) push(q[0], q[1], q[2]);
      }
      break;
    }
    default:
      break;
  }
}

}  // namespace random_detail

// Everything is drawn from `seed` alone (std::mt19937_64 and libstdc++'s distributions).
inline RandomSet drawRandomSet(std::uint64_t seed) {
  using namespace random_detail;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 0x5eedull);
  Draw d{rng};
  RandomSet r;
  const int kind = int(seed % kKindCount);
  r.what = kKinds[kind];
  // Span 1e-3 .. 1e5 world units; 6 .. 30 cubes across, so the dense oracle stays small.
  const double span = std::pow(10.0, d.uni(-3.0, 5.0));
  const float s = float(span / d.uni(6.0, 30.0));
  fluid::SurfaceParams& p = r.params;
  p.cube = s;
  // Rc / S a whole number half the time (the game uses Rc = 4 S: reaches land on lattice planes).
  const bool whole = d.coin(0.5);
  p.rc = whole ? s * float(d.pick(1, 5)) : float(double(s) * d.uni(0.6, 4.5));
  p.threshold = d.coin(0.6) ? 0.2f : float(d.uni(0.02, 0.24));
  // Centre near the origin, a thousand cubes out, or up to 300000 cubes out (float positions
  // there are 1/30 of a cube apart); the output origin is moved there half the time.
  double c[3];
  const int where = d.pick(0, 2);
  for (double& v : c) v = where == 0 ? d.uni(-1, 1) * span : double(s) * d.uni(-1, 1) * (where == 1 ? 1e3 : 3e5);
  if (d.coin(0.5)) p.originX = c[0], p.originY = c[1], p.originZ = c[2];
  if (kind < 6) {
    addGroup(r, d, kind, c, s, span);
  } else if (kind == 6) {
    // Particles on lattice corners with T the value a lone particle gives at a corner d cubes
    // away along an axis, so corners lie exactly on the threshold (outside: inside is f > T).
    p.rc = s * float(d.pick(2, 4));
    const double q = std::round(c[0] / s) * double(s), w = std::round(c[1] / s) * double(s),
                 e = std::round(c[2] / s) * double(s);
    const std::vector<glm::vec3> lone = {{float(q), float(w), float(e)}};
    const std::int64_t ci = std::int64_t(std::floor(double(lone[0].x) / double(s) + 0.5)),
                       cj = std::int64_t(std::floor(double(lone[0].y) / double(s) + 0.5)),
                       ck = std::int64_t(std::floor(double(lone[0].z) / double(s) + 0.5));
    p.threshold = fluid::surfaceFieldAtCorner({fluid::pointView(lone)}, p, ci + 1, cj, ck);
    if (!(p.threshold > 0.0f && p.threshold < 0.25f)) p.threshold = 0.2f;
    const int n = d.pick(1, 40), cells = std::max(2, int(span / s));
    for (int i = 0; i < n; ++i) {
      const float px = float(q + d.pick(-cells / 2, cells / 2) * double(s));
      const float py = float(w + d.pick(-cells / 2, cells / 2) * double(s));
      const float pz = float(e + d.pick(-cells / 2, cells / 2) * double(s));
      r.points.push_back({px, py, pz});
    }
  } else {
    // Two or three groups of other kinds, with radius scales and strengths.
    const int groups = d.pick(2, 3);
    for (int g = 0; g < groups; ++g) {
      const int k = d.pick(0, 5);
      r.what += std::string("+") + kKinds[k];
      double cg[3];
      for (int a = 0; a < 3; ++a) cg[a] = c[a] + d.uni(-0.5, 0.5) * span;
      addGroup(r, d, k, cg, s, span * 0.5);
    }
    const bool scales = d.coin(0.7), strengths = d.coin(0.7);
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      if (scales) r.scale.push_back(float(d.uni(0.3, 2.0)));
      if (strengths) r.strength.push_back(float(d.uni(0.5, 2.0)));
    }
  }
  // Sweep frame: plain, or ordered for a random view (every octant and axis in turn).
  const int order = d.pick(0, 3);
  p.order = order == 0 ? fluid::SurfaceOrder::none
                       : (order == 3 ? fluid::SurfaceOrder::frontToBack : fluid::SurfaceOrder::backToFront);
  p.exactSlabOrder = order == 2;
  p.viewDir = glm::vec3(float(d.uni(-1, 1)), float(d.uni(-1, 1)), float(d.uni(-1, 1)));
  if (p.viewDir == glm::vec3(0.0f)) p.viewDir.z = -1.0f;
  p.eye =
      glm::vec3(float(c[0] - span * p.viewDir.x), float(c[1] - span * p.viewDir.y), float(c[2] - span * p.viewDir.z));
  p.portableKernels = d.coin(0.5);
  const char* const orderNames[] = {"unordered", "back-to-front", "exact slab order", "front-to-back"};
  r.what += std::string(", ") + orderNames[order] + (whole ? ", Rc/S whole" : "");
  r.blockSizes[0] = 0;
  r.blockSizes[1] = d.pick(4, 12);
  r.blockSizes[2] = d.pick(13, 48);
  return r;
}

// The set with anisotropic kernels (SurfaceInput::stretch), drawn from `seed`: odd seeds give
// each particle a random ellipsoid (a random rotation, semi-axis factors in [1/3, 3], a quarter of
// them spheres); even seeds take Yu & Turk's kernels of the set itself (fluid::computeAnisotropy,
// neighbourhood 1.5 Rc, k_n = 3 so small groups stretch too), centres included, as the game does.
inline void withStretch(RandomSet& r, std::uint64_t seed) {
  std::mt19937_64 rng(seed * 0x2545F4914F6CDD1Dull + 0xa11ull);
  random_detail::Draw d{rng};
  r.stretch.assign(r.points.size(), glm::mat3(1.0f));
  if (seed % 2 == 0) {
    fluid::AnisotropyParams a;
    a.radius = 1.5f * r.params.rc;
    a.k_n = 3;
    fluid::AnisotropyScratch scratch;
    fluid::Anisotropy out;
    if (fluid::computeAnisotropy(r.points, a, scratch, out)) {
      r.points = out.centre;
      r.stretch = out.g;
    }
    r.what += ", Yu & Turk kernels";
    return;
  }
  for (glm::mat3& g : r.stretch) {
    if (d.coin(0.25)) continue;
    glm::dquat q(d.uni(-1, 1), d.uni(-1, 1), d.uni(-1, 1), d.uni(-1, 1));
    if (glm::length(q) < 1e-3) continue;
    const glm::dmat3 rot = glm::mat3_cast(glm::normalize(q));
    const glm::dvec3 inv(1.0 / std::exp(d.uni(-std::log(3.0), std::log(3.0))),
                         1.0 / std::exp(d.uni(-std::log(3.0), std::log(3.0))),
                         1.0 / std::exp(d.uni(-std::log(3.0), std::log(3.0))));
    const glm::dmat3 m = rot * glm::dmat3(inv.x, 0, 0, 0, inv.y, 0, 0, 0, inv.z) * glm::transpose(rot);
    for (int c = 0; c < 3; ++c)
      for (int row = c; row < 3; ++row) g[c][row] = g[row][c] = float(m[c][row]);  // exactly symmetric
  }
  r.what += ", random ellipsoids";
}

// A check of the stretched field that shares no lookup with the extractors: every vertex of `m`
// (meshed from r.input() with r.params) lies on a lattice edge whose two corners are on opposite
// sides of T in the field summed over *all* particles (no bounding sphere, no cache), in the
// extractors' (z, index) order. A bounding radius too small for an ellipsoid would leave out
// terms and show here; the dense oracle would not see it, as it bounds the same way.
inline std::string checkCrossingsByBruteForce(const RandomSet& r, const fluid::SurfaceMesh& m) {
  namespace fd = fluid::detail;
  const fluid::SurfaceParams& p = r.params;
  const fd::SweepFrame frame = fd::chooseFrame(p);
  std::vector<glm::vec3> rotated(r.points.size());
  std::vector<glm::mat3> rotatedStretch(r.stretch.size());
  for (std::size_t i = 0; i < r.points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      rotated[i][a] = float(frame.sign[a]) * r.points[i][frame.axis[a]];
      for (int b = 0; b < 3 && !r.stretch.empty(); ++b)
        rotatedStretch[i][b][a] = float(frame.sign[a] * frame.sign[b]) * r.stretch[i][frame.axis[b]][frame.axis[a]];
    }
  fluid::SurfaceParams po = p;
  po.order = fluid::SurfaceOrder::none;
  std::vector<fd::Particle> ps;
  std::vector<fd::StretchTerm> terms;
  double rcMax = 0;
  fd::prepareParticles({fluid::pointView(rotated), r.strength, r.scale, {}, rotatedStretch}, po, fd::SweepFrame{}, ps,
                       rcMax, nullptr, &terms);
  const double s = p.cube;
  auto field = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    float v = 0, gx = 0, gy = 0, gz = 0;
    for (const fd::Particle& q : ps) fd::accumulateAt(q, terms.empty() ? nullptr : terms.data(), i, j, k, s, v, gx, gy, gz);
    return v;
  };
  const double origin[3] = {p.originX, p.originY, p.originZ};
  const std::int64_t wrap = std::int64_t(1) << 20;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const std::uint64_t key = m.edgeKeys[v];
    const int axis = int(key & 3u);
    const std::int64_t part[3] = {std::int64_t((key >> 42) & (wrap - 1)), std::int64_t((key >> 22) & (wrap - 1)),
                                  std::int64_t((key >> 2) & (wrap - 1))};
    std::int64_t c[3];
    for (int a = 0; a < 3; ++a) {
      // The frame lattice index near the vertex, then the representative of the key's residue.
      const double w = double(m.positions[v][frame.axis[a]]) + origin[frame.axis[a]];
      const double near = std::floor(double(frame.sign[a]) * w / s);
      const std::int64_t base = std::int64_t(near) - ((std::int64_t(near) - part[a]) % wrap + wrap) % wrap;
      c[a] = (std::int64_t(near) - base > wrap / 2) ? base + wrap : base;
    }
    std::int64_t d[3] = {c[0], c[1], c[2]};
    ++d[axis];
    const bool inA = field(c[0], c[1], c[2]) > p.threshold, inB = field(d[0], d[1], d[2]) > p.threshold;
    if (inA == inB) return "vertex " + std::to_string(v) + " sits on an edge whose corners are both " +
                           (inA ? "inside" : "outside") + " in the brute-force field";
  }
  return {};
}

// Caller-owned scratch: extractors stay warm across seeds.
struct RandomSetChecker {
  fluid::SurfaceExtractor slices[3];  // 1, 2, 3 threads
  fluid::BaselineExtractor dense;
  fluid::SurfaceMesh ref, mesh[3];
  std::vector<Tri> firstSet;  // the first block size's triangles (checkRandomSet)
};

// The oracle's triangles less `got`: must be whole connected components of the oracle mesh (welded
// by lattice edge), none of which holds a seeding corner (a particle's nearest corner) within its
// bounding box. Such a component lies where overlapping fields exceed T away from every particle's
// nearest corner; §4 seeds only from those corners, so marching slices cannot find it (the
// dense oracle visits every corner). `ghosts` counts them. Any other difference is an error.
inline std::string compareWithOracle(const std::vector<Tri>& got, const std::vector<Tri>& ref,
                                     const RandomSetChecker& ck, const std::vector<glm::dvec3>& seeds,
                                     const fluid::SurfaceParams& po, std::size_t& ghosts) {
  if (got == ref) return {};
  if (!std::includes(ref.begin(), ref.end(), got.begin(), got.end()))
    return std::to_string(got.size()) + " triangles, the dense oracle " + std::to_string(ref.size()) +
           ", and some are not the oracle's";
  // Components of the oracle mesh: union-find over vertex keys.
  std::unordered_map<std::uint64_t, std::uint64_t> parent;
  auto find = [&](std::uint64_t k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  for (const Tri& t : ref)
    for (std::uint64_t k : t) parent.emplace(k, k);
  for (const Tri& t : ref) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  struct Comp {
    std::size_t tris = 0, found = 0;
    glm::dvec3 lo{1e300}, hi{-1e300};
  };
  std::unordered_map<std::uint64_t, Comp> comps;
  std::unordered_map<std::uint64_t, glm::dvec3> pos;
  for (std::size_t v = 0; v < ck.ref.positions.size(); ++v)
    pos[ck.ref.edgeKeys[v]] =
        (glm::dvec3(ck.ref.positions[v]) + glm::dvec3(po.originX, po.originY, po.originZ)) / double(po.cube);
  for (const Tri& t : ref) {
    Comp& c = comps[find(t[0])];
    ++c.tris;
    c.found += std::binary_search(got.begin(), got.end(), t);
    for (std::uint64_t k : t) c.lo = glm::min(c.lo, pos[k]), c.hi = glm::max(c.hi, pos[k]);
  }
  for (const auto& [key, c] : comps) {
    if (c.found == c.tris) continue;
    if (c.found)
      return "part of a surface component is missing (" + std::to_string(c.tris - c.found) + " of " +
             std::to_string(c.tris) + " triangles): a hole";
    for (const glm::dvec3& q : seeds)
      if (glm::all(glm::greaterThan(q, c.lo)) && glm::all(glm::lessThan(q, c.hi)))
        return "a surface component of " + std::to_string(c.tris) + " triangles around a seeding corner is missing";
    ++ghosts;
  }
  return {};
}

// The first property that does not hold, or "" (see the header comment). `ghosts` (if given)
// counts the oracle components that §4 seeding cannot reach (compareWithOracle).
// `blockSizeDependent` (if given) counts the seeds whose block sizes found different sets of those
// components (each block size found them whole or not at all, so each still matches the oracle).
inline std::string checkRandomSet(const RandomSet& r, RandomSetChecker& ck, std::size_t* ghostCount = nullptr,
                                  std::size_t* blockSizeDependent = nullptr) {
  std::size_t ghostsLocal = 0;
  std::size_t& ghosts = ghostCount ? *ghostCount : ghostsLocal;
  bool setsDiffer = false;
  const fluid::SurfaceInput in = r.input();
  fluid::SurfaceParams p = r.params;
  // With a view order the mesher sweeps in a rotated frame (paper §5): local axis a is world axis
  // frame.axis[a] times frame.sign[a], edge keys are frame lattice edges, and the field sums run
  // in frame-z order. The oracle therefore meshes the set rotated into that frame (same sums, so
  // the same bits), and mesher positions are rotated the same way before they are compared.
  const fluid::detail::SweepFrame frame = fluid::detail::chooseFrame(p);
  std::vector<glm::vec3> rotated(r.points.size());
  const double origin[3] = {p.originX, p.originY, p.originZ};
  fluid::SurfaceParams po = p;
  po.order = fluid::SurfaceOrder::none;
  double* po3[3] = {&po.originX, &po.originY, &po.originZ};
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < rotated.size(); ++i) rotated[i][a] = float(frame.sign[a]) * r.points[i][frame.axis[a]];
    *po3[a] = frame.sign[a] * origin[frame.axis[a]];
  }
  auto toFrame = [&](glm::vec3 w) {
    return glm::vec3(float(frame.sign[0]) * w[frame.axis[0]], float(frame.sign[1]) * w[frame.axis[1]],
                     float(frame.sign[2]) * w[frame.axis[2]]);
  };
  // Kernels rotate with the set: g_frame(a, b) = sign[a] sign[b] g(axis[a], axis[b]).
  std::vector<glm::mat3> rotatedStretch(r.stretch.size());
  for (std::size_t i = 0; i < r.stretch.size(); ++i)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        rotatedStretch[i][b][a] = float(frame.sign[a] * frame.sign[b]) * r.stretch[i][frame.axis[b]][frame.axis[a]];
  fluid::SurfaceStatus st =
      ck.dense.extract(fluid::BaselineMethod::dense,
                       {fluid::pointView(rotated), in.strength, in.radiusScale, {}, rotatedStretch}, po, ck.ref);
  if (!st.ok()) return "dense oracle: " + st.error;
  const std::vector<Tri> refTris = canonicalTriangles(ck.ref);
  std::unordered_map<std::uint64_t, glm::vec3> refPos;
  for (std::size_t v = 0; v < ck.ref.positions.size(); ++v) refPos[ck.ref.edgeKeys[v]] = ck.ref.positions[v];
  // Seeding corners (§4): each particle's nearest lattice corner, in the sweep frame.
  std::vector<glm::dvec3> frameSeeds;
  for (const glm::vec3& q : rotated)
    frameSeeds.emplace_back(std::floor(double(q.x) / double(p.cube) + 0.5),
                            std::floor(double(q.y) / double(p.cube) + 0.5),
                            std::floor(double(q.z) / double(p.cube) + 0.5));
  for (int b : r.blockSizes) {
    p.blockCubes = b;
    const std::string at = "blockCubes " + std::to_string(b);
    for (int t = 0; t < 3; ++t) {
      p.threads = t + 1;
      st = ck.slices[t].extract(in, p, ck.mesh[t]);
      if (!st.ok()) return at + ", " + std::to_string(t + 1) + " threads: " + st.error;
    }
    const fluid::SurfaceMesh& m = ck.mesh[0];
    for (int t = 1; t < 3; ++t)
      if (ck.mesh[t].positions != m.positions || ck.mesh[t].normals != m.normals || ck.mesh[t].indices != m.indices ||
          ck.mesh[t].edgeKeys != m.edgeKeys)
        return at + ": " + std::to_string(t + 1) + " threads differ from 1 thread";
    const Topology topo = checkTopology(m);
    if (topo.badEdges)
      return at + ": not closed or not consistently oriented (" + std::to_string(topo.badEdges) + " edges)";
    if (topo.degenerate) return at + ": " + std::to_string(topo.degenerate) + " degenerate triangles";
    if (topo.keyPositionMismatch) return at + ": one lattice edge with two positions";
    const std::vector<Tri> got = canonicalTriangles(m);
    const std::string diff = compareWithOracle(got, refTris, ck, frameSeeds, po, ghosts);
    if (b == r.blockSizes[0])
      ck.firstSet = got;
    else
      setsDiffer = setsDiffer || got != ck.firstSet;
    if (!diff.empty()) return at + ": " + diff;
    for (std::size_t v = 0; v < m.positions.size(); ++v)
      if (refPos.at(m.edgeKeys[v]) != toFrame(m.positions[v]))
        return at + ": a vertex position differs from the oracle's";
    if (!m.indices.empty()) {
      // Signed volume about the first vertex (float positions far from zero would cancel badly).
      const glm::dvec3 o(m.positions[m.indices[0]]);
      double vol = 0;
      for (std::size_t i = 0; i + 2 < m.indices.size(); i += 3) {
        const glm::dvec3 a = glm::dvec3(m.positions[m.indices[i]]) - o,
                         bb = glm::dvec3(m.positions[m.indices[i + 1]]) - o,
                         cc = glm::dvec3(m.positions[m.indices[i + 2]]) - o;
        vol += glm::dot(a, glm::cross(bb, cc));
      }
      if (!(vol > 0)) return at + ": signed volume " + std::to_string(vol / 6) + " is not positive (inward winding)";
    }
  }
  if (setsDiffer && blockSizeDependent) ++*blockSizeDependent;
  return {};
}

}  // namespace surface_test
