// The DFSPH pair loops (pair_loops.hpp): portable lanes and AVX2 lanes.
#include "fluid/sph/pair_loops.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include <cmath>

namespace fluid::sph_step {
namespace {

constexpr int kLanes = 8;

// The fixed lane tree: ((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7)).
inline float hsum8(const float* s) {
  const float t0 = s[0] + s[4], t1 = s[1] + s[5], t2 = s[2] + s[6], t3 = s[3] + s[7];
  return (t0 + t2) + (t1 + t3);
}

// One lane of the density pass for x = x_i - x_j: W and m grad W_ij. Coincident particles
// (r <= r_min) have grad W = 0 between them and could never separate; they get the kernel's
// steepest slope along a direction fixed by the two ids (odd in i <-> j, so momentum is still
// conserved), which pushes stacked particles apart deterministically.
inline void densityLane(const DensityConsts& c, glm::vec3 x, std::uint32_t id_i, std::uint32_t id_j, float& w,
                        glm::vec3& g) {
  const float r = std::sqrt((x.x * x.x + x.y * x.y) + x.z * x.z);
  const float q = r * c.inv_support;
  const float t = 1.0f - q;
  float dw;
  if (q <= 0.5f) {
    w = c.sigma * ((6.0f * q * q * q - 6.0f * q * q) + 1.0f);
    dw = c.c_inner * (18.0f * q * q - 12.0f * q);
  } else {
    w = c.sigma2 * t * t * t;
    dw = c.c_outer * t * t;
  }
  if (r > c.r_min) {
    const float dr = dw / r;
    g = glm::vec3(c.mass * (dr * x.x), c.mass * (dr * x.y), c.mass * (dr * x.z));
  } else {
    g = c.steepest_mass * coincidentDirection(id_i, id_j);
  }
}

// Portable lanes.
DensitySums densityPortable(const DensityConsts& c, const glm::vec4* positions, const std::uint32_t* id,
                            const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, std::uint32_t i,
                            const PairBlocks& out) {
  float sw[kLanes] = {}, sx[kLanes] = {}, sy[kLanes] = {}, sz[kLanes] = {}, sq[kLanes] = {};
  const glm::vec4 xi = positions[i];
  const std::uint32_t p = out.start[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const std::uint32_t j = nbr[k], d = p + (k - b);
    out.nb16[d] = j << 4;
    const glm::vec4 xj = positions[j];
    float wv;
    glm::vec3 g;
    densityLane(c, glm::vec3(xi.x - xj.x, xi.y - xj.y, xi.z - xj.z), id[i], id[j], wv, g);
    out.gx[d] = g.x;
    out.gy[d] = g.y;
    out.gz[d] = g.z;
    sw[l] += wv;
    sx[l] += g.x;
    sy[l] += g.y;
    sz[l] += g.z;
    sq[l] += (g.x * g.x + g.y * g.y) + g.z * g.z;
  }
  for (std::uint32_t d = p + (e - b); d < out.start[i + 1]; ++d) {
    out.nb16[d] = 0;
    out.gx[d] = out.gy[d] = out.gz[d] = 0.0f;
  }
  DensitySums sums;
  sums.w = hsum8(sw);
  sums.grad = glm::vec3(hsum8(sx), hsum8(sy), hsum8(sz));
  sums.sq = hsum8(sq);
  return sums;
}

void densityRangePortable(const DensityConsts& c, const glm::vec4* positions, const std::uint32_t* id,
                          const std::uint32_t* nbr, const std::uint32_t* b, const std::uint32_t* e, std::uint32_t i0,
                          std::uint32_t i1, const PairBlocks& out, DensitySums* sums) {
  for (std::uint32_t i = i0; i < i1; ++i) sums[i - i0] = densityPortable(c, positions, id, nbr, b[i], e[i], i, out);
}

glm::vec3 viscosityPortable(const glm::vec4* positions, const IterationArgs& a, std::uint32_t i, float eps) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  const glm::vec4* velocities = a.vel4;
  const glm::vec4 xi = positions[i], vi = velocities[i];
  const std::uint32_t b = a.start[i], e = b + a.cnt[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const std::uint32_t j = a.nb16[k] >> 4;
    const float x = xi.x - positions[j].x, y = xi.y - positions[j].y, z = xi.z - positions[j].z;
    const float vx = ((vi.x - velocities[j].x) * x + (vi.y - velocities[j].y) * y) + (vi.z - velocities[j].z) * z;
    const float denom = ((x * x + y * y) + z * z) + eps;
    const float coef = velocities[j].w * (vx / denom);
    ax[l] += coef * a.gx[k];
    ay[l] += coef * a.gy[k];
    az[l] += coef * a.gz[k];
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}

void viscosityRangePortable(const glm::vec4* positions, const IterationArgs& a, std::uint32_t i0, std::uint32_t i1,
                            float eps, glm::vec3* out) {
  for (std::uint32_t i = i0; i < i1; ++i) out[i - i0] = viscosityPortable(positions, a, i, eps);
}

inline float divergencePortable(const IterationArgs& a, std::uint32_t i) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  const glm::vec3 vi(a.vel4[i]);
  const std::uint32_t b = a.start[i], e = b + a.cnt[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const glm::vec4 vj = a.vel4[a.nb16[k] >> 4];
    ax[l] += (vi.x - vj.x) * a.gx[k];
    ay[l] += (vi.y - vj.y) * a.gy[k];
    az[l] += (vi.z - vj.z) * a.gz[k];
  }
  float s[kLanes];
  for (int l = 0; l < kLanes; ++l) s[l] = (ax[l] + ay[l]) + az[l];
  return hsum8(s);
}

inline glm::vec3 kappaSumPortable(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i) {
  float ax[kLanes] = {}, ay[kLanes] = {}, az[kLanes] = {};
  const float ki = kr4[i].x;
  const std::uint32_t b = a.start[i], e = b + a.cnt[i];
  for (std::uint32_t k = b; k < e; ++k) {
    const int l = static_cast<int>((k - b) % kLanes);
    const float s = ki + kr4[a.nb16[k] >> 4].x;
    ax[l] += s * a.gx[k];
    ay[l] += s * a.gy[k];
    az[l] += s * a.gz[k];
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}

void divergenceRangePortable(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out) {
  for (std::uint32_t i = i0; i < i1; ++i) out[i - i0] = divergencePortable(a, i);
}
void kappaRangePortable(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1,
                        glm::vec3* out) {
  for (std::uint32_t i = i0; i < i1; ++i) out[i - i0] = kappaSumPortable(a, kr4, i);
}

constexpr PairLoops kPortableLoops{&densityRangePortable, &viscosityRangePortable, &divergenceRangePortable,
                                   &kappaRangePortable};

#if defined(__x86_64__) && defined(__GNUC__)
#define FLUID_SPH_AVX2_PAIRS 1
// AVX2 lanes. Neighbour data come in by one 16-byte load per neighbour (pos4 / vel4) or
// scalar loads (load8): on the Zen 3 machine we measure on, vgatherdps was slower than the
// SSE2 loop it replaced. In the density pass's last block of a list (fewer than 8 pairs) the
// lanes past the end read particle 0 (valid data) and are zeroed by a lane mask, so they add
// exact zeros and store the zero pads of the lane blocks (pair_loops.hpp); the other loops read
// whole blocks.
#define FLUID_AVX2 __attribute__((target("avx2")))
FLUID_AVX2 inline __m256i laneMask(std::uint32_t left) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(std::min<std::uint32_t>(left, 8))),
                            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}
