// bench_surface_peers: our marching-slices extractor against the dense-lattice peer (every particle
// splatted into a dense float lattice, then VTK 9's vtkFlyingEdges3D on it: Schroeder, Maynard &
// Geveci 2015), on the same particles, Rc, T and cube size S, in one process, interleaved. Built only
// when CMake finds VTK 9 (Debian: `apt-get install libvtk9-dev`); not part of scripts/test.sh.
//
//   bench_surface_peers [--reps N] [--scale-reps N] [--out FILE] [--callgrind] [--quick]
//   bench_surface_peers --count SET ROUTE [MESHES]   (one warm mesh, or MESHES of them for `perf
//                                           record`, between callgrind client requests; ROUTE = ours |
//                                           ours-one-block | cache | splat | dense | value | peer | peer-scalar |
//                                           peer-no-normals)
//
// Timings: rounds interleave ours and the peer (1 thread, then 2 threads); each timed mesh follows
// an untimed one of the same route (steady state, as a game meshing every frame); medians of N
// rounds (default 21). The triangle counts of both routes are compared and printed. --out replaces
// the text between the markers `<!-- bench_surface_peers -->` and `<!-- /bench_surface_peers -->`
// of FILE (appends them when absent). --callgrind runs `valgrind --tool=callgrind` on this program
// in --count mode for fountain and spray and adds the instruction counts (ours / peer).
#include "bench_timing.hpp"
#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "load_average.hpp"
#include "surface_peers_vtk.hpp"

#include <immintrin.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <valgrind/callgrind.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <time.h>

