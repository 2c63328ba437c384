// Internal: the slice-splat field route (SurfaceFieldRoute::sliceSplat). Part of BlockMesher's class
// body, included by block_mesher.inl (twice, see there): no include guard and no includes on purpose.
//
// The sweep of Alg. 1 holds two slices at a time (§4); here each slice's field is summed whole when
// the sweep takes the slice up: the block's particles in (z, index) order each add their term f_i
// (§2) and its gradient to the corners of their disc in that slice, 8 corners of a row at once. A
// corner thus gets exactly the terms of the §6 cache's walk (the particles within Rc_i, found by the
// same double predicate, influences(), and the same clamps to the expanded block's inner corners, so
// the field is 0 on its outer boundary, §3), in the same order and by the same float expressions
// (field.hpp's accumulateDz2S4), so every corner value has the same bits and the mesh is the same.
// Where particles are dense almost every corner of a slice near the surface is needed, and one pass
// over the slice's particles with no per-corner search beats a walk per corner; that is also how the
// dense-lattice peer (dense splat + Flying Edges) sums, only held to two slices instead of a volume.
//
// §4 seeding asks for inside/outside at corners along descents before the march: when the block's
// whole field fits Worker::kVolumeBytes it is summed once up front and serves both; otherwise
// value-only slices (Worker::seedRing) serve seeding, summed the same way (see Worker::setPlanes).
//
// Masked lanes add +0.0f or -0.0f (their w is zeroed, and w, s, k and the offsets are finite), which
// leaves every sum unchanged: x + -0 = x for every x, +0 included, and a sum that starts at +0
// never becomes -0 (round to nearest gives -0 only for -0 + -0).

  // GCC vector extensions: 8 floats, 8 int32 and 4 doubles (two SSE registers each in the
  // portable copy, one AVX register in the AVX2 one; the same IEEE operations lane by lane, no FMA).
  using SplatF8 = float __attribute__((vector_size(32)));
  using SplatI8 = std::int32_t __attribute__((vector_size(32)));
  using SplatD4 = double __attribute__((vector_size(32)));
  using SplatU8 = std::uint32_t __attribute__((vector_size(32)));
  using SplatI4 = std::int32_t __attribute__((vector_size(16)));
  int splatReachMax_ = 0;  // largest particleReach() of the block's particles (prepareSplat)
  float oneSpan2_ = 0;     // float((4 S)^2): splatSlice's one-window rows
  float invS_ = 1, hSlack_ = 0;  // float(1 / S) and float(1e-3 S): splatSlice's disc rows
  int splatFirst_ = 1, splatLast_[2] = {0, 0};  // rows and columns written: first (both), last x, last y

  // Block setup for the route: the block particles' float records (CacheParticle, as the cache has
  // them), the offsets table float(d S) and the corners' x coordinates over the padded plane rows.
  void prepareSplat(std::span<const Particle> particles) {
    const int m = su_.m;
    // Windows start at most 2 m + 9 columns from a particle's anchor either way (splatSlice).
    offsetRange_ = 2 * m + 10;
    oneSpan2_ = float(16.0 * su_.s * su_.s);
    invS_ = float(1.0 / su_.s);
    hSlack_ = float(1e-3 * su_.s);
    w_.splatOffsets.resize(std::size_t(2 * offsetRange_ + 1));
    for (int d = -offsetRange_; d <= offsetRange_; ++d)
      w_.splatOffsets[std::size_t(d + offsetRange_)] = float(double(d) * su_.s);
    // The corners the splat writes: the expanded block's inner ones (the walk and §4 seeding read
    // margin corners too; the outer faces stay 0, §3), or for the dense scan, which reads nothing
    // but the interior's corners, the interior alone (a particle near a seam then writes each of
    // its corners in one block only); valueScan's central differences also read the ring of
    // corners around the interior (m >= 2 there, so the ring is inside the outer faces).
    const int ring = int(su_.valueOnly);
    const int lo = su_.dense ? su_.m - ring : 1;
    splatLast_[0] = su_.dense ? su_.m + su_.b[0] + ring : nx_ - 1;
    splatLast_[1] = su_.dense ? su_.m + su_.b[1] + ring : ny_ - 1;
    splatFirst_ = lo;
    w_.splatInBlock.resize(std::size_t(w_.planeStride));
    for (int x = 0; x < w_.planeStride; ++x)
      w_.splatInBlock[std::size_t(x)] = x >= lo && x <= splatLast_[0] ? -1 : 0;
    w_.splatCx.resize(std::size_t(nx_ + 1 + 2 * m + 16));
    for (int i = -m; i <= nx_ + m + 15; ++i) w_.splatCx[std::size_t(i + m)] = double(g0_[0] + i) * su_.s;
    w_.local.resize(particles.size());
    w_.splatReach.resize(particles.size());
    // Each route's predicate data alone: splatSlice's band, or the value scan's float(Rc_i^2).
    w_.splatBand.resize(su_.valueOnly ? 0 : particles.size());
    w_.splatRc2.resize(su_.valueOnly ? particles.size() : 0);
    splatReachMax_ = 0;
    for (std::uint32_t li = 0; li < particles.size(); ++li) {
      const Particle& p = particles[li];
      const int r = particleReach(p, su_.s);  // <= m (blockSpan)
      w_.splatReach[li] = std::int16_t(r);
      splatReachMax_ = std::max(splatReachMax_, r);
      if (su_.valueOnly) {
        w_.splatRc2[li] = float(p.rc2);
      } else {  // splatSlice's band around Rc_i^2 where the float r^2 does not settle a lane
        const double span = double(r + 9) * su_.s, tol = 3e-5 * span * span;
        w_.splatBand[li] = {float(p.rc2 - tol), float(p.rc2 + tol)};
      }
      CacheParticle& cp = w_.local[li];
      for (int a = 0; a < 3; ++a) {
        cp.rest[a] = p.rest[a];
        assert(p.anchor[a] - g0_[a] >= 0 && p.anchor[a] - g0_[a] <= su_.n[a]);  // as buildParticleCache
        cp.na[a] = std::int16_t(g0_[a] - p.anchor[a]);
      }
      cp.k = p.k;
      cp.s = p.strength;
      cp.s4 = 4.0f * p.strength;
    }
    std::fill(w_.ringZ.begin(), w_.ringZ.end(), -1);
    parts_ = w_.local.data();
    if (w_.volumeMode)  // the whole block's field, once (see Worker::setPlanes)
      for (int z = 0; z <= nz_; ++z)
        splatSliceInto(w_.volume.data() + std::size_t(z) * 4 * w_.planeFloats, z, w_.volumeRect[std::size_t(z)]);
  }

  // Sums slice z into four planes that are 0 outside `rect`, what their last splat wrote (rows
  // y0..y1, columns x0..x1): only that is cleared first, so a sparse slice costs what its particles
  // write, not the whole plane; `rect` becomes what this splat wrote.
  void splatSliceInto(float* planes, int z, std::array<std::int16_t, 4>& rect) {
    for (int y = rect[0]; y <= rect[1]; ++y)
      for (int a = 0; a < 4; ++a) {
        float* row = planes + std::size_t(a) * w_.planeFloats + std::size_t(y) * std::size_t(w_.planeStride);
        std::fill(row + rect[2], row + rect[3] + 1, 0.0f);
      }
    looked_ += splatSlice<true>(planes, z, &rect);
  }

  // Slice z's planes for the sweep: its part of the block's volume, or summed into its own.
  void attachPlanes(Slice<Policy>& slice, int z) {
    if (w_.volumeMode) {
      slice.planes = w_.volume.data() + std::size_t(z) * 4 * w_.planeFloats;
    } else {
      looked_ += splatSlice<true>(slice.field.data(), z);
      slice.planes = slice.field.data();
    }
  }

  // Whether any lane of an int mask is set. (By reference: a 32-byte vector by value would be
  // passed differently with and without AVX where not inlined, GCC's -Wpsabi note.)
  static bool anyLane(const SplatI8& m) {
#if defined(FLUID_SURFACE_IN_AVX2_COPY)
    const __m256i v = reinterpret_cast<const __m256i&>(m);
    return !_mm256_testz_si256(v, v);
#else
    const SplatI4 lo = __builtin_shufflevector(m, m, 0, 1, 2, 3), hi = __builtin_shufflevector(m, m, 4, 5, 6, 7);
    const SplatI4 o = lo | hi;
    return (o[0] | o[1] | o[2] | o[3]) != 0;
#endif
  }
  // Whether any lane of an int mask is clear.
  static bool anyLaneClear(const SplatI8& m) {
#if defined(FLUID_SURFACE_IN_AVX2_COPY)
    const __m256i v = reinterpret_cast<const __m256i&>(m);
    return !_mm256_testc_si256(v, _mm256_set1_epi32(-1));
#else
    const SplatI4 lo = __builtin_shufflevector(m, m, 0, 1, 2, 3), hi = __builtin_shufflevector(m, m, 4, 5, 6, 7);
    const SplatI4 a = lo & hi;
    return (a[0] & a[1] & a[2] & a[3]) != -1;
#endif
  }

  // Sums slice z's field into `planes` (value, then with kGrad df/dx, df/dy, df/dz; Worker::planeFloats
  // each, cleared first). Returns the number of particle terms added.
  //
  // Which corners a particle reaches is decided by influences()'s double predicate. The float
  // r^2 = (dx dx + dy dy) + dz dz that the term is made of anyway agrees with it to within about
  // 2e-6 L^2 (L = (reach + 9) S bounds every offset in the 8-wide windows: float(d S) and rest are
  // each within 2^-24 of their value, the squares and sums add a few more such errors), so a lane
  // with float r^2 more than tol = 3e-5 L^2 from Rc_i^2 is settled by it; a window with a lane
  // inside that band is decided lane by lane in double, as influences() does.
  // With `rect` the planes are already 0 outside what the splat writes, and the rows and columns it
  // writes are stored there (Worker::volumeRect).
  template <bool kGrad>
  std::uint64_t splatSlice(float* planes, int z, std::array<std::int16_t, 4>* rect = nullptr) {
    const std::size_t pf = w_.planeFloats;
    if (rect)
      *rect = {1, 0, 1, 0};
    else
      std::fill(planes, planes + (kGrad ? 4 : 1) * pf, 0.0f);
    if (z < 1 || z > nz_ - 1) return 0;  // outer slices stay 0 (§3)
    int wy0 = ny_, wy1 = 0, wx0 = w_.planeStride, wx1 = 0;  // rows and columns written
    const int m = su_.m, stride = w_.planeStride;
    const CacheParticle* parts = w_.local.data();
    const std::size_t n = w_.local.size();
    // Local anchors along z that can reach slice z (|z - anchor| <= reach); -na[2] is
    // non-decreasing in li.
    const int reachMax = splatReachMax_;
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < z - reachMax; });
    const CacheParticle* last =
        std::partition_point(first, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) <= z + reachMax; });
    const float* off = w_.splatOffsets.data() + offsetRange_;
    const double* cxPad = w_.splatCx.data() + m;  // cxPad[x] = double(g0 + x) S for x in [-m, nx + m + 15]
    const std::int16_t* reachOf = w_.splatReach.data();
    const std::int32_t* inBlockAt = w_.splatInBlock.data();  // -1 on the columns written, else 0
    const int ylo = splatFirst_, yhi = splatLast_[1];
    SplatI8 counted = {};
    for (const CacheParticle* cp = first; cp != last; ++cp) {
      const std::size_t li = std::size_t(cp - parts);
      const Particle& p = particles_[li];
      const double dzd = w_.cz[z] - p.z, dz2d = dzd * dzd;
      if (!(dz2d < p.rc2)) continue;  // (dx^2 + dy^2) + dz^2 >= dz^2 in rounded arithmetic too
      const int r = reachOf[li];
      const int ax = -cp->na[0], ay = -cp->na[1];
      const float dzf = off[z + cp->na[2]] - cp->rest[2], dz2f = dzf * dzf;
      const float rest0 = cp->rest[0], rest1 = cp->rest[1], outFrom = w_.splatBand[li][1];
      // The rows of the particle's disc in this slice (not all of ay - r .. ay + r: every window
      // would test the rows outside it). A corner that influences() accepts has exact dy^2 <
      // Rc_i^2 - dz^2, below outFrom - dz2f by about tol (the float dz2f errs by ~2e-6 L^2, tol =
      // 3e-5 L^2), so |dy| < hz, and the 1e-3 S on top is far beyond the rounding of hz and of the
      // row bounds: rows d = y - ay with |d S - rest| < hz, ceil((rest - hz) / S) .. floor((rest +
      // hz) / S), within blockSpan's -r .. r. (Floors by truncation of x + r + 2 >= 0.)
      // (outFrom > dz2f: dz^2 < Rc_i^2 in double just above.)
      const float hz = std::sqrt(outFrom - dz2f) + hSlack_;
      const int ir = r + 2;
      const float fr = float(ir);
      const int y0 = std::max(ylo, ay + std::max(-r, ir - int((hz - rest1) * invS_ + fr)));
      const int y1 = std::min(yhi, ay + std::min(r, int((rest1 + hz) * invS_ + fr) - ir));
      // Columns ax - r .. ax + r (blockSpan's reach) in `vectors` windows of 8 from xs, the start
      // moved into the row where the reach sticks out of it (the lane mask keeps columns 1 .. nx - 1).
      const int vectors = (2 * r + 8) / 8;
      const int xs = std::min(std::max(ax - r, 0), stride - 8 * vectors);
      const float k = cp->k, s = cp->s, s4 = cp->s4;
      const float inBelow = w_.splatBand[li][0];
      wy0 = std::min(wy0, y0), wy1 = std::max(wy1, y1);
      wx0 = std::min(wx0, xs), wx1 = std::max(wx1, xs + 8 * vectors - 1);
      // Rows ya .. yb in `nv` windows of 8 from column xw.
      // Loop invariants read once: the stores below go through memcpy, which the compiler must
      // assume may write anything, so it would reload cp->na[1] in every row.
      const float* offY = off + cp->na[1];
      auto rows = [&](int xw, int nv, int ya, int yb) __attribute__((always_inline)) {
        float* base = planes + std::size_t(xw);
        for (int v = 0; v < nv; ++v) {
          const int x = xw + 8 * v;
          SplatI8 inBlock;
          std::memcpy(&inBlock, inBlockAt + x, sizeof inBlock);
          SplatF8 offs;
          std::memcpy(&offs, off + (x - ax), sizeof offs);
          const SplatF8 dxf = offs - rest0, dxf2 = dxf * dxf;
          float* at = base + std::size_t(ya) * std::size_t(stride) + 8 * v;
          for (int y = ya; y <= yb; ++y, at += stride) {
            // (No test of dy^2 + dz^2 against outFrom first: the rows are the disc's, and a row just
            // outside it has r^2 >= outFrom on every lane, so its mask is empty and it adds +0.)
            const float dyf = offY[y] - rest1, dy2f = dyf * dyf;
            // accumulateDz2S4's expressions: w = ((dx dx + dy dy) + dz dz) k - 1/2, f += s w^2,
            // grad += (4 s w) k (dx, dy, dz).
            const SplatF8 r2 = (dxf2 + dy2f) + dz2f;
            const SplatI8 in = r2 < inBelow;
            SplatI8 mask = in & inBlock;
            // (Lanes outside the block may take this path too; the mask below drops them.)
            if (anyLaneClear(in | (r2 >= outFrom))) [[unlikely]] {
              // A lane near Rc_i: the exact predicate of influences(), lane by lane in double.
              const double dyd = w_.cy[y] - p.y, dy2d = dyd * dyd;
              SplatD4 cxa, cxb;
              std::memcpy(&cxa, cxPad + x, sizeof cxa);
              std::memcpy(&cxb, cxPad + x + 4, sizeof cxb);
              const SplatD4 dxa = cxa - p.x, dxb = cxb - p.x;
              const auto ina = ((dxa * dxa + dy2d) + dz2d) < p.rc2;
              const auto inb = ((dxb * dxb + dy2d) + dz2d) < p.rc2;
              const SplatI4 ma = __builtin_convertvector(ina, SplatI4), mb = __builtin_convertvector(inb, SplatI4);
              mask = __builtin_shufflevector(ma, mb, 0, 1, 2, 3, 4, 5, 6, 7) & inBlock;
            }
            counted -= mask;
            // w is zeroed on masked lanes (one mask instead of one per plane): their terms are then
            // +-0, which leave every sum as it is (see the top of this file).
            const SplatF8 wv = (SplatF8)((SplatI8)(r2 * k - 0.5f) & mask);
            SplatF8 acc;
            std::memcpy(&acc, at, sizeof acc);
            acc += s * (wv * wv);
            std::memcpy(at, &acc, sizeof acc);
            if constexpr (kGrad) {
              const SplatF8 g = (s4 * wv) * k;
              float* gp[3] = {at + pf, at + 2 * pf, at + 3 * pf};
              const SplatF8 terms[3] = {g * dxf, g * dyf, g * dzf};
              for (int a = 0; a < 3; ++a) {
                std::memcpy(&acc, gp[a], sizeof acc);
                acc += terms[a];
                std::memcpy(gp[a], &acc, sizeof acc);
              }
            }
          }
        }
      };
      // Rows whose chord reaches less than 4 S from the particle fit the one window ax - 3 .. ax + 4
      // (the particle lies in column ax .. ax + 1): with rest in [0, S), a column d = x - ax with
      // |d S - rest| < 4 S has -3 <= d <= 4. A corner that influences() accepts has exact dx^2 <
      // Rc_i^2 - dy^2 - dz^2, below outFrom - dyz by about tol (the float dyz = dy^2 + dz^2 errs by
      // ~2e-6 L^2, tol = 3e-5 L^2), so rows with dyz >= outFrom - (4 S)^2 have their chord within
      // 4 S. Those rows are the disc's outer ones (dyz grows with |dy|): for Rc_i / S in (3, 5]
      // about 2/3 of them, which windows from ax - r would cover with two. The lanes of a window are
      // still settled by the predicate, so the narrower one only leaves out lanes that add +0.
      // Different rows, the same particle: every corner's terms keep their order.
      if (vectors == 2 && ax >= 3 && ax + 4 < stride) {
        const float oneFrom = outFrom - oneSpan2_;
        if (dz2f >= oneFrom) {  // every row's dy^2 + dz^2 >= oneFrom (Rc_i < 4 S: all of them)
          rows(ax - 3, 1, y0, y1);
          continue;
        }
        int ya = y0;  // first row that needs both windows
        while (ya <= y1) {
          const float dyf = offY[ya] - rest1;
          if (dyf * dyf + dz2f < oneFrom) break;
          ++ya;
        }
        int yb = y1;  // last one
        while (yb >= ya) {
          const float dyf = offY[yb] - rest1;
          if (dyf * dyf + dz2f < oneFrom) break;
          --yb;
        }
        rows(ax - 3, 1, y0, ya - 1);
        rows(xs, 2, ya, yb);
        rows(ax - 3, 1, yb + 1, y1);
      } else {
        rows(xs, vectors, y0, y1);
      }
    }
    if (rect && wy0 <= wy1) *rect = {std::int16_t(wy0), std::int16_t(wy1), std::int16_t(wx0), std::int16_t(wx1)};
    std::uint64_t terms = 0;
    for (int i = 0; i < 8; ++i) terms += std::uint32_t(counted[i]);
    return terms;
  }

  // Seeding's field at corner (x, y, z) from the ring of value slices (the full sum: (f > T) as
  // sumUntilAbove decides it).
  float seedFieldAt(int x, int y, int z) {
    const std::size_t at = std::size_t(y) * std::size_t(w_.planeStride) + std::size_t(w_.planePad + x);
    if (w_.volumeMode) return w_.volume[std::size_t(z) * 4 * w_.planeFloats + at];
    const std::size_t slots = w_.ringZ.size();
    const std::size_t slot = std::size_t(z) % slots;
    float* plane = w_.seedRing.data() + slot * w_.planeFloats;
    if (w_.ringZ[slot] != z) {
      looked_ += splatSlice<false>(plane, z);
      w_.ringZ[slot] = z;
    }
    return plane[at];
  }

  // A corner of slice `slice` from its planes.
  void cornerFromPlanes(const Slice<Policy>& slice, int x, int y, Corner<Policy>& c) const {
    cornerFromPlanes(slice.planes, x, y, c);
  }
  // Corner (x, y) of a slice's four planes (value, df/dx, df/dy, df/dz; planeFloats each).
  void cornerFromPlanes(const float* f, int x, int y, Corner<Policy>& c) const {
    const std::size_t at = std::size_t(y) * std::size_t(w_.planeStride) + std::size_t(w_.planePad + x);
    const std::size_t pf = w_.planeFloats;
    c.value = f[at];
    c.g[0] = f[at + pf];
    c.g[1] = f[at + 2 * pf];
    c.g[2] = f[at + 3 * pf];
    c.user = {};
  }