// hsum8's tree in registers: t_l = s_l + s_(l+4), then (t0 + t2) + (t1 + t3).
FLUID_AVX2 inline float hsum8(__m256 v) {
  const __m128 t = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 u = _mm_add_ps(t, _mm_movehl_ps(t, t));
  return _mm_cvtss_f32(_mm_add_ss(u, _mm_shuffle_ps(u, u, 1)));
}
FLUID_AVX2 inline __m256 loadPair(const glm::vec4* base, std::uint32_t a, std::uint32_t b) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&base[a].x)), _mm_loadu_ps(&base[b].x), 1);
}
// Rows r0..r3 hold records (0, 4), (1, 5), (2, 6), (3, 7) in their low | high halves; writes
// the components of the eight records in lane order (w only when asked for).
FLUID_AVX2 inline void transposeRows(__m256 r0, __m256 r1, __m256 r2, __m256 r3, __m256& x, __m256& y, __m256& z,
                                     __m256* w) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);  // x0 x1 y0 y1 | x4 x5 y4 y5; z.. w..
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  x = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  y = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  z = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  if (w != nullptr) *w = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
FLUID_AVX2 inline void load8xyz(const glm::vec4* base, const std::uint32_t* idx, __m256& x, __m256& y, __m256& z) {
  transposeRows(loadPair(base, idx[0], idx[4]), loadPair(base, idx[1], idx[5]), loadPair(base, idx[2], idx[6]),
                loadPair(base, idx[3], idx[7]), x, y, z, nullptr);
}
// The last block of a list: lanes past `left` read particle 0 (valid data; their gradient
// lanes are masked to 0, so they add exact zeros).
FLUID_AVX2 inline const std::uint32_t* tailIndices(const std::uint32_t* nbr, std::uint32_t left, std::uint32_t* buf) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(buf),
                      _mm256_maskload_epi32(reinterpret_cast<const int*>(nbr), laneMask(left)));
  return buf;
}