// Allocation counter for the "no allocation per mesh after warm-up" bar (counts every operator new).
static std::atomic<std::uint64_t> gAllocations{0};
void* operator new(std::size_t n) {
  ++gAllocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using benchtiming::median;
using benchtiming::threadCpuMs;
using benchtiming::timeMs;

constexpr float kRc = 3.0f, kT = 0.2f;

template <class F>
double timeCpuMs(F&& f, std::vector<double>& cpu) {
  const double c0 = threadCpuMs();
  const double w = timeMs(f);
  cpu.push_back(threadCpuMs() - c0);
  return w;
}

// The dense peer: the same field f (paper §2, Rc = 3, strength 1) splatted into every lattice point of
// the particles' bounding box (plus Rc), then Flying Edges with normals. Point (i, j, k) sits at
// (i0 + i) S etc. on the global lattice, so its triangles are the dense-MC triangles of ours.
//
// Made as fast as we could (a slow peer flatters us; issue 34): the particles are put in z order by a
// counting sort of their lattice z (each slice's rows are then written by neighbouring particles,
// while they are in cache, and a z-slab task finds its particles by binary search); each particle's
// anchor and rest are computed once; a row of its ball is one to three 8-wide AVX2 windows starting
// at its leftmost possible point (no chord, floor or sqrt per row), each lane adding w^2 where
// r^2 < Rc^2 by a masked load and store, so lanes outside the ball touch no memory. `scalar` keeps
// the row-chord loop it replaced (per-row sqrt and floor/ceil, particles in input order), for the
// before/after of that change (--count SET peer-scalar).
struct DensePeer {
  std::int64_t i0[3] = {0, 0, 0};
  int dims[3] = {0, 0, 0};
  std::vector<float> lattice;
  std::vector<float> offsets;  // float(d S), d in [-range, range]: the lattice offsets of field.hpp
  struct Prepared {
    std::int32_t c[3];  // anchor - i0 per axis (lattice point of the particle's floor corner)
    float rest[3];      // float(p - anchor S)
  };
  std::vector<Prepared> prepared, sorted;  // per particle; in z order
  std::vector<std::uint32_t> zCount;
  benchpeers::FlyingEdges fe;
  std::unique_ptr<tbb::task_arena> arena;
  int threads = 0;
  bool scalar = false;
  bool normals = true;  // false: Flying Edges without its normals (--count SET peer-no-normals)

  std::size_t bytes() const { return lattice.size() * sizeof(float); }

  std::size_t mesh(const fluid::ParticlePositions& ps, double s, int nThreads) {
    if (threads != nThreads) {
      arena = std::make_unique<tbb::task_arena>(nThreads);
      threads = nThreads;
    }  // (benchpeers::setThreads(nThreads) comes first, from the caller, untimed)
    const std::size_t n = ps.size();
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(ps[i][a])), hi[a] = std::max(hi[a], double(ps[i][a]));
    for (int a = 0; a < 3; ++a) {
      i0[a] = std::int64_t(std::floor((lo[a] - kRc) / s)) - 1;
      dims[a] = int(std::int64_t(std::ceil((hi[a] + kRc) / s)) + 1 - i0[a] + 1);
    }
    const std::size_t sx = std::size_t(dims[0]), sxy = sx * std::size_t(dims[1]);
    lattice.assign(sxy * std::size_t(dims[2]), 0.0f);
    const int range = int(std::ceil(kRc / s)) + 2;
    offsets.resize(std::size_t(2 * range + 1));
    for (int d = -range; d <= range; ++d) offsets[std::size_t(d + range)] = float(double(d) * s);
    if (scalar) {
      splatScalar(ps, s, nThreads, range);
    } else {
      prepare(ps, s);
      const int r = range - 2;
      auto slab = [&](int zBegin, int zEnd) {
        // Particles whose z reach [c - r, c + r + 1] meets the slab: a run of the z-sorted list.
        const Prepared* first = std::lower_bound(sorted.data(), sorted.data() + n, zBegin - r - 1,
                                                 [](const Prepared& p, int z) { return p.c[2] < z; });
        const Prepared* last = std::upper_bound(first, static_cast<const Prepared*>(sorted.data() + n), zEnd - 1 + r,
                                                [](int z, const Prepared& p) { return z < p.c[2]; });
        splatAvx2(first, last, zBegin, zEnd, r);
      };
      if (nThreads <= 1) {
        slab(0, dims[2]);
      } else {
        arena->execute([&] {
          tbb::parallel_for(0, nThreads, [&](int t) { slab(dims[2] * t / nThreads, dims[2] * (t + 1) / nThreads); });
        });
      }
    }
    const double origin[3] = {double(i0[0]) * s, double(i0[1]) * s, double(i0[2]) * s};
    return fe.run(lattice.data(), dims, s, origin, kT, normals);
  }

  // Anchors and rests once per particle, then a stable counting sort by lattice z.
  void prepare(const fluid::ParticlePositions& ps, double s) {
    const std::size_t n = ps.size();
    prepared.resize(n);
    sorted.resize(n);
    zCount.assign(std::size_t(dims[2]) + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      Prepared& q = prepared[i];
      for (int a = 0; a < 3; ++a) {
        const double p = ps[i][a];
        const std::int64_t anchor = std::int64_t(std::floor(p / s));
        q.c[a] = std::int32_t(anchor - i0[a]);
        q.rest[a] = float(p - double(anchor) * s);
      }
      ++zCount[std::size_t(q.c[2]) + 1];
    }
    for (std::size_t z = 1; z < zCount.size(); ++z) zCount[z] += zCount[z - 1];
    for (const Prepared& q : prepared) sorted[zCount[std::size_t(q.c[2])]++] = q;
  }

  // Rows of each particle's ball in slices [zBegin, zEnd): windows of 8 lanes from x = c - r.
  [[gnu::target("avx2")]] void splatAvx2(const Prepared* first, const Prepared* last, int zBegin, int zEnd, int r) {
    const std::size_t sx = std::size_t(dims[0]), sxy = sx * std::size_t(dims[1]);
    const float* off0 = offsets.data() + (r + 2);
    const float rc2 = kRc * kRc, k = float(1.0 / (2.0 * double(kRc) * double(kRc)));
    const int windows = (2 * r + 2 + 7) / 8;  // lanes for x in [c - r, c + r + 1]
    assert(windows <= 4 && 2 * r + 2 <= 64);  // Rc / S <= 14 (the sets: 3, 5, 10)
    const __m256 vrc2 = _mm256_set1_ps(rc2), vk = _mm256_set1_ps(k), vhalf = _mm256_set1_ps(0.5f);
    float dy2[64], dz2[64];  // per offset -r .. r + 1 (r <= 31 here)
    for (const Prepared* p = first; p != last; ++p) {
      const int z0 = std::max(zBegin, p->c[2] - r), z1 = std::min(zEnd - 1, p->c[2] + r + 1);
      if (z0 > z1) continue;
      for (int d = -r; d <= r + 1; ++d) {
        const float dy = off0[d] - p->rest[1], dz = off0[d] - p->rest[2];
        dy2[d + r] = dy * dy;
        dz2[d + r] = dz * dz;
      }
      __m256 dx2[4];
      for (int w = 0; w < windows; ++w) {
        // Lane l: x = c - r + 8w + l, offset d = 8w + l - r (past r + 1 the lanes only read the table's
        // slack and are outside the ball).
        float lane[8];
        for (int l = 0; l < 8; ++l) {
          const int d = 8 * w + l - r;
          const float dx = d <= r + 2 ? off0[d] - p->rest[0] : 1e9f;
          lane[l] = dx * dx;
        }
        dx2[w] = _mm256_loadu_ps(lane);
      }
      const int y0 = std::max(0, p->c[1] - r), y1 = std::min(dims[1] - 1, p->c[1] + r + 1);
      for (int z = z0; z <= z1; ++z) {
        const float fz = dz2[z - p->c[2] + r];
        if (fz >= rc2) continue;
        float* slice = lattice.data() + std::size_t(z) * sxy + std::size_t(p->c[0] - r);
        for (int y = y0; y <= y1; ++y) {
          const float dyz = dy2[y - p->c[1] + r] + fz;
          if (dyz >= rc2) continue;
          float* row = slice + std::size_t(y) * sx;
          const __m256 vdyz = _mm256_set1_ps(dyz);
          for (int w = 0; w < windows; ++w) {
            const __m256 r2 = _mm256_add_ps(dx2[w], vdyz);
            const __m256i in = _mm256_castps_si256(_mm256_cmp_ps(r2, vrc2, _CMP_LT_OQ));
            const __m256 t = _mm256_sub_ps(_mm256_mul_ps(r2, vk), vhalf);
            float* at = row + 8 * w;
            const __m256 v = _mm256_add_ps(_mm256_maskload_ps(at, in), _mm256_mul_ps(t, t));
            _mm256_maskstore_ps(at, in, v);
          }
        }
      }
    }
  }

  // The row-chord loop (input order, per-row sqrt and floor/ceil): the peer before issue 34.
  void splatScalar(const fluid::ParticlePositions& ps, double s, int nThreads, int range) {
    const std::size_t n = ps.size();
    const std::size_t sx = std::size_t(dims[0]), sxy = sx * std::size_t(dims[1]);
    const float* off0 = offsets.data() + range;
    const float rc2 = kRc * kRc, k = float(1.0 / (2.0 * double(kRc) * double(kRc)));
    auto splat = [&](int zBegin, int zEnd) {
      for (std::size_t i = 0; i < n; ++i) {
        std::int64_t anchor[3];
        float rest[3];
        for (int a = 0; a < 3; ++a) {
          const double p = ps[i][a];
          anchor[a] = std::int64_t(std::floor(p / s));
          rest[a] = float(p - double(anchor[a]) * s);
        }
        const int r = range - 2;
        const int z0 = std::max<int>(zBegin, int(anchor[2] - r - i0[2])),
                  z1 = std::min<int>(zEnd - 1, int(anchor[2] + r + 1 - i0[2]));
        const int y0 = std::max(0, int(anchor[1] - r - i0[1])),
                  y1 = std::min(dims[1] - 1, int(anchor[1] + r + 1 - i0[1]));
        const int x0 = std::max(0, int(anchor[0] - r - i0[0])),
                  x1 = std::min(dims[0] - 1, int(anchor[0] + r + 1 - i0[0]));
        const int ax = int(i0[0] - anchor[0]);
        for (int z = z0; z <= z1; ++z) {
          const float dz = off0[z + i0[2] - anchor[2]] - rest[2];
          for (int y = y0; y <= y1; ++y) {
            const float dy = off0[y + i0[1] - anchor[1]] - rest[1];
            const float dyz = dy * dy + dz * dz;
            if (dyz >= rc2) continue;
            float* row = lattice.data() + std::size_t(z) * sxy + std::size_t(y) * sx;
            // The row's chord of the ball (plus one point of slack each side; the mask decides).
            const float h = std::sqrt(rc2 - dyz);
            const int c = int(anchor[0] - i0[0]);
            const float rx = rest[0] / float(s), hc = h / float(s);
            const int xa = std::max(x0, c + int(std::floor(rx - hc)) - 1),
                      xb = std::min(x1, c + int(std::ceil(rx + hc)) + 1);
            for (int x = xa; x <= xb; ++x) {
              const float dx = off0[x + ax] - rest[0];
              const float r2 = dx * dx + dyz;
              const float w = r2 * k - 0.5f;
              row[x] += r2 < rc2 ? w * w : 0.0f;
            }
          }
        }
      }
    };
    if (nThreads <= 1) {
      splat(0, dims[2]);
    } else {
      arena->execute([&] {
        tbb::parallel_for(0, nThreads, [&](int t) { splat(dims[2] * t / nThreads, dims[2] * (t + 1) / nThreads); });
      });
    }
  }
};

