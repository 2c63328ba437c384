// Internal: the 2D-projection 1D-lookup particle cache (paper §6): its build, the exact lookup and
// the corner field sums that walk it. Part of BlockMesher's class body, included by block_mesher.inl
// (twice, see there): no include guard and no includes on purpose.

  // §6: particles arrive sorted by (z, index); insert one element per column of the projection
  // slice within Rc_i. Skip boundary columns and clamp min_z/max_z to [1, Nz-1] so the field is
  // zero on the outer boundary of the expanded block (§3) and every surface is closed.
  // Two passes over the same disc rows (count, then fill in place) build the CSR arrays directly.
  //
  // The column range of one row of the disc, widened by 1e-6 cubes against rounding; the fill
  // pass applies the exact predicate (an element whose z range comes out empty is never returned).
  struct DiscRow {
    int x0, x1;
    double dy;
  };
  DiscRow discRow(const Particle& p, int y, double inv) const {
    const double dy = w_.cy[y] - p.y;
    const double hx = std::sqrt(std::max(0.0, p.rc2 - dy * dy));
    return {std::max(1, iceil((p.x - hx) * inv - double(g0_[0]) - 1e-6)),
            std::min(nx_ - 1, ifloor((p.x + hx) * inv - double(g0_[0]) + 1e-6)), dy};
  }
  void discRows(const Particle& p, double inv, int& y0, int& y1) const {
    const double rc = std::sqrt(p.rc2);
    y0 = std::max(1, iceil((p.y - rc) * inv - double(g0_[1]) - 1e-6));
    y1 = std::min(ny_ - 1, ifloor((p.y + rc) * inv - double(g0_[1]) + 1e-6));
  }

  // An anisotropic particle's disc: the rows and columns of its ellipsoid's shadow on the xy plane
  // within its bounding sphere's disc. The shadow is the ellipse [dx dy] Q [dx dy]^T < L, Q the
  // Schur complement of M's zz entry (u minimised over dz), L as in fillDiscStretched, each bound
  // widened by 1e-6 cubes as discRow's: a superset of the columns whose chords are not empty.
  struct Shadow {
    double qxx = 0, qxy = 0, qyy = 0;
    bool ok = false;  // false: a degenerate Q (not expected for M positive definite): the sphere's disc
  };
  static constexpr double kStretchLimit = 0.5 * (1.0 + 1.0 / 512.0);
  Shadow shadowOf(const Particle& p) const {
    const float* m = su_.stretch[p.index].m;
    const double mzz = m[5];
    Shadow sh;
    sh.qxx = double(m[0]) - double(m[2]) * double(m[2]) / mzz;
    sh.qxy = double(m[1]) - double(m[2]) * double(m[4]) / mzz;
    sh.qyy = double(m[3]) - double(m[4]) * double(m[4]) / mzz;
    sh.ok = mzz > 0.0 && sh.qxx > 0.0 && sh.qxx * sh.qyy - sh.qxy * sh.qxy > 0.0;
    return sh;
  }
  void stretchedRows(const Particle& p, const Shadow& sh, double inv, int& y0, int& y1) const {
    discRows(p, inv, y0, y1);
    if (!sh.ok) return;
    const double ey = std::sqrt(kStretchLimit * sh.qxx / (sh.qxx * sh.qyy - sh.qxy * sh.qxy));
    y0 = std::max(y0, iceil((p.y - ey) * inv - double(g0_[1]) - 1e-6));
    y1 = std::min(y1, ifloor((p.y + ey) * inv - double(g0_[1]) + 1e-6));
  }
  void stretchedRow(const Particle& p, const Shadow& sh, int y, double inv, int& x0, int& x1) const {
    const DiscRow r = discRow(p, y, inv);
    x0 = r.x0, x1 = r.x1;
    if (!sh.ok) return;
    const double dy = r.dy;
    const double b = sh.qxy * dy, disc = b * b - sh.qxx * (sh.qyy * dy * dy - kStretchLimit);
    if (disc < 0.0) {
      x0 = 1, x1 = 0;  // empty row
      return;
    }
    const double root = std::sqrt(disc);
    x0 = std::max(x0, iceil((p.x + (-b - root) / sh.qxx) * inv - double(g0_[0]) - 1e-6));
    x1 = std::min(x1, ifloor((p.x + (-b + root) / sh.qxx) * inv - double(g0_[0]) + 1e-6));
  }

  void buildParticleCache(std::span<const Particle> particles) {
    const std::size_t cols = w_.columns();
    const std::size_t stride = std::size_t(stride_);
    const double inv = 1.0 / su_.s;
    // Offsets float(d S): |corner - anchor| <= m + 1 for every influence (m = ceil(Rc_max / S)).
    offsetRange_ = su_.m + 2;
    w_.offsets.resize(std::size_t(2 * offsetRange_ + 1));
    for (int d = -offsetRange_; d <= offsetRange_; ++d)
      w_.offsets[std::size_t(d + offsetRange_)] = float(double(d) * su_.s);
    // Count pass as a difference array along x (two updates per disc row), then prefix sums.
    // The rows' column ranges are kept for the fill pass (rowSpans, in the same order).
    std::uint32_t* start = w_.colStart.data();
    std::fill(start, start + cols + 1, 0u);
    w_.rowSpans.clear();
    auto addRow = [&](int y, int x0, int x1) {
      w_.rowSpans.push_back({std::int16_t(x0), std::int16_t(x1)});
      if (x0 > x1) return;
      ++start[std::size_t(y) * stride + std::size_t(x0) + 1];
      --start[std::size_t(y) * stride + std::size_t(x1) + 2];  // x1 + 1 <= nx: same row
    };
    const double* cyRow = w_.cy.data();
    if constexpr (isAnisotropic<Policy>()) {
      for (const Particle& p : particles) {
        const Shadow sh = shadowOf(p);
        int y0, y1;
        stretchedRows(p, sh, inv, y0, y1);
        for (int y = y0; y <= y1; ++y) {
          int x0, x1;
          stretchedRow(p, sh, y, inv, x0, x1);
          addRow(y, x0, x1);
        }
      }
    } else {
      for (const Particle& p : particles) {
        int y0, y1;
        discRows(p, inv, y0, y1);
        int y = y0;
#if defined(__SSE2__)
        // Two rows at once: discRow()'s double expressions lane by lane, and its iceil / ifloor as
        // truncation plus the same one-step correction, so the spans come out identical.
        const __m128d vpx = _mm_set1_pd(p.x), vpy = _mm_set1_pd(p.y), vrc2 = _mm_set1_pd(p.rc2);
        const __m128d vinv = _mm_set1_pd(inv), vg0 = _mm_set1_pd(double(g0_[0])), eps = _mm_set1_pd(1e-6);
        for (; y + 1 <= y1; y += 2) {
          const __m128d dy = _mm_sub_pd(_mm_loadu_pd(cyRow + y), vpy);
          const __m128d hx = _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(vrc2, _mm_mul_pd(dy, dy)), _mm_setzero_pd()));
          const __m128d a = _mm_sub_pd(_mm_sub_pd(_mm_mul_pd(_mm_sub_pd(vpx, hx), vinv), vg0), eps);
          const __m128d b = _mm_add_pd(_mm_sub_pd(_mm_mul_pd(_mm_add_pd(vpx, hx), vinv), vg0), eps);
          const __m128i ta = _mm_cvttpd_epi32(a), tb = _mm_cvttpd_epi32(b);
          // Lane masks (all ones = -1) of a > trunc(a) and b < trunc(b), low 32 bits of each lane.
          const __m128i up =
              _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmpgt_pd(a, _mm_cvtepi32_pd(ta))), _MM_SHUFFLE(2, 0, 2, 0));
          const __m128i down =
              _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmplt_pd(b, _mm_cvtepi32_pd(tb))), _MM_SHUFFLE(2, 0, 2, 0));
          const __m128i c = _mm_sub_epi32(ta, up), f = _mm_add_epi32(tb, down);  // iceil(a), ifloor(b)
          addRow(y, std::max(1, _mm_cvtsi128_si32(c)), std::min(nx_ - 1, _mm_cvtsi128_si32(f)));
          addRow(y + 1, std::max(1, _mm_cvtsi128_si32(_mm_shuffle_epi32(c, 1))),
                 std::min(nx_ - 1, _mm_cvtsi128_si32(_mm_shuffle_epi32(f, 1))));
        }