// load8xyz with byte offsets o[l] = 16 idx[l].
FLUID_AVX2 inline __m256 loadPair16(const glm::vec4* base, std::uint32_t a, std::uint32_t b) {
  const char* p = reinterpret_cast<const char*>(base);
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(reinterpret_cast<const float*>(p + a))),
                              _mm_loadu_ps(reinterpret_cast<const float*>(p + b)), 1);
}
FLUID_AVX2 inline void load8xyz16(const glm::vec4* base, const std::uint32_t* o, __m256& x, __m256& y, __m256& z) {
  transposeRows(loadPair16(base, o[0], o[4]), loadPair16(base, o[1], o[5]), loadPair16(base, o[2], o[6]),
                loadPair16(base, o[3], o[7]), x, y, z, nullptr);
}
// The same with the 4th component.
FLUID_AVX2 inline void load8xyzw16(const glm::vec4* base, const std::uint32_t* o, __m256& x, __m256& y, __m256& z,
                                   __m256& w) {
  transposeRows(loadPair16(base, o[0], o[4]), loadPair16(base, o[1], o[5]), loadPair16(base, o[2], o[6]),
                loadPair16(base, o[3], o[7]), x, y, z, &w);
}
// base[idx[l]].x for byte offsets o[l] = 16 idx[l], by scalar loads (Zen 3 runs these faster
// than vgatherdps).
FLUID_AVX2 inline __m256 load8x16(const glm::vec4* base, const std::uint32_t* o) {
  const char* p = reinterpret_cast<const char*>(base);
  auto at = [p](std::uint32_t off) { return reinterpret_cast<const float*>(p + off); };
  const __m128 lo = _mm_insert_ps(
      _mm_insert_ps(_mm_insert_ps(_mm_load_ss(at(o[0])), _mm_load_ss(at(o[1])), 0x10), _mm_load_ss(at(o[2])), 0x20),
      _mm_load_ss(at(o[3])), 0x30);
  const __m128 hi = _mm_insert_ps(
      _mm_insert_ps(_mm_insert_ps(_mm_load_ss(at(o[4])), _mm_load_ss(at(o[5])), 0x10), _mm_load_ss(at(o[6])), 0x20),
      _mm_load_ss(at(o[7])), 0x30);
  return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}