struct Ours {
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  fluid::SurfaceStatus last;
  std::size_t mesh1(const fluid::ParticlePositions& ps, double s, int threads, fluid::SurfaceParams p = {}) {
    p.rc = kRc;
    p.threshold = kT;
    p.cube = float(s);
    p.threads = threads;
    last = extractor.extract({fluid::pointView(ps)}, p, mesh);
    if (!last.ok()) {
      std::fprintf(stderr, "bench_surface_peers: %s\n", last.error.c_str());
      std::exit(1);
    }
    return mesh.indices.size() / 3;
  }
};

struct Set {
  const char* name;
  float cube;
  fluid::ParticlePositions ps;
};

fluid::ParticlePositions load(const char* name) {
  fluid::ParticlePositions ps;
  const std::string path = std::string(FLUIDDEMO_TEST_DATA_DIR) + "/" + name + ".xyz";
  const fluid::IoStatus io = fluid::readParticleFile(path, ps);
  if (!io.ok()) {
    std::fprintf(stderr, "bench_surface_peers: %s\n", io.error.c_str());
    std::exit(1);
  }
  return ps;
}

// The fountain set tiled t x t in the x-y plane (copies one set width plus 2 Rc apart), for the
// scaling table: 1, 4, 16, 64 copies = 3k, 12k, 48k, 192k particles.
fluid::ParticlePositions tiled(const fluid::ParticlePositions& base, int t) {
  float lo[2] = {1e30f, 1e30f}, hi[2] = {-1e30f, -1e30f};
  for (std::size_t i = 0; i < base.size(); ++i) {
    lo[0] = std::min(lo[0], base[i].x), hi[0] = std::max(hi[0], base[i].x);
    lo[1] = std::min(lo[1], base[i].y), hi[1] = std::max(hi[1], base[i].y);
  }
  const float step[2] = {std::ceil(hi[0] - lo[0] + 2 * kRc), std::ceil(hi[1] - lo[1] + 2 * kRc)};
  fluid::ParticlePositions out;
  for (int ty = 0; ty < t; ++ty)
    for (int tx = 0; tx < t; ++tx)
      for (std::size_t i = 0; i < base.size(); ++i)
        out.push_back({base[i].x + float(tx) * step[0], base[i].y + float(ty) * step[1], base[i].z});
  return out;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// --count: one warm mesh of SET by ROUTE (ours | ours-one-block | cache | splat | dense | value | peer |
// peer-scalar | peer-no-normals), one thread, between callgrind's start and stop; `repeats` meshes there instead of one
// for a sampling profiler (perf record), which needs many to split the time between functions.
int countMode(const std::string& set, const std::string& route, int repeats) {
  const float cube = set == "blob" ? 0.3f : set == "explosion" ? 0.6f : 1.0f;
  const fluid::ParticlePositions ps = load(set.c_str());
  Ours ours;
  DensePeer peer;
  benchpeers::setThreads(1);
  // ours = default SurfaceParams; cache / splat = that field route (SurfaceFieldRoute); ours-one-block =
  // the default route with blocks as large as the set (the automatic plan halves a set that fits one
  // block for two threads' sake, and each block sums its margins again).
  fluid::SurfaceParams params;
  if (route == "cache") params.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
  if (route == "splat") params.fieldRoute = fluid::SurfaceFieldRoute::sliceSplat;
  if (route == "dense") params.fieldRoute = fluid::SurfaceFieldRoute::denseScan;
  if (route == "value") params.fieldRoute = fluid::SurfaceFieldRoute::valueScan;
  if (route == "ours-one-block") params.blockCubes = 1024;
  peer.scalar = route == "peer-scalar";
  peer.normals = route != "peer-no-normals";
  auto run = [&] { return route.rfind("peer", 0) == 0 ? peer.mesh(ps, cube, 1) : ours.mesh1(ps, cube, 1, params); };
  run();
  CALLGRIND_START_INSTRUMENTATION;
  std::size_t tris = 0;
  for (int i = 0; i < repeats; ++i) tris = run();
  CALLGRIND_STOP_INSTRUMENTATION;
  std::printf("%s %s triangles %zu\n", set.c_str(), route.c_str(), tris);
  return 0;
}

// Total instructions of a --count run under callgrind (the "totals:" line), or -1.
double callgrindIr(const char* self, const std::string& set, const std::string& route) {
  const std::string out = "/tmp/bench_surface_peers." + set + "." + route + ".callgrind";
  const std::string cmd = "valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file=" + out + " " + self +
                          " --count " + set + " " + route + " > /dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return -1;
  std::ifstream f(out);
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("totals:", 0) == 0) return std::atof(line.c_str() + 7);
  return -1;
}