#endif
        for (; y <= y1; ++y) {
          const DiscRow r = discRow(p, y, inv);
          addRow(y, r.x0, r.x1);
        }
      }
    }
    // Difference array -> per-column counts -> CSR starts, as two running sums in one pass (the
    // same integers as two prefix-sum passes, one loop instead of two).
    {
      std::uint32_t count = 0, at = 0;
      for (std::size_t c = 1; c <= cols; ++c) {
        count += start[c];
        at += count;
        start[c] = at;
      }
    }
    std::uint32_t* cursor = w_.cursor.data();
    std::copy(start, start + cols, cursor);
    // Running max_z per column while filling: reachMax of each element as it is written.
    std::fill(w_.runMax.begin(), w_.runMax.end(), std::int16_t(-32000));
    // Grown, never shrunk: a block with fewer elements than the last one uses a prefix (no
    // zero-fill of the part that a larger block's build then overwrites anyway).
    if (w_.entries.size() < start[cols]) w_.entries.resize(start[cols]);
    w_.local.resize(particles.size());
    if constexpr (isAnisotropic<Policy>()) {
      w_.localStretch.resize(particles.size());
      for (std::size_t li = 0; li < particles.size(); ++li) w_.localStretch[li] = su_.stretch[particles[li].index];
    }
    ColumnEntry* entries = w_.entries.data();
    const int zmax = nz_ - 1;
    const std::array<std::int16_t, 2>* span = w_.rowSpans.data();
    for (std::uint32_t li = 0; li < particles.size(); ++li) {
      const Particle& p = particles[li];
      CacheParticle& cp = w_.local[li];
      for (int a = 0; a < 3; ++a) {
        cp.rest[a] = p.rest[a];
        // Block particles lie within Rc of the interior, so their anchors are inside the
        // expanded block (margin m >= Rc / S): 0 <= a <= n.
        assert(p.anchor[a] - g0_[a] >= 0 && p.anchor[a] - g0_[a] <= su_.n[a]);
        cp.na[a] = std::int16_t(g0_[a] - p.anchor[a]);
      }
      cp.k = p.k;
      cp.s = p.strength;
      cp.s4 = 4.0f * p.strength;
      const double fz = p.z * inv - double(g0_[2]);
      // Away from the block's top and bottom (the usual case) the clamps below cannot act.
      const double reach = std::sqrt(p.rc2) * inv + 2.0;
      const bool clampFree = fz - reach >= 1.0 && fz + reach <= double(zmax);
      if constexpr (isAnisotropic<Policy>()) {
        fillDiscStretched(p, li, fz, clampFree, span, entries, cursor);
        continue;
      }
#if defined(FLUID_SURFACE_AVX2_FILL)
      if (su_.avx2) {
        if (clampFree)
          fillDiscAvx2<false>(p, li, fz, span, entries, cursor);
        else
          fillDiscAvx2<true>(p, li, fz, span, entries, cursor);
        continue;
      }
#endif
      if (clampFree)
        fillDisc<false>(p, li, fz, span, entries, cursor);
      else
        fillDisc<true>(p, li, fz, span, entries, cursor);
    }
    assert(span == w_.rowSpans.data() + w_.rowSpans.size());
    // reachMin: suffix minimum of min_z per column (see ColumnEntry; reachMax was set by the fill).
    for (std::size_t c = 0; c < cols; ++c) {
      const std::uint32_t b = start[c], en = start[c + 1];
      if (b == en) continue;
      // The low half of a key is 0x8000 - min_z (0 when empty), so the smallest min_z is the largest
      // low half; 768 = 0x8000 - 32000 stands for "none" (reachMin 32000) and is below every real one.
      std::uint32_t run = 0x8000u - 32000u;
      // Two elements per step (one loop test per pair; same values as one at a time).
      ColumnEntry* p = entries + en;
      ColumnEntry* const first = entries + b;
      if ((en - b) & 1u) {
        --p;
        run = std::max(run, p->zKey & 0xffffu);
        p->reachMinB = std::uint16_t(run);  // 0x8000 - reachMin
      }
      while (p != first) {
        p -= 2;
        run = std::max(run, p[1].zKey & 0xffffu);
        p[1].reachMinB = std::uint16_t(run);
        run = std::max(run, p[0].zKey & 0xffffu);
        p[0].reachMinB = std::uint16_t(run);
      }
    }
    std::copy(start, start + cols, cursor);
    colStart_ = w_.colStart.data();
    cursor_ = w_.cursor.data();
    entries_ = w_.entries.data();
    off0_ = w_.offsets.data() + offsetRange_;
    parts_ = w_.local.data();
    if constexpr (isAnisotropic<Policy>()) stretch_ = w_.localStretch.data();
  }

  // Element for column x of a row: z range [lo, hi] (empty: stored as key 0 with max_z -32000),
  // reachMax from the column's running max, reachMin set after the fill.
  // `key` is columnKey(lo, hi), or 0 when empty.
  static void storeEntry(ColumnEntry* entries, std::uint32_t* rowCursor, std::int16_t* rowRun, int x, std::uint32_t key,
                         int hi, std::uint32_t li) {
    const std::int16_t rm = std::max(rowRun[x], std::int16_t(hi));
    rowRun[x] = rm;
    ColumnEntry& en = entries[rowCursor[x]++];
    en.zKey = key;
    en.reachMax = rm;
    en.particle8 = 8 * li;
  }

  // One column, scalar: the closed form, bounds near a lattice slice settled by the exact
  // predicate (influences()), so the cache returns precisely the particles within Rc_i.
  // fz = the particle's z in local cubes; dy2 = its row's dy * dy (see fillDisc).
  template <bool kClamp>
  void fillColumn(const Particle& p, std::uint32_t li, double fz, ColumnEntry* entries, std::uint32_t* rowCursor,
                  std::int16_t* rowRun, int x, double dy2) const {
    const double inv = 1.0 / su_.s;
    const double* cz = w_.cz.data();
    const int zmax = nz_ - 1;
    const double pz = p.z, rc2 = p.rc2;
    auto inside = [&](double dxy, int z) {
      const double dz = cz[z] - pz;
      return dxy + dz * dz < rc2;
    };
    const double dx = w_.cx[x] - p.x;
    const double dxy = dx * dx + dy2;
    int lo = -32000, hi = -32000;  // an empty range, which no corner (z >= 0) falls in
    if (dxy < rc2) {
      const double h = std::sqrt(rc2 - dxy) * inv;
      const double zlo = fz - h, zhi = fz + h;
      // ceil / floor without clamping first: c - 1 < zlo <= c and f <= zhi < f + 1.
      const int c = static_cast<int>(zlo) + (zlo > double(static_cast<int>(zlo)));
      const int f = static_cast<int>(zhi) - (zhi < double(static_cast<int>(zhi)));
      int l = c, u = f;
      if constexpr (kClamp) {
        // Intersect with [1, zmax] (not clamp each bound: a range wholly below 1 or above zmax,
        // possible for a particle in the outermost margin cube, must stay empty).
        l = std::max(c, 1);
        u = std::min(f, zmax);
      }  // else fz -/+ (Rc / S + 2) lies in [1, zmax], so c >= 1 and f <= zmax
      // The closed form differs from the predicate only by rounding (~1e-12 cubes); when a
      // bound is within about 1e-6 of a lattice slice (c - zlo in [0, 1) near 0 or 1, resp.
      // zhi - f), settle it with the predicate itself. Elsewhere the closed form is exact,
      // so where exactly the 1e-6 cut falls does not matter.
      // One test for both bounds; settling a bound the closed form already got right
      // leaves it unchanged, so both are settled when either is close.
      if (std::max(std::abs(double(c) - zlo - 0.5), std::abs(zhi - double(f) - 0.5)) > 0.5 - 1e-6) [[unlikely]] {
        if (l > 1 && inside(dxy, l - 1)) {
          do --l;
          while (l > 1 && inside(dxy, l - 1));
        } else {
          while (l <= u && !inside(dxy, l)) ++l;
        }
        if (u < zmax && inside(dxy, u + 1)) {
          do ++u;
          while (u < zmax && inside(dxy, u + 1));
        } else {
          while (u >= l && !inside(dxy, u)) --u;
        }
      }
      if (l <= u) {
        lo = l;
        hi = u;
      }
    }
    storeEntry(entries, rowCursor, rowRun, x, lo > -32000 ? columnKey(lo, hi) : 0u, hi, li);
  }

  // An anisotropic particle's elements: the rows and spans of its shadow (as the count pass made
  // them, stretchedRows / stretchedRow), each column's z range the ellipsoid's chord.
  // Along a column, u(dz) = A dz^2 + 2 B dz + C (field.hpp's stretchedU in exact arithmetic), so
  // u < L holds on [(-B - r) / A, (-B + r) / A], r = sqrt(B^2 - A (C - L)). L = 1/2 (1 + 2^-9)
  // widens the chord past every corner whose float u comes out below 1/2 (a superset, like the
  // bounding sphere: the sums test u themselves), and the chord stays within the sphere's.
  void fillDiscStretched(const Particle& p, std::uint32_t li, double fz, bool clampFree,
                         const std::array<std::int16_t, 2>*& span, ColumnEntry* entries, std::uint32_t* cursor) {
    const double inv = 1.0 / su_.s;
    const int zmax = nz_ - 1;
    const float* m = w_.localStretch[li].m;
    const double mxx = m[0], mxy = m[1], mxz = m[2], myy = m[3], myz = m[4], mzz = m[5];
    const double reach = std::sqrt(p.rc2) * inv;
    const int sphereLo = iceil(fz - reach), sphereHi = ifloor(fz + reach);
    std::int16_t* runMax = w_.runMax.data();
    int y0, y1;
    stretchedRows(p, shadowOf(p), inv, y0, y1);  // the count pass's rows (its spans are in `span`)
    for (int y = y0; y <= y1; ++y, ++span) {
      const double dy = w_.cy[y] - p.y;
      const std::size_t rowBase = std::size_t(y) * std::size_t(stride_);
      std::uint32_t* rowCursor = cursor + rowBase;
      std::int16_t* rowRun = runMax + rowBase;
      for (int x = (*span)[0]; x <= (*span)[1]; ++x) {
        const double dx = w_.cx[x] - p.x;
        const double b = mxz * dx + myz * dy;
        const double c = mxx * dx * dx + 2.0 * mxy * dx * dy + myy * dy * dy - kStretchLimit;
        const double disc = b * b - mzz * c;
        int lo = -32000, hi = -32000;
        if (disc >= 0.0) {
          const double r = std::sqrt(disc);
          int l = std::max(iceil(fz + (-b - r) / mzz * inv), sphereLo);
          int u = std::min(ifloor(fz + (-b + r) / mzz * inv), sphereHi);
          if (!clampFree) {
            l = std::max(l, 1);
            u = std::min(u, zmax);
          }
          if (l <= u) lo = l, hi = u;
        }
        storeEntry(entries, rowCursor, rowRun, x, lo > -32000 ? columnKey(lo, hi) : 0u, hi, li);
      }
    }
  }

  // One particle's elements, row by row of its disc (rows and spans as in the count pass).
  // Without clamping (the particle is away from the block's top and bottom: fz -/+ (Rc / S + 2)
  // lies in [1, zmax]) two columns go through the closed form at once (SSE2, the same double
  // operations lane by lane); a pair with a rim column (outside the disc) or a bound that needs
  // the exact predicate takes the scalar path, column by column.
  template <bool kClamp>
  void fillDisc(const Particle& p, std::uint32_t li, double fz, const std::array<std::int16_t, 2>*& span,
                ColumnEntry* entries, std::uint32_t* cursor) {
    const double inv = 1.0 / su_.s;
    const double* cx = w_.cx.data();
    const int zmax = nz_ - 1;
    const double px = p.x, rc2 = p.rc2;
    (void)cx, (void)zmax, (void)px, (void)rc2;  // used by the SSE2 path only
    std::int16_t* runMax = w_.runMax.data();
    int y0, y1;
    discRows(p, inv, y0, y1);
    for (int y = y0; y <= y1; ++y, ++span) {
      const double dyr = w_.cy[y] - p.y;  // as discRow()
      const double dy2 = dyr * dyr;
      const std::size_t rowBase = std::size_t(y) * std::size_t(stride_);
      std::uint32_t* rowCursor = cursor + rowBase;
      std::int16_t* rowRun = runMax + rowBase;
      const int x0 = (*span)[0], x1 = (*span)[1];
      int x = x0;
#if defined(__SSE2__)
      {
        // Without clamping zlo >= 1, so truncation is floor: c = trunc(zlo) + 1 is ceil(zlo)
        // except when zlo is a whole number, where c - zlo = 1 sends the column to the scalar path
        // (settled). With clamping zlo may be below 1: then ceil(zlo) <= 1 and c <= 1 (trunc
        // rounds towards zero), both 1 after the clamp; zhi = fz + h >= 0 always.
        const __m128d vpx = _mm_set1_pd(px), vdy2 = _mm_set1_pd(dy2), vrc2 = _mm_set1_pd(rc2);
        const __m128d vinv = _mm_set1_pd(inv), vfz = _mm_set1_pd(fz), half = _mm_set1_pd(0.5);
        const __m128d cut = _mm_set1_pd(0.5 - 1e-6), absMask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffll));
        const __m128i one = _mm_set1_epi32(1);
        for (; x <= x1; x += 2) {
          // The row's last column, when alone, rides in both lanes; only lane 0 is stored.
          const bool pair = x < x1;
          const __m128d dx = _mm_sub_pd(pair ? _mm_loadu_pd(cx + x) : _mm_set1_pd(cx[x]), vpx);
          const __m128d dxy = _mm_add_pd(_mm_mul_pd(dx, dx), vdy2);
          const __m128d in = _mm_cmplt_pd(dxy, vrc2);
          const __m128d h = _mm_mul_pd(_mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(vrc2, dxy), _mm_setzero_pd())), vinv);
          const __m128d zlo = _mm_sub_pd(vfz, h), zhi = _mm_add_pd(vfz, h);
          const __m128i c = _mm_add_epi32(_mm_cvttpd_epi32(zlo), one), f = _mm_cvttpd_epi32(zhi);
          const __m128d a = _mm_and_pd(_mm_sub_pd(_mm_sub_pd(_mm_cvtepi32_pd(c), zlo), half), absMask);
          const __m128d b = _mm_and_pd(_mm_sub_pd(_mm_sub_pd(zhi, _mm_cvtepi32_pd(f)), half), absMask);
          const __m128d settle = _mm_cmpgt_pd(_mm_max_pd(a, b), cut);
          if (_mm_movemask_pd(_mm_andnot_pd(settle, in)) != 3) [[unlikely]] {
            fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x, dy2);
            if (pair) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x + 1, dy2);
            continue;
          }
          // Both columns are inside the disc with clear bounds; c <= f holds unless the range
          // holds no slice, where the element is stored empty like the scalar path does. Keys
          // (columnKey, 0 when empty) and max_z (-32000 when empty) for both lanes at once.
          __m128i cc = c, ff = f;
          if constexpr (kClamp) {  // intersect with [1, zmax], as the scalar path
            const __m128i vz = _mm_set1_epi32(zmax);
            const __m128i below1 = _mm_cmplt_epi32(cc, one), above = _mm_cmpgt_epi32(ff, vz);
            cc = _mm_or_si128(_mm_andnot_si128(below1, cc), _mm_and_si128(below1, one));
            ff = _mm_or_si128(_mm_andnot_si128(above, ff), _mm_and_si128(above, vz));
          }
          const __m128i empty = _mm_cmpgt_epi32(cc, ff);
          const __m128i key =
              _mm_andnot_si128(empty, _mm_or_si128(_mm_slli_epi32(ff, 16), _mm_sub_epi32(_mm_set1_epi32(0x8000), cc)));
          const __m128i hi = _mm_or_si128(_mm_andnot_si128(empty, ff), _mm_and_si128(empty, _mm_set1_epi32(-32000)));
          if (!pair) [[unlikely]] {
            const __m128i kh = _mm_unpacklo_epi32(key, hi);  // key0 hi0 key1 hi1
            storeEntry(entries, rowCursor, rowRun, x, std::uint32_t(_mm_cvtsi128_si32(kh)),
                       _mm_cvtsi128_si32(_mm_shuffle_epi32(kh, 1)), li);
            break;
          }
          // Columns x and x + 1 are neighbours, so their running max_z (int16) and cursors
          // (uint32) are adjacent: update both at once, then write each element's first 8 bytes
          // (key, reachMax; reachMinB is set by the suffix pass) in one store.
          std::int32_t run2;
          std::memcpy(&run2, rowRun + x, 4);
          const __m128i rm = _mm_max_epi16(_mm_cvtsi32_si128(run2), _mm_packs_epi32(hi, hi));  // reachMax x, x+1
          run2 = _mm_cvtsi128_si32(rm);
          std::memcpy(rowRun + x, &run2, 4);
          const __m128i cur = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(rowCursor + x));
          _mm_storel_epi64(reinterpret_cast<__m128i*>(rowCursor + x), _mm_sub_epi32(cur, _mm_set1_epi32(-1)));
          const __m128i kr = _mm_unpacklo_epi32(key, _mm_unpacklo_epi16(rm, _mm_setzero_si128()));  // k0 r0 k1 r1
          ColumnEntry* e0 = entries + std::uint32_t(_mm_cvtsi128_si32(cur));
          ColumnEntry* e1 = entries + std::uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(cur, 1)));
          static_assert(offsetof(ColumnEntry, reachMax) == 4 && offsetof(ColumnEntry, particle8) == 8);
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e0), kr);
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e1), _mm_unpackhi_epi64(kr, kr));
          e0->particle8 = 8 * li;
          e1->particle8 = 8 * li;
        }
        continue;
      }