// One particle's density pass into its five lane accumulators acc[0..4]: W, the three gradient
// components and |gradient|^2.
FLUID_AVX2 inline void densityAvx2(const DensityConsts& c, const glm::vec4* positions, const std::uint32_t* id,
                                   const std::uint32_t* nbr, std::uint32_t b, std::uint32_t e, std::uint32_t i,
                                   const PairBlocks& out, __m256* acc) {
  const glm::vec4 xi = positions[i];
  const __m256 pix = _mm256_set1_ps(xi.x), piy = _mm256_set1_ps(xi.y), piz = _mm256_set1_ps(xi.z);
  const __m256 inv_h = _mm256_set1_ps(c.inv_support), sigma = _mm256_set1_ps(c.sigma),
               sigma2 = _mm256_set1_ps(c.sigma2), c_in = _mm256_set1_ps(c.c_inner), c_out = _mm256_set1_ps(c.c_outer),
               mass = _mm256_set1_ps(c.mass), r_min = _mm256_set1_ps(c.r_min), one = _mm256_set1_ps(1.0f),
               half = _mm256_set1_ps(0.5f), six = _mm256_set1_ps(6.0f), c18 = _mm256_set1_ps(18.0f),
               c12 = _mm256_set1_ps(12.0f);
  __m256 sw = _mm256_setzero_ps(), sx = sw, sy = sw, sz = sw, sq = sw;
  alignas(32) std::uint32_t buf[kLanes];
  // d: the block's place in i's lane blocks (aligned; the last block's pad lanes get zeros).
  for (std::uint32_t k = b, d = out.start[i]; k < e; k += kLanes, d += kLanes) {
    const __m256i mi = laneMask(e - k);
    const __m256 m = _mm256_castsi256_ps(mi);
    const std::uint32_t* idx = e - k >= kLanes ? nbr + k : tailIndices(nbr + k, e - k, buf);
    __m256 x, y, z;
    load8xyz(positions, idx, x, y, z);
    x = _mm256_sub_ps(pix, x);
    y = _mm256_sub_ps(piy, y);
    z = _mm256_sub_ps(piz, z);
    const __m256 r =
        _mm256_sqrt_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)));
    const __m256 q = _mm256_mul_ps(r, inv_h);
    const __m256 t = _mm256_sub_ps(one, q);
    const __m256 q6q = _mm256_mul_ps(_mm256_mul_ps(six, q), q);
    const __m256 w_in = _mm256_mul_ps(sigma, _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(q6q, q), q6q), one));
    const __m256 dw_in =
        _mm256_mul_ps(c_in, _mm256_sub_ps(_mm256_mul_ps(_mm256_mul_ps(c18, q), q), _mm256_mul_ps(c12, q)));
    const __m256 tt = _mm256_mul_ps(_mm256_mul_ps(sigma2, t), t);
    const __m256 w_out = _mm256_mul_ps(tt, t);
    const __m256 dw_out = _mm256_mul_ps(_mm256_mul_ps(c_out, t), t);
    const __m256 inner = _mm256_cmp_ps(q, half, _CMP_LE_OQ);
    // Masked lanes have x = x_i, so they are inside or outside the support: their W is zeroed.
    const __m256 wv = _mm256_and_ps(_mm256_blendv_ps(w_out, w_in, inner), m);
    const __m256 dr = _mm256_div_ps(_mm256_blendv_ps(dw_out, dw_in, inner), r);
    __m256 g0 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, x));
    __m256 g1 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, y));
    __m256 g2 = _mm256_mul_ps(mass, _mm256_mul_ps(dr, z));
    const __m256 close = _mm256_and_ps(_mm256_cmp_ps(r, r_min, _CMP_LE_OQ), m);
    if (_mm256_movemask_ps(close) != 0) {  // rare: coincident particles, lane by lane
      alignas(32) float a0[kLanes], a1[kLanes], a2[kLanes];
      _mm256_store_ps(a0, g0);
      _mm256_store_ps(a1, g1);
      _mm256_store_ps(a2, g2);
      const int bits = _mm256_movemask_ps(close);
      for (int l = 0; l < kLanes; ++l)
        if (bits & (1 << l)) {
          const glm::vec3 g = c.steepest_mass * coincidentDirection(id[i], id[nbr[k + l]]);
          a0[l] = g.x;
          a1[l] = g.y;
          a2[l] = g.z;
        }
      g0 = _mm256_load_ps(a0);
      g1 = _mm256_load_ps(a1);
      g2 = _mm256_load_ps(a2);
    }
    g0 = _mm256_and_ps(g0, m);
    g1 = _mm256_and_ps(g1, m);
    g2 = _mm256_and_ps(g2, m);
    // Whole blocks, pads included (tailIndices left 0 in the pad lanes, so 16 j = 0 there).
    _mm256_store_si256(reinterpret_cast<__m256i*>(out.nb16 + d),
                       _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(idx)), 4));
    _mm256_store_ps(out.gx + d, g0);
    _mm256_store_ps(out.gy + d, g1);
    _mm256_store_ps(out.gz + d, g2);
    sw = _mm256_add_ps(sw, wv);
    sx = _mm256_add_ps(sx, g0);
    sy = _mm256_add_ps(sy, g1);
    sz = _mm256_add_ps(sz, g2);
    sq = _mm256_add_ps(
        sq, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(g0, g0), _mm256_mul_ps(g1, g1)), _mm256_mul_ps(g2, g2)));
  }
  acc[0] = sw;
  acc[1] = sx;
  acc[2] = sy;
  acc[3] = sz;
  acc[4] = sq;
}