// The four sets: ours and the peer, interleaved, 1 and 2 threads; the allocation count; the bars.
void setsTables(int reps, std::ostringstream& md) {
  std::vector<Set> sets = {{"fountain", 1.0f, load("fountain")},
                           {"blob", 0.3f, load("blob")},
                           {"explosion", 0.6f, load("explosion")},
                           {"spray", 1.0f, load("spray")}};
  // Allocations after warm-up, counted before VTK runs at all (its TBB workers allocate on their own
  // schedule, and the counter sees the whole process): 3 untimed meshes, then 20 counted, per thread count.
  std::vector<std::array<std::uint64_t, 2>> allocs(sets.size());
  for (std::size_t i = 0; i < sets.size(); ++i)
    for (int t = 1; t <= 2; ++t) {
      Ours o;
      for (int r = 0; r < 3; ++r) o.mesh1(sets[i].ps, sets[i].cube, t);
      const std::uint64_t a0 = gAllocations;
      for (int r = 0; r < 20; ++r) o.mesh1(sets[i].ps, sets[i].cube, t);
      allocs[i][std::size_t(t - 1)] = gAllocations - a0;
    }
  bool allMet = true, allMetCpu = true, allMetValue = true;
  std::ostringstream cpuTable;
  for (Set& set : sets) {
    Ours o1, o2, oc, os, ov;  // oc, os, ov: one thread with the field route fixed (cache, splat, value)
    DensePeer p1, p2, p0;  // p0: the peer's row-chord splat of before issue 34 (DensePeer::scalar)
    p0.scalar = true;
    std::vector<double> to1, to2, tp1, tp2, co1, cp1, cc1, cs1, cv1, cp0;
    fluid::SurfaceParams cacheRoute, splatRoute, valueRoute;
    cacheRoute.fieldRoute = fluid::SurfaceFieldRoute::particleCache;
    splatRoute.fieldRoute = fluid::SurfaceFieldRoute::sliceSplat;
    valueRoute.fieldRoute = fluid::SurfaceFieldRoute::valueScan;
    std::size_t tri[5] = {};
    for (int r = 0; r < reps; ++r) {
      // Two threads first (VTK's thread setting caps the process, see setThreads), then one.
      benchpeers::setThreads(2);
      p2.mesh(set.ps, set.cube, 2);
      tp2.push_back(timeMs([&] { tri[3] = p2.mesh(set.ps, set.cube, 2); }));
      o2.mesh1(set.ps, set.cube, 2);
      to2.push_back(timeMs([&] { tri[2] = o2.mesh1(set.ps, set.cube, 2); }));
      o1.mesh1(set.ps, set.cube, 1);
      to1.push_back(timeCpuMs([&] { tri[0] = o1.mesh1(set.ps, set.cube, 1); }, co1));
      oc.mesh1(set.ps, set.cube, 1, cacheRoute);
      timeCpuMs([&] { oc.mesh1(set.ps, set.cube, 1, cacheRoute); }, cc1);
      os.mesh1(set.ps, set.cube, 1, splatRoute);
      timeCpuMs([&] { os.mesh1(set.ps, set.cube, 1, splatRoute); }, cs1);
      ov.mesh1(set.ps, set.cube, 1, valueRoute);
      timeCpuMs([&] { tri[4] = ov.mesh1(set.ps, set.cube, 1, valueRoute); }, cv1);
      benchpeers::setThreads(1);
      p1.mesh(set.ps, set.cube, 1);
      tp1.push_back(timeCpuMs([&] { tri[1] = p1.mesh(set.ps, set.cube, 1); }, cp1));
      p0.mesh(set.ps, set.cube, 1);
      timeCpuMs([&] { p0.mesh(set.ps, set.cube, 1); }, cp0);
    }
    const double mo1 = median(to1), mp1 = median(tp1), mo2 = median(to2), mp2 = median(tp2);
    const double mc1 = median(co1), mq1 = median(cp1), mcc = median(cc1), mcs = median(cs1), mq0 = median(cp0);
    const double mcv = median(cv1);
    const bool met = mo1 <= 0.8 * mp1, metCpu = mc1 <= 0.8 * mq1, metValue = mcv <= 0.8 * mq1;
    allMet = allMet && met && tri[0] == tri[1];
    allMetCpu = allMetCpu && metCpu && tri[0] == tri[1];
    allMetValue = allMetValue && metValue && tri[4] == tri[1];
    std::printf("%-9s tris %zu/%zu  1 thr ours %.3f peer %.3f ratio %.2f  2 thr ours %.3f peer %.3f  speed-up %.2f\n",
                set.name, tri[0], tri[1], mo1, mp1, mo1 / mp1, mo2, mp2, mo1 / mo2);
    std::fflush(stdout);
    md << "| " << set.name << " | " << fmt("%g", set.cube) << " | " << tri[0] << " / " << tri[1]
       << (tri[0] == tri[1] ? " (equal)" : " (**differ**)") << " | " << fmt("%.3f", mo1) << " | " << fmt("%.3f", mp1)
       << " | " << fmt("%.2f", mo1 / mp1) << (met ? " (met)" : " (**not met**)") << " | " << fmt("%.3f", mo2) << " | "
       << fmt("%.3f", mp2) << " | " << fmt("%.2f", mo2 / mp2) << " | " << fmt("%.2f", mo1 / mo2) << "x | "
       << fmt("%.3f", o2.mesh.stats.workingBytesAllWorkers / 1e6) << " | " << fmt("%.3f", p1.bytes() / 1e6) << " | "
       << allocs[std::size_t(&set - sets.data())][0] << " / " << allocs[std::size_t(&set - sets.data())][1] << " |\n";
    const char* picked = o1.mesh.stats.scannedBlocks ? "dense scan"
                         : o1.mesh.stats.splatBlocks ? "slice splat, walk"
                                                     : "particle cache, walk";
    cpuTable << "| " << set.name << " | " << picked << " | "
             << fmt("%.3f", mc1) << " | " << fmt("%.3f", mq1) << " | " << fmt("%.2f", mc1 / mq1)
             << (metCpu ? " (met)" : " (**not met**)") << " | " << fmt("%.3f", mcc) << " | " << fmt("%.3f", mcs)
             << " | " << fmt("%.2f", mcc / mq1) << " | " << fmt("%.2f", mcs / mq1) << " | " << fmt("%.3f", mq0) << " | "
             << fmt("%.2f", mc1 / mq0) << " | " << fmt("%.3f", mcv) << " | " << fmt("%.2f", mcv / mq1)
             << (metValue ? " (met)" : " (**not met**)") << (tri[4] == tri[1] ? "" : " (**triangles differ**)") << " |\n";
  }
  md << "\nThe same one-thread meshes timed by the CPU time of the calling thread (`CLOCK_THREAD_CPUTIME_ID`, "
        "medians of the same rounds): both routes run on the calling thread there, and this leaves out the time it "
        "waited for a core, which dominates the wall-clock figures on a loaded machine.\n\n"
        "Ours uses the default `SurfaceFieldRoute::automatic`, which picks the route in the second column; the next "
        "four columns time the two routes with §4 seeding and Alg. 1's walk forced (`particleCache`, `sliceSplat`), "
        "in the same rounds (these three routes give the same vertex bits, with analytic normals). The last two "
        "columns time `valueScan` in the same rounds: the dense scan over a value-only float splat with normals from "
        "central differences, the peer's own kind of output (Flying Edges' normals), so the like-for-like "
        "comparison; its normals are 0.6-5.4 degrees from the analytic ones on average "
        "(tests/surface/test_value_scan.cpp prints them per set).\n\n"
        "| set | route picked | ours CPU ms | peer CPU ms | ours / peer (CPU) | particle cache CPU ms | slice splat "
        "CPU "
        "ms | cache / peer | splat / peer | peer before issue 34 (row-chord splat) CPU ms | ours / that peer | "
        "value scan CPU ms | value scan / peer (CPU) |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
     << cpuTable.str();
  md << "\nAll four one-thread ratios at most 0.8 with equal triangles: wall clock **" << (allMet ? "met" : "not met")
     << "**, CPU time **" << (allMetCpu ? "met" : "not met") << "**; the value scan's (CPU time) **"
     << (allMetValue ? "met" : "not met") << "**.\n";
}