#endif
      for (; x <= x1; ++x) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x, dy2);
    }
  }

#if defined(FLUID_SURFACE_AVX2_FILL)
  // fillDisc's twin for CPUs with AVX2 (Setup::avx2): four columns of a row at once, the same
  // double operations lane by lane as the SSE2 path and fillColumn (no FMA contraction: the
  // targets add no FMA), so every element gets the same bits; a group with a column that needs
  // the scalar path sends each of its columns there, as the SSE2 path does for a pair.
  // Reads cx[x .. x + 3] (Worker::cx is padded by 3); lanes past the row's last column are
  // computed but neither stored nor counted (their running max and cursor are rewritten unchanged:
  // they lie inside the column arrays since x1 + 3 <= nx + 2 and y <= ny - 1).
  template <bool kClamp>
  [[gnu::target("avx2")]] void fillDiscAvx2(const Particle& p, std::uint32_t li, double fz,
                                            const std::array<std::int16_t, 2>*& span, ColumnEntry* entries,
                                            std::uint32_t* cursor) {
    const double inv = 1.0 / su_.s;
    const double* cx = w_.cx.data();
    const int zmax = nz_ - 1;
    std::int16_t* runMax = w_.runMax.data();
    const __m256d vpx = _mm256_set1_pd(p.x), vrc2 = _mm256_set1_pd(p.rc2), vinv = _mm256_set1_pd(inv);
    const __m256d vfz = _mm256_set1_pd(fz), half = _mm256_set1_pd(0.5), cut = _mm256_set1_pd(0.5 - 1e-6);
    const __m256d absMask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffll));
    const __m128i one = _mm_set1_epi32(1), lanes = _mm_setr_epi32(0, 1, 2, 3);
    const __m128i none = _mm_set1_epi32(-32000);
    const std::uint32_t p8 = 8 * li;
    int y0, y1;
    discRows(p, inv, y0, y1);
    for (int y = y0; y <= y1; ++y, ++span) {
      const double dyr = w_.cy[y] - p.y;  // as discRow()
      const double dy2 = dyr * dyr;
      const std::size_t rowBase = std::size_t(y) * std::size_t(stride_);
      std::uint32_t* rowCursor = cursor + rowBase;
      std::int16_t* rowRun = runMax + rowBase;
      const int x1 = (*span)[1];
      const __m256d vdy2 = _mm256_set1_pd(dy2);
      for (int x = (*span)[0]; x <= x1; x += 4) {
        const int cnt = std::min(4, x1 - x + 1);
        const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(cx + x), vpx);
        const __m256d dxy = _mm256_add_pd(_mm256_mul_pd(dx, dx), vdy2);
        const __m256d in = _mm256_cmp_pd(dxy, vrc2, _CMP_LT_OS);
        const __m256d h =
            _mm256_mul_pd(_mm256_sqrt_pd(_mm256_max_pd(_mm256_sub_pd(vrc2, dxy), _mm256_setzero_pd())), vinv);
        const __m256d zlo = _mm256_sub_pd(vfz, h), zhi = _mm256_add_pd(vfz, h);
        const __m128i c = _mm_add_epi32(_mm256_cvttpd_epi32(zlo), one), f = _mm256_cvttpd_epi32(zhi);
        const __m256d a = _mm256_and_pd(_mm256_sub_pd(_mm256_sub_pd(_mm256_cvtepi32_pd(c), zlo), half), absMask);
        const __m256d b = _mm256_and_pd(_mm256_sub_pd(_mm256_sub_pd(zhi, _mm256_cvtepi32_pd(f)), half), absMask);
        const __m256d settle = _mm256_cmp_pd(_mm256_max_pd(a, b), cut, _CMP_GT_OS);
        const int want = (1 << cnt) - 1;
        if ((_mm256_movemask_pd(_mm256_andnot_pd(settle, in)) & want) != want) [[unlikely]] {
          for (int l = 0; l < cnt; ++l) fillColumn<kClamp>(p, li, fz, entries, rowCursor, rowRun, x + l, dy2);
          continue;
        }
        __m128i cc = c, ff = f;
        if constexpr (kClamp) {  // intersect with [1, zmax], as the scalar path
          const __m128i vz = _mm_set1_epi32(zmax);
          cc = _mm_max_epi32(cc, one);
          ff = _mm_min_epi32(ff, vz);
        }
        const __m128i empty = _mm_cmpgt_epi32(cc, ff);
        const __m128i key =
            _mm_andnot_si128(empty, _mm_or_si128(_mm_slli_epi32(ff, 16), _mm_sub_epi32(_mm_set1_epi32(0x8000), cc)));
        // max_z, or -32000 for an empty range and for the lanes past the row's end (a no-op in
        // the running max below).
        const __m128i active = _mm_cmpgt_epi32(_mm_set1_epi32(cnt), lanes);
        const __m128i hi = _mm_blendv_epi8(none, ff, _mm_andnot_si128(empty, active));
        const __m128i rm = _mm_max_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(rowRun + x)),
                                         _mm_packs_epi32(hi, hi));  // reachMax of columns x .. x + 3
        _mm_storel_epi64(reinterpret_cast<__m128i*>(rowRun + x), rm);
        const __m128i cur = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rowCursor + x));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(rowCursor + x), _mm_sub_epi32(cur, active));
        const __m128i r32 = _mm_unpacklo_epi16(rm, _mm_setzero_si128());
        const __m128i kr01 = _mm_unpacklo_epi32(key, r32),
                      kr23 = _mm_unpackhi_epi32(key, r32);  // k0 r0 k1 r1, k2 r2 k3 r3
        ColumnEntry* e = entries + std::uint32_t(_mm_cvtsi128_si32(cur));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(e), kr01);
        e->particle8 = p8;
        if (cnt > 1) {
          e = entries + std::uint32_t(_mm_extract_epi32(cur, 1));
          _mm_storel_epi64(reinterpret_cast<__m128i*>(e), _mm_unpackhi_epi64(kr01, kr01));
          e->particle8 = p8;
          if (cnt > 2) {
            e = entries + std::uint32_t(_mm_extract_epi32(cur, 2));
            _mm_storel_epi64(reinterpret_cast<__m128i*>(e), kr23);
            e->particle8 = p8;
            if (cnt > 3) {
              e = entries + std::uint32_t(_mm_extract_epi32(cur, 3));
              _mm_storel_epi64(reinterpret_cast<__m128i*>(e), _mm_unpackhi_epi64(kr23, kr23));
              e->particle8 = p8;
            }
          }
        }
      }
    }
  }