// The loops below run over i's whole lane blocks [start[i], start[i + 1]) with aligned loads.
FLUID_AVX2 inline void viscosityAvx2(const glm::vec4* positions, const IterationArgs& a, std::uint32_t i, float eps,
                                     __m256* acc) {
  const glm::vec4* velocities = a.vel4;
  const __m256 pix = _mm256_set1_ps(positions[i].x), piy = _mm256_set1_ps(positions[i].y),
               piz = _mm256_set1_ps(positions[i].z);
  const __m256 vix = _mm256_set1_ps(velocities[i].x), viy = _mm256_set1_ps(velocities[i].y),
               viz = _mm256_set1_ps(velocities[i].z);
  const __m256 ve = _mm256_set1_ps(eps);
  __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
  for (std::uint32_t k = a.start[i], e = a.start[i + 1]; k < e; k += kLanes) {
    __m256 xj, yj, zj, vcj, uj, vj, wj;
    load8xyz16(positions, a.nb16 + k, xj, yj, zj);
    load8xyzw16(velocities, a.nb16 + k, uj, vj, wj, vcj);
    const __m256 x = _mm256_sub_ps(pix, xj), y = _mm256_sub_ps(piy, yj), z = _mm256_sub_ps(piz, zj);
    const __m256 vx =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(vix, uj), x), _mm256_mul_ps(_mm256_sub_ps(viy, vj), y)),
                      _mm256_mul_ps(_mm256_sub_ps(viz, wj), z));
    const __m256 denom =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)), ve);
    const __m256 coef = _mm256_mul_ps(vcj, _mm256_div_ps(vx, denom));
    ax = _mm256_add_ps(ax, _mm256_mul_ps(coef, _mm256_load_ps(a.gx + k)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(coef, _mm256_load_ps(a.gy + k)));
    az = _mm256_add_ps(az, _mm256_mul_ps(coef, _mm256_load_ps(a.gz + k)));
  }
  acc[0] = ax;
  acc[1] = ay;
  acc[2] = az;
}