// Instruction counts of one warm mesh (fountain, spray) by each route, from callgrind runs of `self`.
void callgrindTable(const char* self, std::ostringstream& md) {
  md << "\nInstruction counts (callgrind, one warm mesh on one thread between client requests: "
        "`bench_surface_peers --count SET ours|cache|splat|value|peer|peer-scalar` under `valgrind --tool=callgrind "
        "--instr-atstart=no`; ours = the default automatic route (the dense scan), cache / splat = the particle "
        "cache or the slice splat with the seeded walk, forced, value = the value scan (central-difference "
        "normals), peer-scalar = the peer's row-chord splat of before issue 34; a memset counts about one "
        "instruction per byte there):\n\n"
        "| set | ours Ir | particle cache Ir | slice splat Ir | value scan Ir | peer Ir | ours / peer | cache / peer | "
        "splat / peer | value / peer | peer before issue 34 Ir |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const char* set : {"fountain", "blob", "explosion", "spray"}) {
    const double a = callgrindIr(self, set, "ours"), c = callgrindIr(self, set, "cache"),
                 sp = callgrindIr(self, set, "splat"), v = callgrindIr(self, set, "value"),
                 b = callgrindIr(self, set, "peer"), b0 = callgrindIr(self, set, "peer-scalar");
    std::printf("callgrind %s: ours %.0f cache %.0f splat %.0f value %.0f peer %.0f ratio %.3f\n", set, a, c, sp, v, b,
                a / b);
    md << "| " << set << " | " << fmt("%.0f", a) << " | " << fmt("%.0f", c) << " | " << fmt("%.0f", sp) << " | "
       << fmt("%.0f", v) << " | " << fmt("%.0f", b) << " | " << fmt("%.3f", a / b) << " | " << fmt("%.3f", c / b)
       << " | " << fmt("%.3f", sp / b) << " | " << fmt("%.3f", v / b) << " | " << fmt("%.0f", b0) << " |\n";
  }
}