#endif

  // The start-pointer update of §6 for column k (entries [begin, end)): moves the column's
  // cursor to the first element whose reach covers z and returns it. reachMax is non-decreasing,
  // so the pointer may skip 8 elements at once when the one 8 away is still on the same side
  // (long moves happen when the sweep jumps between surfaces).
  std::uint32_t seekColumn(std::size_t k, std::uint32_t begin, std::uint32_t end, int z) {
    std::uint32_t cur = cursor_[k];
    const ColumnEntry* e = entries_;
    while (cur > begin && e[cur - 1].reachMax >= z) {
      if (cur >= begin + 9 && e[cur - 9].reachMax >= z)
        cur -= 9;
      else
        --cur;
    }
    while (cur < end && e[cur].reachMax < z) {
      if (cur + 8 < end && e[cur + 8].reachMax < z)
        cur += 9;
      else
        ++cur;
    }
    cursor_[k] = cur;
    return cur;
  }

  // §6 lookup: from the column's start pointer find the bottom-most entry that can reach z
  // (reachMax >= z; the paper's mid_z >= z - window, tightened), walk up while entries can still
  // reach it (reachMin <= z; the paper's mid_z <= z + window), keep min_z <= z <= max_z, and leave
  // the start pointer at the first entry found. f(particle, dx, dy, dz) is called in (z, index)
  // order with the offsets from the particle to the corner (field.hpp's latticeOffset(), bit for
  // bit); the walk stops early when f returns true.
  // With kTable the offsets along z come from the slice's table (dzt, see fillSliceDz), else from
  // the offsets table; f(particle, dx, dy, dz, dz * dz).
  template <bool kTable, class F>
  void forEachInfluencing(int x, int y, int z, const SliceDz* dzt, F&& f) {
    const std::size_t k = col(x, y);
    const std::uint32_t begin = colStart_[k], end = colStart_[k + 1];
    if (begin == end) return;
    const std::uint32_t cur = seekColumn(k, begin, end, z);
    const ColumnEntry* e = entries_;
    const float* off = off0_;
    const float* offX = off + x;
    const float* offY = off + y;
    const float* offZ = off + z;
    const CacheParticle* parts = parts_;
    const std::uint32_t ck = cornerKey(z);
    const unsigned zb = 0x8000u - unsigned(z);
    for (std::uint32_t i = cur; i < end; ++i) {
      const ColumnEntry& en = e[i];
      if (en.reachMinB < zb) break;              // reachMin > z
      if (!coversCorner(en.zKey, ck)) continue;  // min_z <= z <= max_z
      const CacheParticle& p = atParticle8(parts, en.particle8);
      float dz, dz2;
      if constexpr (kTable) {
        const SliceDz& d = atParticle8(dzt, en.particle8);
        dz = d.dz;
        dz2 = d.dz2;
      } else {
        dz = offZ[p.na[2]] - p.rest[2];
        dz2 = dz * dz;
      }
      if (f(p, offX[p.na[0]] - p.rest[0], offY[p.na[1]] - p.rest[1], dz, dz2)) break;
    }
  }

  template <bool kGradient>
  void evaluate(int x, int y, int z, const SliceDz* dzt, Corner<Policy>& c) {
    float v = 0, gx = 0, gy = 0, gz = 0;
    std::uint64_t looked = 0;
    c.user = {};
    if constexpr (!kGradient) {
      // Margin corner: only the sign of f - T is ever read (§3), so stop as soon as the sum
      // passes T (see insideAt). No vertex lies on a margin corner's edges (only interior cubes
      // emit), so a policy's corner data stays empty there.
      v = sumUntilAbove<true>(x, y, z, dzt, looked);
    } else {
      forEachInfluencing<true>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float dz, float dz2) {
        ++looked;
        const float before = v;
        if constexpr (isAnisotropic<Policy>())
          accumulateStretched(stretchOf(p), dx, dy, dz, p.s, v, gx, gy, gz);
        else
          accumulateDz2S4(dx, dy, dx * dx + dy * dy, dz, dz2, p.k, p.s, p.s4, v, gx, gy, gz);
        if constexpr (Policy::kHasUser) pol_.add(c.user, indexOf(p), v - before);
        return false;
      });
    }
    looked_ += looked;
    c.value = v;
    c.g[0] = gx;
    c.g[1] = gy;
    c.g[2] = gz;
  }

  // The field summed in (z, index) order, stopped as soon as the partial sum exceeds T. Every
  // term is >= 0 and rounded float addition is monotone, so a partial sum above T proves the full
  // sum above T, and a sum that never passes T is the full sum: (result > T) == (f > T) exactly.
  template <bool kTable>
  float sumUntilAbove(int x, int y, int z, const SliceDz* dzt, std::uint64_t& looked) {
    const float t = su_.threshold;
    float v = 0;
    forEachInfluencing<kTable>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float dz, float dz2) {
      ++looked;
      if constexpr (isAnisotropic<Policy>())
        v += stretchedContribution(stretchOf(p), dx, dy, dz, p.s);
      else
        v += contributionDz2(dx * dx + dy * dy, dz2, p.k, p.s);
      return v > t;
    });
    return v;
  }

  // A lookup at slice z walks only particles whose anchor lies within m + 1 slices of z (every
  // element it passes has mid_z within ceil(Rc/S) = m of z, see forEachInfluencing, and the
  // anchor is floor(mid_z) up to rounding), a contiguous run of the z-sorted block particles; the
  // run for m + 2 (the offsets table's reach) is tabulated, one slice of slack.
  void fillSliceDz(Slice<Policy>& slice, int z) {
    const std::size_t n = w_.local.size();
    slice.dz.resize(n);
    const CacheParticle* parts = w_.local.data();
    // -na[2] = anchor - corner 0 along z, non-decreasing in the local index.
    const int lo = z - offsetRange_, hi = z + offsetRange_;  // offsetRange_ = m + 2
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < lo; });
    const CacheParticle* last =
        std::partition_point(first, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) <= hi; });
    const float* offZ = w_.offsets.data() + offsetRange_ + z;
    SliceDz* out = slice.dz.data();
    for (const CacheParticle* p = first; p != last; ++p) {
      const float dz = offZ[p->na[2]] - p->rest[2];
      out[p - parts] = {dz, dz * dz};
    }
  }

  // Two interior corners of one column, (x, y, z) and (x, y, z + 1), from one §6 walk: the walk
  // for z + 1 starts at or after the one for z (reachMax is non-decreasing) and stops at or after
  // it (reachMin is too), so walking from z's start to z + 1's stop passes every element of both
  // in the same (z, index) order. Each corner adds exactly the terms, in exactly the order and
  // with exactly the float expressions, of evaluate<true>: the same bits as two separate calls,
  // while the walk, the particle record and the x, y offsets are shared (about a third of the
  // evaluated corners come in such pairs: horizontal stretches of surface). Returns the lower
  // corner's index + 1 (the upper one is cached in its slice).
  // Scalar sums: GCC's SLP vectoriser would pack each corner's four sums into one register and
  // repack them on every term (about 10 more instructions per term for the second corner).
  // A policy's corner data is summed per corner as evaluate<true> sums it: same terms, same order.
  [[gnu::noinline, gnu::optimize("no-tree-slp-vectorize")]] std::uint32_t evaluatePairInto(
      Slice<Policy>& lo, SliceCell& cellLo, Slice<Policy>& hi, SliceCell& cellHi, int x, int y, int z) {
    float v0 = 0, gx0 = 0, gy0 = 0, gz0 = 0, v1 = 0, gx1 = 0, gy1 = 0, gz1 = 0;
    typename Policy::CornerData user0{}, user1{};
    std::uint64_t looked = 0;
    const std::size_t k = col(x, y);
    const std::uint32_t begin = su_.splat ? 0 : colStart_[k], end = su_.splat ? 0 : colStart_[k + 1];
    if (su_.splat) {  // slice-splat route: both corners from their slices' planes (same order of stores)
      Corner<Policy> a, b;
      cornerFromPlanes(lo, x, y, a);
      cornerFromPlanes(hi, x, y, b);
      v0 = a.value, gx0 = a.g[0], gy0 = a.g[1], gz0 = a.g[2];
      v1 = b.value, gx1 = b.g[0], gy1 = b.g[1], gz1 = b.g[2];
    } else if (begin != end) {
      const std::uint32_t cur = seekColumn(k, begin, end, z);  // start of z's walk
      const ColumnEntry* e = entries_;
      const float* off = off0_;
      const float* offX = off + x;
      const float* offY = off + y;
      const CacheParticle* parts = parts_;
      const SliceDz* dzLo = lo.dz.data();
      const SliceDz* dzHi = hi.dz.data();
      const int z1 = z + 1;
      const std::uint32_t ck0 = cornerKey(z), ck1 = cornerKey(z1);
      const unsigned zb1 = 0x8000u - unsigned(z1);
      for (std::uint32_t i = cur; i < end; ++i) {
        const ColumnEntry& en = e[i];
        if (en.reachMinB < zb1) break;  // reachMin > z + 1
        const bool in0 = coversCorner(en.zKey, ck0), in1 = coversCorner(en.zKey, ck1);
        if (!(in0 | in1)) continue;
        const std::uint32_t pi = en.particle8;
        const CacheParticle& p = atParticle8(parts, pi);
        const float dx = offX[p.na[0]] - p.rest[0], dy = offY[p.na[1]] - p.rest[1];
        const float dxy2 = dx * dx + dy * dy;
        if (in0) {
          ++looked;
          const SliceDz& d = atParticle8(dzLo, pi);
          const float before = v0;
          if constexpr (isAnisotropic<Policy>())
            accumulateStretched(atParticle8(stretch_, pi), dx, dy, d.dz, p.s, v0, gx0, gy0, gz0);
          else
            accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v0, gx0, gy0, gz0);
          if constexpr (Policy::kHasUser) pol_.add(user0, indexOf(p), v0 - before);
        }
        if (in1) {
          ++looked;
          const SliceDz& d = atParticle8(dzHi, pi);
          const float before = v1;
          if constexpr (isAnisotropic<Policy>())
            accumulateStretched(atParticle8(stretch_, pi), dx, dy, d.dz, p.s, v1, gx1, gy1, gz1);
          else
            accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v1, gx1, gy1, gz1);
          if constexpr (Policy::kHasUser) pol_.add(user1, indexOf(p), v1 - before);
        }
      }
    }
    looked_ += looked;
    Corner<Policy> c;
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.cell = std::uint32_t(col(x, y));
    auto store = [&c](Slice<Policy>& slice, SliceCell& cell, float v, float gx, float gy, float gz,
                      const typename Policy::CornerData& user) {
      c.user = user;
      c.value = v;
      c.g[0] = gx;
      c.g[1] = gy;
      c.g[2] = gz;
      slice.corners.push_back(c);
      cell.corner = std::uint32_t(slice.corners.size());
    };
    store(hi, cellHi, v1, gx1, gy1, gz1, user1);
    store(lo, cellLo, v0, gx0, gy0, gz0, user0);
    return cellLo.corner;
  }