// hsum8's tree for eight particles at once: lane p of the result is hsum8(v[p]). The same adds
// on the same pairs (t_l = s_l + s_(l+4), then (t0 + t2) + (t1 + t3)), done across registers, so
// a range pays one short reduction per eight particles instead of a dependent chain per particle.
FLUID_AVX2 inline __m256 laneHalves(__m256 x, __m256 y) {  // [t(x) | t(y)]
  return _mm256_add_ps(_mm256_permute2f128_ps(x, y, 0x20), _mm256_permute2f128_ps(x, y, 0x31));
}
FLUID_AVX2 inline __m256 lanePairs(__m256 x, __m256 y) {  // per 128-bit half: t0 + t2, t1 + t3 of x, then of y
  return _mm256_add_ps(_mm256_shuffle_ps(x, y, _MM_SHUFFLE(1, 0, 1, 0)),
                       _mm256_shuffle_ps(x, y, _MM_SHUFFLE(3, 2, 3, 2)));
}
FLUID_AVX2 inline __m256 hsum8x8(const __m256* v) {
  const __m256 u0 = lanePairs(laneHalves(v[0], v[1]), laneHalves(v[2], v[3]));  // particles 0, 2 | 1, 3
  const __m256 u1 = lanePairs(laneHalves(v[4], v[5]), laneHalves(v[6], v[7]));  // particles 4, 6 | 5, 7
  const __m256 s = _mm256_add_ps(_mm256_shuffle_ps(u0, u1, _MM_SHUFFLE(2, 0, 2, 0)),
                                 _mm256_shuffle_ps(u0, u1, _MM_SHUFFLE(3, 1, 3, 1)));  // 0 2 4 6 | 1 3 5 7
  return _mm256_permutevar8x32_ps(s, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
}

// The per-particle sums of a group of eight, particles g .. g + m - 1 (m <= 8): lane(i, one) leaves
// particle i's Q accumulators in one, a short group's missing particles get zero accumulators, and
// t[q][p] is hsum8 of particle g + p's q-th accumulator (hsum8x8's tree, the same adds as hsum8).
template <int Q, class Lane>
FLUID_AVX2 inline void groupSums(std::uint32_t g, std::uint32_t m, const Lane& lane, float (&t)[Q][kLanes]) {
  __m256 acc[Q][kLanes];
  for (std::uint32_t p = 0; p < kLanes; ++p) {
    __m256 one[Q];
    if (p < m)
      lane(g + p, one);
    else
      for (int q = 0; q < Q; ++q) one[q] = _mm256_setzero_ps();
    for (int q = 0; q < Q; ++q) acc[q][p] = one[q];
  }
  for (int q = 0; q < Q; ++q) _mm256_store_ps(t[q], hsum8x8(acc[q]));
}

// The density pass of a range, eight particles per group (missing particles are not stored).
FLUID_AVX2 void densityRangeAvx2(const DensityConsts& c, const glm::vec4* positions, const std::uint32_t* id,
                                 const std::uint32_t* nbr, const std::uint32_t* b, const std::uint32_t* e,
                                 std::uint32_t i0, std::uint32_t i1, const PairBlocks& out, DensitySums* sums) {
  const auto lane = [&](std::uint32_t i, __m256* one)
                        FLUID_AVX2 { densityAvx2(c, positions, id, nbr, b[i], e[i], i, out, one); };
  for (std::uint32_t g = i0; g < i1; g += kLanes) {
    const std::uint32_t m = std::min<std::uint32_t>(kLanes, i1 - g);
    alignas(32) float t[5][kLanes];
    groupSums(g, m, lane, t);
    for (std::uint32_t p = 0; p < m; ++p) {
      DensitySums& out_sums = sums[g - i0 + p];
      out_sums.w = t[0][p];
      out_sums.grad = glm::vec3(t[1][p], t[2][p], t[3][p]);
      out_sums.sq = t[4][p];
    }
  }
}

// The viscosity sums of a range, eight particles per group (as densityRangeAvx2).
FLUID_AVX2 void viscosityRangeAvx2(const glm::vec4* positions, const IterationArgs& a, std::uint32_t i0,
                                   std::uint32_t i1, float eps, glm::vec3* out) {
  const auto lane = [&](std::uint32_t i, __m256* one) FLUID_AVX2 { viscosityAvx2(positions, a, i, eps, one); };
  for (std::uint32_t g = i0; g < i1; g += kLanes) {
    const std::uint32_t m = std::min<std::uint32_t>(kLanes, i1 - g);
    alignas(32) float t[3][kLanes];
    groupSums(g, m, lane, t);
    for (std::uint32_t p = 0; p < m; ++p) out[g - i0 + p] = glm::vec3(t[0][p], t[1][p], t[2][p]);
  }
}

// The solver iterations' divergence loop, eight particles per group (a short last group gets
// zero accumulators for its missing particles, which are not stored).
FLUID_AVX2 void divergenceRangeAvx2(const IterationArgs& a, std::uint32_t i0, std::uint32_t i1, float* out) {
  const glm::vec4* const vel = a.vel4;
  const float *const gx = a.gx, *const gy = a.gy, *const gz = a.gz;
  const std::uint32_t *const nb16 = a.nb16, *const start = a.start;
  for (std::uint32_t g = i0; g < i1; g += kLanes) {
    const std::uint32_t m = std::min<std::uint32_t>(kLanes, i1 - g);
    __m256 acc[kLanes];
    for (std::uint32_t p = 0; p < kLanes; ++p) {
      __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
      if (p < m) {
        const glm::vec4 vi = vel[g + p];
        const __m256 vix = _mm256_set1_ps(vi.x), viy = _mm256_set1_ps(vi.y), viz = _mm256_set1_ps(vi.z);
        for (std::uint32_t k = start[g + p], e = start[g + p + 1]; k < e; k += kLanes) {
          __m256 vx, vy, vz;
          load8xyz16(vel, nb16 + k, vx, vy, vz);
          ax = _mm256_add_ps(ax, _mm256_mul_ps(_mm256_sub_ps(vix, vx), _mm256_load_ps(gx + k)));
          ay = _mm256_add_ps(ay, _mm256_mul_ps(_mm256_sub_ps(viy, vy), _mm256_load_ps(gy + k)));
          az = _mm256_add_ps(az, _mm256_mul_ps(_mm256_sub_ps(viz, vz), _mm256_load_ps(gz + k)));
        }
      }
      acc[p] = _mm256_add_ps(_mm256_add_ps(ax, ay), az);
    }
    const __m256 sums = hsum8x8(acc);
    if (m == kLanes) {
      _mm256_storeu_ps(out + (g - i0), sums);
    } else {
      alignas(32) float t[kLanes];
      _mm256_store_ps(t, sums);
      for (std::uint32_t p = 0; p < m; ++p) out[g - i0 + p] = t[p];
    }
  }
}

// The kappa loop keeps one reduction per particle: with three sums a particle, staging eight
// particles' accumulators for hsum8x8 cost more instructions than it saved (callgrind).
FLUID_AVX2 inline glm::vec3 kappaSumAvx2(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i) {
  const __m256 vk = _mm256_set1_ps(kr4[i].x);
  __m256 ax = _mm256_setzero_ps(), ay = ax, az = ax;
  for (std::uint32_t k = a.start[i], e = a.start[i + 1]; k < e; k += kLanes) {
    const __m256 s = _mm256_add_ps(vk, load8x16(kr4, a.nb16 + k));
    ax = _mm256_add_ps(ax, _mm256_mul_ps(s, _mm256_load_ps(a.gx + k)));
    ay = _mm256_add_ps(ay, _mm256_mul_ps(s, _mm256_load_ps(a.gy + k)));
    az = _mm256_add_ps(az, _mm256_mul_ps(s, _mm256_load_ps(a.gz + k)));
  }
  return {hsum8(ax), hsum8(ay), hsum8(az)};
}
FLUID_AVX2 void kappaRangeAvx2(const IterationArgs& a, const glm::vec4* kr4, std::uint32_t i0, std::uint32_t i1,
                               glm::vec3* out) {
  for (std::uint32_t i = i0; i < i1; ++i) out[i - i0] = kappaSumAvx2(a, kr4, i);
}
#undef FLUID_AVX2

constexpr PairLoops kAvx2Loops{&densityRangeAvx2, &viscosityRangeAvx2, &divergenceRangeAvx2, &kappaRangeAvx2};
#endif

}  // namespace

const PairLoops& pairLoops(bool portable) {
#if defined(FLUID_SPH_AVX2_PAIRS)
  if (!portable && __builtin_cpu_supports("avx2")) return kAvx2Loops;
#endif
  (void)portable;
  return kPortableLoops;
}

}  // namespace fluid::sph_step