// Scaling past the paper: the fountain set tiled in the x-y plane.
void scalingTable(int scaleReps, std::ostringstream& md) {
  md << "\n### Scaling with particle count\n\nThe fountain set (S = 1) tiled t x t in the x-y plane, copies a set "
        "width plus 2 Rc apart (t = 1, 2, 4, 8); medians of "
     << scaleReps
     << " interleaved rounds (warm, as above). Ours MB = working memory of all workers (block caches); "
        "peer MB = the dense lattice alone (4 bytes per point), which grows with the bounding box.\n\n"
     << "| particles | triangles | ours ms 1 thr | peer ms 1 thr | ours ms 2 thr | peer ms 2 thr | ours / peer 1 thr | "
        "ours / peer 2 thr | ours MB (2 thr) | peer MB |\n|---|---|---|---|---|---|---|---|---|---|\n";
  const fluid::ParticlePositions fountain = load("fountain");
  for (int t : {1, 2, 4, 8}) {
    const fluid::ParticlePositions ps = tiled(fountain, t);
    Ours o1, o2;
    DensePeer p1, p2;
    std::vector<double> to1, to2, tp1, tp2;
    std::size_t tri[2] = {};
    for (int r = 0; r < scaleReps; ++r) {
      benchpeers::setThreads(2);
      p2.mesh(ps, 1.0, 2);
      tp2.push_back(timeMs([&] { p2.mesh(ps, 1.0, 2); }));
      o2.mesh1(ps, 1.0, 2);
      to2.push_back(timeMs([&] { o2.mesh1(ps, 1.0, 2); }));
      o1.mesh1(ps, 1.0, 1);
      to1.push_back(timeMs([&] { tri[0] = o1.mesh1(ps, 1.0, 1); }));
      benchpeers::setThreads(1);
      p1.mesh(ps, 1.0, 1);
      tp1.push_back(timeMs([&] { tri[1] = p1.mesh(ps, 1.0, 1); }));
    }
    const double mo1 = median(to1), mp1 = median(tp1), mo2 = median(to2), mp2 = median(tp2);
    std::printf("scaling %zu particles: tris %zu/%zu 1 thr %.2f / %.2f  2 thr %.2f / %.2f\n", ps.size(), tri[0], tri[1],
                mo1, mp1, mo2, mp2);
    std::fflush(stdout);
    md << "| " << ps.size() << " | " << tri[0] << (tri[0] == tri[1] ? "" : " (peer " + std::to_string(tri[1]) + ")")
       << " | " << fmt("%.2f", mo1) << " | " << fmt("%.2f", mp1) << " | " << fmt("%.2f", mo2) << " | "
       << fmt("%.2f", mp2) << " | " << fmt("%.2f", mo1 / mp1) << " | " << fmt("%.2f", mo2 / mp2) << " | "
       << fmt("%.3f", o2.mesh.stats.workingBytesAllWorkers / 1e6) << " | " << fmt("%.2f", p1.bytes() / 1e6) << " |\n";
  }
}

// Replaces the marked section of `outPath` (or appends it).
void writeSection(const std::string& outPath, const std::ostringstream& md) {
  std::printf("\n%s", md.str().c_str());
  if (!outPath.empty()) {
    const std::string begin = "<!-- bench_surface_peers -->", end = "<!-- /bench_surface_peers -->";
    std::string doc;
    {
      std::ifstream f(outPath);
      std::stringstream ss;
      ss << f.rdbuf();
      doc = ss.str();
    }
    const std::string section = begin + "\n" + md.str() + end;
    const std::size_t b = doc.find(begin), e = doc.find(end);
    if (b != std::string::npos && e != std::string::npos && e > b)
      doc.replace(b, e + end.size() - b, section);
    else
      doc += (doc.empty() || doc.back() == '\n' ? "\n" : "\n\n") + section + "\n";
    std::ofstream(outPath) << doc;
    std::printf("wrote %s\n", outPath.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 21, scaleReps = 7;
  bool callgrind = false;
  std::string outPath;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--count" && i + 2 < argc)
      return countMode(argv[i + 1], argv[i + 2], i + 3 < argc ? std::max(1, std::atoi(argv[i + 3])) : 1);
    if (a == "--reps" && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--scale-reps" && i + 1 < argc) {
      scaleReps = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--out" && i + 1 < argc) {
      outPath = argv[++i];
    } else if (a == "--callgrind") {
      callgrind = true;
    } else if (a == "--quick") {
      reps = 5, scaleReps = 3;
    } else {
      std::fprintf(stderr,
                   "usage: bench_surface_peers [--reps N] [--scale-reps N] [--out FILE] [--callgrind] [--quick]\n"
                   "       bench_surface_peers --count SET ours|ours-one-block|cache|splat|dense|value|peer|peer-scalar|peer-no-normals "
                   "[MESHES]\n");
      return 2;
    }
  }
  const std::string loadStart = benchplot::loadAverage();
  std::ostringstream md;
  md << "## Against the dense-lattice peer, measured in one run (issue 20)\n\n"
     << "Generated by `bench_surface_peers --reps " << reps << " --scale-reps " << scaleReps
     << (callgrind ? " --callgrind" : "")
     << " --out docs/surface.md` (optional target, built only when CMake finds VTK 9: "
     << "`apt-get install libvtk9-dev`, then `cmake --build build/dev --target bench_surface_peers` and run "
     << "`build/dev/tests/bench/bench_surface_peers`). Peer = every particle splatted into a dense float lattice over "
     << "the particles' bounding box plus Rc (same f, same global lattice; particles in lattice-z order by a counting "
     << "sort, each row of a particle's ball one to three 8-wide AVX2 windows with masked loads and stores; split in "
     << "z-slabs over the threads), then VTK 9.1 `vtkFlyingEdges3D` with normals (TBB backend, "
     << "`vtkSMPTools::Initialize(threads)`). Ours = `SurfaceExtractor` with default `SurfaceParams` (Rc = 3, "
     << "T = 0.2; field route `automatic`: the slice splat with the dense scan, per the CPU table below). "
        "Rounds interleave the two routes; every timed mesh follows an untimed one of the same route; "
     << "medians of " << reps << " rounds, wall clock. Bars (issue 20): ours / peer <= 0.8 on one thread; two threads "
     << ">= 1.7x one thread on spray and explosion; working memory on spray < 2.4 MB; no allocation per mesh after "
     << "warm-up (operator new calls counted over 20 meshes after 3 untimed ones, before VTK has run).\n\n"
     << "| set | S | triangles ours / peer | ours ms 1 thr | peer ms 1 thr | ours / peer 1 thr | ours ms 2 thr | "
        "peer ms 2 thr | ours / peer 2 thr | ours 2 thr speed-up | ours working MB (2 thr) | peer lattice MB | "
        "operator new calls in 20 warm meshes (ours alone), 1 thr / 2 thr "
        "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  setsTables(reps, md);
  if (callgrind) callgrindTable(argv[0], md);
  scalingTable(scaleReps, md);
  md << "\nLoad average (1, 5, 15 min) from /proc/loadavg: " << loadStart << " at the start, "
     << benchplot::loadAverage() << " at the end of the run, on " << std::thread::hardware_concurrency()
     << " hardware threads.\n";

  writeSection(outPath, md);
  return 0;
}
