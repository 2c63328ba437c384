// Internal: the per-block marching-slices algorithm (paper Alg. 1, §3-§6), the body of
// marching_slices_impl.hpp's BlockMesher. No include guard and no includes on purpose: that
// header includes it twice, once as is and once compiled for AVX2 (namespace avx2, see there).
// ---------------------------------------------------------------------------------------------
// The per-block algorithm.
template <class Policy>
class BlockMesher {
 public:
  // `append`: add to `out`'s arrays after what earlier blocks put there (vertex ids and index
  // positions continue from theirs; not with exact slab order), instead of replacing them.
  BlockMesher(Worker<Policy>& w, const Setup& setup, const Policy& policy, BlockOut& out, bool append = false)
      : w_(w),
        su_(setup),
        pol_(policy),
        out_(out),
        nx_(setup.n[0]),
        ny_(setup.n[1]),
        nz_(setup.n[2]),
        stride_(setup.n[0] + 1),
        append_(append) {
    assert(!(append && setup.exact));
  }

  // `seams`: the squares neighbours asked this block to seed (in), the seam squares it marches (out).
  void run(const BlockDesc& block, std::span<const Particle> particles, BlockSeams& seams) {
    particles_ = particles;
    seams_ = &seams;
    seams.visits.clear();
    if (append_) {
      out_.stats = {};
      out_.cornerBytes = out_.particleBytes = 0;
    } else {
      out_.reset();
    }
    vertexBase_ = std::uint32_t(out_.positions.size());
    indexBase_ = out_.indices.size();
    runBase_ = out_.runs.size();
    vertexCount_ = vertexBase_;
    nIndices_ = indexBase_;
    const PhaseClock::time_point start = PhaseClock::now();
    begin(block);
    buildParticleCache(particles);
    const PhaseClock::time_point cached = PhaseClock::now();
    seed(particles);
    seedFromNeighbours();
    const PhaseClock::time_point seeded = PhaseClock::now();
    march();
    out_.stats.particlesLookedUp += looked_;
    looked_ = 0;
    if (su_.exact) {  // otherwise polygonize() built the runs as it went
      sortBySlab();
      buildRuns(out_);
    }
    const PhaseClock::time_point marched = PhaseClock::now();
    out_.stats.cacheBuildMs = phaseMs(start, cached);
    out_.stats.seedMs = phaseMs(cached, seeded);
    out_.stats.marchMs = phaseMs(seeded, marched);
    out_.indexCount = std::uint32_t(out_.indices.size() - indexBase_);
    out_.vertexCount = std::uint32_t(out_.positions.size() - vertexBase_);
    out_.runCount = std::uint32_t(out_.runs.size() - runBase_);
    out_.stats.triangles = out_.indexCount / 3;
    out_.stats.vertices = out_.vertexCount;
    out_.particleBytes = std::uint64_t(w_.columns()) * (2 * sizeof(std::uint32_t) + sizeof(std::int16_t)) +
                         std::uint64_t(w_.colStart[w_.columns()]) * sizeof(ColumnEntry) +  // elements in use
                         std::uint64_t(w_.local.size()) * sizeof(CacheParticle) +
                         std::uint64_t(w_.rowSpans.size()) * sizeof(w_.rowSpans[0]);
    out_.cornerBytes = peakCornerBytes_;
    w_.peakBytes = std::max(w_.peakBytes, out_.particleBytes + out_.cornerBytes);
  }

  // Test hook (detail/testing.hpp): build the particle cache only, then look up corners.
  void prepareCache(const BlockDesc& block, std::span<const Particle> particles) {
    particles_ = particles;
    begin(block);
    buildParticleCache(particles);
  }
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found) {
    found.clear();
    forEachInfluencing<false>(x, y, z, nullptr, [&](const CacheParticle& p, float, float, float, float) {
      found.push_back(indexOf(p));
      return false;
    });
  }

 private:
  Worker<Policy>& w_;
  const Setup& su_;
  const Policy& pol_;
  BlockOut& out_;
  const int nx_, ny_, nz_, stride_;
  std::int64_t g0_[3] = {0, 0, 0};
  // The block's position in the block grid.
  int bc_[3] = {0, 0, 0};
  int offsetRange_ = 0;  // offsets table half-width: m + 2 >= |corner - anchor| of any influence
  int activeSlices_ = 0;
  // Particle contributions summed (SurfaceStats::particlesLookedUp), kept here rather than in
  // out_.stats, which the compiler must reload through out_ after every call that may write it.
  std::uint64_t looked_ = 0;
  int activeLo_ = std::numeric_limits<int>::max(), activeHi_ = -1;  // lowest, highest active slice z
  std::uint64_t peakCornerBytes_ = 0;
  std::span<const Particle> particles_;  // the block's particles; CacheParticle i is particles_[i]
  BlockSeams* seams_ = nullptr;          // seam propagation (runBlocks): seeds in, visits out
  const bool append_;
  std::uint32_t vertexBase_ = 0;             // out_'s vertices before this block (0 unless append_)
  std::size_t indexBase_ = 0, runBase_ = 0;  // likewise its indices and slab runs
  std::uint32_t vertexCount_ = 0;            // vertex id of the next vertex (out_.positions.size())
  std::size_t nIndices_ = 0;                 // used length of out_.indices while marching (polygonize)
  // The particle cache's arrays, set once it is built (they do not move while the block runs).
  const std::uint32_t* colStart_ = nullptr;
  std::uint32_t* cursor_ = nullptr;
  const ColumnEntry* entries_ = nullptr;
  const float* off0_ = nullptr;  // offsets table at d = 0
  const CacheParticle* parts_ = nullptr;
  std::uint32_t indexOf(const CacheParticle& p) const { return particles_[std::size_t(&p - w_.local.data())].index; }
  int lowestTodo_ = std::numeric_limits<int>::max();

  std::size_t col(int x, int y) const { return std::size_t(y) * std::size_t(stride_) + std::size_t(x); }

  void begin(const BlockDesc& block) {
    blockOrigin(su_, block, g0_);
    bc_[0] = block.bx;
    bc_[1] = block.by;
    bc_[2] = block.bz;
    // Face bits (mc::CaseTable::faceMask) of the seam planes per local cube index: the interior's
    // first and last cubes along an axis, unless that face is the grid's outer one (field 0 there).
    std::uint8_t* seam[3] = {w_.seamX.data(), w_.seamY.data(), w_.seamZ.data()};
    for (int a = 0; a < 3; ++a) {
      std::fill(seam[a], seam[a] + su_.n[a] + 1, std::uint8_t(0));
      if (bc_[a] > 0) seam[a][su_.m] |= std::uint8_t(1u << (2 * a));
      if (bc_[a] + 1 < su_.nb[a]) seam[a][su_.m + su_.b[a] - 1] |= std::uint8_t(2u << (2 * a));
    }
    for (int i = 0; i <= nx_ + 3; ++i) w_.cx[i] = double(g0_[0] + i) * su_.s;  // + 3: padding (resize)
    for (int i = 0; i <= ny_; ++i) w_.cy[i] = double(g0_[1] + i) * su_.s;
    for (int i = 0; i <= nz_; ++i) w_.cz[i] = double(g0_[2] + i) * su_.s;
    // edgeKey(i, j, k, axis) = kx[i] | ky[j] | kz[k] | axis for the block's lattice indices.
    for (int i = 0; i <= nx_; ++i) w_.kx[i] = edgeKey(g0_[0] + i, 0, 0, 0);
    for (int i = 0; i <= ny_; ++i) w_.ky[i] = edgeKey(0, g0_[1] + i, 0, 0);
    for (int i = 0; i <= nz_; ++i) w_.kz[i] = edgeKey(0, 0, g0_[2] + i, 0);
  }

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
    if constexpr (!kGradient && !Policy::kHasUser) {
      // Margin corner: only the sign of f - T is ever read (§3), so stop as soon as the sum
      // passes T (see insideAt).
      v = sumUntilAbove<true>(x, y, z, dzt, looked);
    } else {
      forEachInfluencing<true>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float dz, float dz2) {
        ++looked;
        const float before = v;
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
    forEachInfluencing<kTable>(x, y, z, dzt, [&](const CacheParticle& p, float dx, float dy, float, float dz2) {
      ++looked;
      v += contributionDz2(dx * dx + dy * dy, dz2, p.k, p.s);
      return v > t;
    });
    return v;
  }

  // Seeding only asks whether a corner is inside (§4).
  bool insideAt(int x, int y, int z) {
    std::uint64_t looked = 0;
    ++out_.stats.seedEvaluations;
    return sumUntilAbove<false>(x, y, z, nullptr, looked) > su_.threshold;
  }

  bool interiorCorner(int x, int y, int z) const {
    // m <= v <= m + b per axis, as one unsigned compare each.
    const int m = su_.m;
    return (unsigned(x - m) <= unsigned(su_.b[0])) & (unsigned(y - m) <= unsigned(su_.b[1])) &
           (unsigned(z - m) <= unsigned(su_.b[2]));
  }

  // Seeding (§4): snap each particle to its nearest corner and step down -z until the field is
  // at or below T; push the cube whose vertical edge holds the crossing into that slab's todo.
  // Stop after Rc_i. A per-column memo of the inside corners already walked lets a later
  // particle stop as soon as its descent reaches one (same connected inside run: same seed).
  //
  // Only the interior's corners have the complete field: a margin corner sums just the block's
  // particles, those that reach the interior (§3). A descent that starts in the margin and stops
  // after Rc_i + S, still inside, on §4's "a particle below seeds it" can leave the part of its
  // surface that lies in this block's interior unseeded, since that particle need not reach the
  // interior and so need not be among the block's particles (a hole at the seam: the interior is
  // emitted by this block alone). So a descent from a margin corner counts only its steps through
  // interior corners. Everything it walks is inside in the block's field, hence in the full field
  // (a sum over a subset of the same non-negative terms), so the crossing it finds is on the
  // surface of a component holding a particle's nearest corner, one §4 seeds anyway; it never
  // starts a component that §4 leaves out (a descent from some other corner could, and would
  // then leave half of that component, a hole, where it crosses into a block that does not).
  void seed(std::span<const Particle> particles) {
    for (std::uint32_t c : w_.chainTouched) {
      w_.chainLo[c] = 0;
      w_.chainHi[c] = -1;
    }
    w_.chainTouched.clear();
    const double inv = 1.0 / su_.s;
    for (const Particle& p : particles) {
      const int x = iround(p.x * inv - double(g0_[0]));
      const int y = iround(p.y * inv - double(g0_[1]));
      const int z0 = iround(p.z * inv - double(g0_[2]));
      if (x < 1 || x > nx_ - 1 || y < 1 || y > ny_ - 1 || z0 < 1 || z0 > nz_ - 1) continue;
      seedWalk(p, x, y, z0);
    }
  }

  // One §4 descent from corner (x, y, z0) of the expanded block (1 <= x, y, z0 <= n - 1): pushes the
  // cube below the first outside corner, or stops after Rc_i + S (interior steps, see seed()).
  void seedWalk(const Particle& p, int x, int y, int z0) {
    const float t = su_.threshold;
    const std::size_t k = col(x, y);
    if (z0 >= w_.chainLo[k] && z0 <= w_.chainHi[k]) return;
    // The field is a sum of non-negative terms, so the particle's own term above T already
    // proves the start corner inside (no lookup needed); otherwise evaluate.
    const float ox = latticeOffset(g0_[0] + x, p.anchor[0], p.rest[0], su_.s);
    const float oy = latticeOffset(g0_[1] + y, p.anchor[1], p.rest[1], su_.s);
    const float oz = latticeOffset(g0_[2] + z0, p.anchor[2], p.rest[2], su_.s);
    const bool ownInside =
        influences(p, w_.cx[x], w_.cy[y], w_.cz[z0]) && contribution(ox * ox + oy * oy, oz, p.k, p.strength) > t;
    if (!ownInside && !insideAt(x, y, z0)) return;  // start corner outside: no seed here
    const int steps = iceil(std::sqrt(p.rc2) * (1.0 / su_.s)) + 1;
    const bool fromMargin = !interiorCorner(x, y, z0);
    int z = z0;
    bool joined = false;
    for (int i = 0; i < steps && z > 0;) {
      const int below = z - 1;
      if (below >= w_.chainLo[k] && below <= w_.chainHi[k]) {
        joined = true;
        break;
      }
      // As at the start: the particle's own term above T proves the corner inside.
      const float ozb = latticeOffset(g0_[2] + below, p.anchor[2], p.rest[2], su_.s);
      const bool ownBelow = below >= 1 && influences(p, w_.cx[x], w_.cy[y], w_.cz[below]) &&
                            contribution(ox * ox + oy * oy, ozb, p.k, p.strength) > t;
      if (!ownBelow && !insideAt(x, y, below)) {
        pushTodo(below, x, y);
        joined = true;
        break;
      }
      z = below;
      if (!fromMargin || interiorCorner(x, y, z)) ++i;  // margin steps do not count (see seed())
    }
    if (!joined) return;  // went Rc down without leaving: a particle below seeds it (§4)
    // Keep one walked run [z, z0] per column: merge when it touches the old one, else replace
    // (a gap between two runs is not known to be inside).
    if (w_.chainHi[k] < w_.chainLo[k]) w_.chainTouched.push_back(std::uint32_t(k));
    if (w_.chainHi[k] >= w_.chainLo[k] && z <= w_.chainHi[k] + 1 && z0 >= w_.chainLo[k] - 1) {
      w_.chainLo[k] = std::int16_t(std::min<int>(w_.chainLo[k], z));
      w_.chainHi[k] = std::int16_t(std::max<int>(w_.chainHi[k], z0));
    } else {
      w_.chainLo[k] = std::int16_t(z);
      w_.chainHi[k] = std::int16_t(z0);
    }
  }

  // Seam propagation (§3 with §4; runBlocks): a block has only the particles that reach its
  // interior, so its field in the margin is partial and its own §4 seeds can miss the piece of a
  // surface component that lies in its interior while a neighbour marches the rest (a hole at the
  // seam). Such a piece joins the rest through squares of a seam plane, whose corners are interior
  // to both blocks and evaluated alike, so the neighbour's march crosses them: runBlocks hands
  // every square crossed from one side only to the block on the other, which seeds the interior
  // cube behind it here and runs again. Seeds come only from surfaces some block reached from §4
  // seeds, so no block starts a component that §4 leaves out.
  void seedFromNeighbours() {
    for (const SeamSquare& sq : seams_->seeds) {
      int l[3];
      for (int a = 0; a < 3; ++a) l[a] = int(sq.g[a] - g0_[a]);
      if (l[sq.axis] != su_.m) --l[sq.axis];  // on the high plane m + b: the cube below it
      assert(l[sq.axis] == su_.m || l[sq.axis] == su_.m + su_.b[sq.axis] - 1);
      pushTodo(l[2], l[0], l[1]);
    }
  }

  // An emitted cube on the interior's boundary: records its crossed faces that lie on a seam plane
  // for the propagation above. `f`: those faces as mc::CaseTable::faceMask bits (2 axis + side;
  // the march masks the cube's faceMask with seamX/Y/Z).
  [[gnu::noinline, gnu::cold]] void noteSeamFaces(unsigned f, int x, int y, int z) {
    const int l[3] = {x, y, z};
    for (int a = 0; a < 3; ++a)
      for (int side = 0; side < 2; ++side) {
        if (!((f >> (2 * a + side)) & 1u)) continue;
        SeamSquare sq;
        for (int i = 0; i < 3; ++i) sq.g[i] = g0_[i] + l[i];
        sq.g[a] += side;
        sq.axis = a;
        seams_->visits.push_back(sq);
      }
  }

  void pushTodo(int slab, int x, int y) {
    w_.todo[slab].push_back(std::uint32_t(x) | (std::uint32_t(y) << 16));
    lowestTodo_ = std::min(lowestTodo_, slab);
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

  Slice<Policy>* ensureSlice(int z) {
    if (!w_.active[z]) {
      w_.active[z] = w_.acquireSlice();
      fillSliceDz(*w_.active[z], z);
      ++activeSlices_;
      activeLo_ = std::min(activeLo_, z);
      activeHi_ = std::max(activeHi_, z);
      out_.stats.maxActiveSlices = std::max<std::uint32_t>(out_.stats.maxActiveSlices, activeSlices_);
    }
    return w_.active[z];
  }
  void freeSlice(int z) {
    if (!w_.active[z]) return;
    // Every evaluated corner sits in exactly one slice's corner cache until the slice is
    // returned (all are by the end of march()): count them here rather than per evaluation.
    out_.stats.cornersEvaluated += w_.active[z]->corners.size();
    w_.releaseSlice(w_.active[z]);
    w_.active[z] = nullptr;
    --activeSlices_;
    if (activeSlices_ == 0) {
      activeLo_ = std::numeric_limits<int>::max();
      activeHi_ = -1;
      return;
    }
    while (!w_.active[activeLo_]) ++activeLo_;  // (some slice in [lo, hi] is still active)
    while (!w_.active[activeHi_]) --activeHi_;
  }
  void notePeak(int z) {
    // Active slices are z, z+1 and any abandoned below after a reversal; count all of them.
    std::uint64_t bytes = 0;
    for (int i = activeLo_; i <= activeHi_; ++i)  // (every active slice lies in that range)
      if (w_.active[i])
        bytes += w_.active[i]->cells.size() * sizeof(SliceCell) +
                 w_.active[i]->corners.size() * sizeof(Corner<Policy>) + w_.active[i]->dz.size() * sizeof(SliceDz);
    (void)z;
    peakCornerBytes_ = std::max(peakCornerBytes_, bytes);
  }

  // Alg. 1 lookupOrEval: the corner's index in the slice's corner cache, evaluated on first use.
  // `interior`: the caller knows the corner is interior (a corner of an emitted cube).
  std::uint32_t lookupOrEval(Slice<Policy>& slice, SliceCell& cell, int x, int y, int z, bool interior) {
    const std::uint32_t id = cell.corner;
    if (id) [[likely]]
      return id - 1;
    return evaluateInto(slice, cell, x, y, z, interior) - 1;
  }

  // lookupOrEval for a corner of the lower slice (z) whose twin one slice up (z + 1, same column)
  // the cube needs as well: when neither is cached yet, both come from one walk of the column.
  std::uint32_t lookupOrEvalLow(Slice<Policy>& lo, SliceCell& cellLo, Slice<Policy>& hi, SliceCell& cellHi, int x,
                                int y, int z, bool interior) {
    const std::uint32_t id = cellLo.corner;
    if (id) [[likely]]
      return id - 1;
    if constexpr (!Policy::kHasUser) {
      if (!cellHi.corner && (interior || (interiorCorner(x, y, z) && interiorCorner(x, y, z + 1))))
        return evaluatePairInto(lo, cellLo, hi, cellHi, x, y, z) - 1;
    }
    return evaluateInto(lo, cellLo, x, y, z, interior) - 1;
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
  [[gnu::noinline, gnu::optimize("no-tree-slp-vectorize")]] std::uint32_t evaluatePairInto(
      Slice<Policy>& lo, SliceCell& cellLo, Slice<Policy>& hi, SliceCell& cellHi, int x, int y, int z) {
    float v0 = 0, gx0 = 0, gy0 = 0, gz0 = 0, v1 = 0, gx1 = 0, gy1 = 0, gz1 = 0;
    std::uint64_t looked = 0;
    const std::size_t k = col(x, y);
    const std::uint32_t begin = colStart_[k], end = colStart_[k + 1];
    if (begin != end) {
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
          accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v0, gx0, gy0, gz0);
        }
        if (in1) {
          ++looked;
          const SliceDz& d = atParticle8(dzHi, pi);
          accumulateDz2S4(dx, dy, dxy2, d.dz, d.dz2, p.k, p.s, p.s4, v1, gx1, gy1, gz1);
        }
      }
    }
    looked_ += looked;
    Corner<Policy> c;
    c.user = {};
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.cell = std::uint32_t(col(x, y));
    auto store = [&c](Slice<Policy>& slice, SliceCell& cell, float v, float gx, float gy, float gz) {
      c.value = v;
      c.g[0] = gx;
      c.g[1] = gy;
      c.g[2] = gz;
      slice.corners.push_back(c);
      cell.corner = std::uint32_t(slice.corners.size());
    };
    store(hi, cellHi, v1, gx1, gy1, gz1);
    store(lo, cellLo, v0, gx0, gy0, gz0);
    return cellLo.corner;
  }

  // Evaluates corner (x, y, z) into the slice's corner cache; returns its index + 1. Not inlined:
  // one out-of-line copy keeps the march loop small (most corners are already cached).
  [[gnu::noinline]] std::uint32_t evaluateInto(Slice<Policy>& slice, SliceCell& cell, int x, int y, int z,
                                               bool interior) {
    Corner<Policy> c;
    if (interior || interiorCorner(x, y, z))
      evaluate<true>(x, y, z, slice.dz.data(), c);
    else
      evaluate<false>(x, y, z, slice.dz.data(), c);  // margin: only the sign is needed (§3)
    c.vert[0] = c.vert[1] = c.vert[2] = 0;
    c.cell = std::uint32_t(col(x, y));
    slice.corners.push_back(c);
    cell.corner = std::uint32_t(slice.corners.size());
    return cell.corner;
  }

  // Alg. 1 main loop.
  void march() {
    const float t = su_.threshold;
    const auto& table = mc::tables().cases[su_.octant];
    const int ia = su_.m, ibx = su_.m + su_.b[0], iby = su_.m + su_.b[1], ibz = su_.m + su_.b[2];
    int z = lowestTodo_;
    std::uint64_t cubes = 0;  // cubes visited (a local: out_ is written through by the calls below)
    while (true) {
      while (z < nz_ && w_.todo[z].empty()) ++z;  // lowest slab with work
      if (z >= nz_) break;
      Slice<Policy>* below = ensureSlice(z);
      Slice<Policy>* above = ensureSlice(z + 1);
      auto& list = w_.todo[z];
      const bool interiorSlab = z >= ia && z < ibz;
      // The index arrays never move while the slices are active; the corner arrays may grow
      // (evaluateInto), so corner pointers are taken after the cube's evaluations.
      SliceCell* const cellsB = below->cells.data();
      SliceCell* const cellsA = above->cells.data();
      const std::size_t sy = std::size_t(stride_);
      const std::size_t slabFirst = nIndices_;
      while (!list.empty()) {
        const std::uint32_t item = list.back();
        list.pop_back();
        const int x = int(item & 0xffff), y = int(item >> 16);
        const std::size_t c0 = col(x, y);
        SliceCell& cb = cellsB[c0];
        SliceCell& ca = cellsA[c0];
        if (cb.doneAbove || ca.doneBelow) continue;
        cb.doneAbove = 1;
        ca.doneBelow = 1;
        ++cubes;
        // A cube of the block's interior (the ones polygonize() emits): all eight corners interior.
        const bool emit = interiorSlab && x >= ia && x < ibx && y >= ia && y < iby;
        std::uint32_t ci[8];
        ci[0] = lookupOrEvalLow(*below, cellsB[c0], *above, cellsA[c0], x, y, z, emit);
        ci[1] = lookupOrEvalLow(*below, cellsB[c0 + 1], *above, cellsA[c0 + 1], x + 1, y, z, emit);
        ci[2] = lookupOrEvalLow(*below, cellsB[c0 + sy], *above, cellsA[c0 + sy], x, y + 1, z, emit);
        ci[3] = lookupOrEvalLow(*below, cellsB[c0 + sy + 1], *above, cellsA[c0 + sy + 1], x + 1, y + 1, z, emit);
        ci[4] = lookupOrEval(*above, cellsA[c0], x, y, z + 1, emit);
        ci[5] = lookupOrEval(*above, cellsA[c0 + 1], x + 1, y, z + 1, emit);
        ci[6] = lookupOrEval(*above, cellsA[c0 + sy], x, y + 1, z + 1, emit);
        ci[7] = lookupOrEval(*above, cellsA[c0 + sy + 1], x + 1, y + 1, z + 1, emit);
        Corner<Policy>* const cornersB = below->corners.data();
        Corner<Policy>* const cornersA = above->corners.data();
        Corner<Policy>* cp[8];
        for (int i = 0; i < 4; ++i) cp[i] = cornersB + ci[i];
        for (int i = 4; i < 8; ++i) cp[i] = cornersA + ci[i];
#if defined(__SSE2__)
        // The case index: bit i set when corner i is inside, as two 4-wide compares.
        const __m128 lo = _mm_setr_ps(cp[0]->value, cp[1]->value, cp[2]->value, cp[3]->value);
        const __m128 hi = _mm_setr_ps(cp[4]->value, cp[5]->value, cp[6]->value, cp[7]->value);
        const __m128 tv = _mm_set1_ps(t);
        const unsigned cube =
            unsigned(_mm_movemask_ps(_mm_cmpgt_ps(lo, tv))) | (unsigned(_mm_movemask_ps(_mm_cmpgt_ps(hi, tv))) << 4);
#else
        unsigned cube = 0;
        for (int i = 0; i < 8; ++i) cube |= unsigned(cp[i]->value > t) << i;
#endif
        if (cube == 0 || cube == 255) continue;
        const mc::CaseTable& cs = table[cube];
        if (emit) {
          polygonize(cs, cp, x, y, z);
          // Crossed faces on a seam plane (seam propagation): rare, kept out of line.
          if (cs.faceMask & (w_.seamX[x] | w_.seamY[y] | w_.seamZ[z])) [[unlikely]]
            noteSeamFaces(cs.faceMask & (w_.seamX[x] | w_.seamY[y] | w_.seamZ[z]), x, y, z);
        }
        // Push neighbours across crossed faces unless done (Alg. 1).
        const unsigned f = cs.faceMask;
        auto pushIn = [&](SliceCell& n, std::uint32_t next) {
          if (!(n.doneAbove | n.queuedAbove)) {
            n.queuedAbove = 1;
            list.push_back(next);
          }
        };
        if (f & 1) pushIn(cellsB[c0 - 1], item - 1);
        if (f & 2) pushIn(cellsB[c0 + 1], item + 1);
        if (f & 4) pushIn(cellsB[c0 - sy], item - (1u << 16));
        if (f & 8) pushIn(cellsB[c0 + sy], item + (1u << 16));
        if ((f & 16) && !(cb.doneBelow | cb.queuedBelow)) {
          assert(z > 0);
          cb.queuedBelow = 1;
          w_.todo[z - 1].push_back(item);
        }
        if ((f & 32) && !(ca.doneAbove | ca.queuedAbove)) {
          assert(z + 1 < nz_);
          ca.queuedAbove = 1;
          w_.todo[z + 1].push_back(item);
        }
      }
      closeSlabVisit(z, slabFirst);
      notePeak(z);
      // Return slices no neighbouring slab still needs (Alg. 1, end of the slab).
      const bool belowEmpty = z == 0 || w_.todo[z - 1].empty();
      const bool aboveEmpty = z + 1 >= nz_ || w_.todo[z + 1].empty();
      if (belowEmpty) freeSlice(z);
      if (aboveEmpty) freeSlice(z + 1);
      if (!belowEmpty) {  // the sweep reverses: slab z-1 got work from this one (Fig. 4)
        --z;
        ++out_.stats.slabReversals;
      }
    }
    for (int i = 0; i <= nz_; ++i) freeSlice(i);
    out_.stats.cubesVisited += cubes;
    out_.indices.resize(nIndices_);  // drop the unused tail of the last step (polygonize)
    lowestTodo_ = std::numeric_limits<int>::max();
  }

#if defined(FLUID_SURFACE_IN_AVX2_COPY)
  // makeVertexAt (marching_slices_impl.hpp) for the plain frame, in vector registers: a corner's
  // value and gradient are one 4-float load, the interpolation, squares and normal run lane by
  // lane, and the position is one 4-double add, blend and convert. The same float and double
  // operations in the same order as makeVertexAt (no FMA), so the same bits; a flat gradient
  // (rare) takes makeVertexAt itself.
  VertexOut makeVertexPlainAvx2(const Corner<Policy>& ca, const Corner<Policy>& cb, unsigned axis,
                                double local[3]) const {
    static_assert(offsetof(Corner<Policy>, g) == sizeof(float));
    const float va = ca.value, vb = cb.value;
    const double tt = (double(su_.threshold) - double(va)) / (double(vb) - double(va));
    const float tf = float(tt);
    const __m128 a = _mm_loadu_ps(&ca.value), b = _mm_loadu_ps(&cb.value);  // value, g[0..2]
    const __m128 g = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(tf), _mm_sub_ps(b, a)));  // lanes 1-3
    const __m128 sq = _mm_mul_ps(g, g);
    const float len2 = (_mm_cvtss_f32(_mm_movehdup_ps(sq)) + _mm_cvtss_f32(_mm_unpackhi_ps(sq, sq))) +
                       _mm_cvtss_f32(_mm_shuffle_ps(sq, sq, 3));  // (g0 g0 + g1 g1) + g2 g2
    if (!(len2 > 1e-30f && std::isfinite(len2))) [[unlikely]]
      return makeVertexAt(su_, local, int(axis), va, ca.g, vb, cb.g);
    const float inv = -1.0f / _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(len2)));
    const __m128 n = _mm_mul_ps(g, _mm_set1_ps(inv));
    // local[axis] += tt S, then float(local - origin) per axis.
    const __m256d l = _mm256_setr_pd(local[0], local[1], local[2], 0.0);
    const __m256d on = _mm256_castsi256_pd(
        _mm256_cmpeq_epi64(_mm256_set1_epi64x(std::int64_t(axis)), _mm256_setr_epi64x(0, 1, 2, 3)));
    const __m256d moved = _mm256_blendv_pd(l, _mm256_add_pd(l, _mm256_set1_pd(tt * su_.s)), on);
    const __m128 pos = _mm256_cvtpd_ps(
        _mm256_sub_pd(moved, _mm256_setr_pd(su_.origin[0], su_.origin[1], su_.origin[2], 0.0)));
    alignas(16) float pf[4], nf[4];
    _mm_store_ps(pf, pos);
    _mm_store_ps(nf, n);
    return {glm::vec3(pf[0], pf[1], pf[2]), glm::vec3(nf[1], nf[2], nf[3])};
  }
#endif

  // `baseAxis`: the edge's base corner | axis << 3 (mc::CaseTable::firstCorner).
  std::uint32_t vertexOn(Corner<Policy>* cp[8], unsigned baseAxis, int x, int y, int z) {
    const unsigned base = baseAxis & 7u, axis = baseAxis >> 3;
    Corner<Policy>& ca = *cp[base];
    if (ca.vert[axis]) return ca.vert[axis] - 1;
    const Corner<Policy>& cb = *cp[base | (1 << axis)];
    const int lx = x + (base & 1), ly = y + ((base >> 1) & 1), lz = z + (base >> 2);
    double local[3] = {w_.cx[lx], w_.cy[ly], w_.cz[lz]};  // double(g0 + l) * S, see begin()
#if defined(FLUID_SURFACE_IN_AVX2_COPY)
    const VertexOut v = su_.plainFrame ? makeVertexPlainAvx2(ca, cb, axis, local)
                                       : makeVertexAt(su_, local, int(axis), ca.value, ca.g, cb.value, cb.g);
#else
    const VertexOut v = makeVertexAt(su_, local, int(axis), ca.value, ca.g, cb.value, cb.g);
#endif
    out_.positions.push_back(v.position);
    out_.normals.push_back(v.normal);
    if constexpr (Policy::kHasUser) {
      const float tf = (su_.threshold - ca.value) / (cb.value - ca.value);
      out_.attributes.push_back(pol_.vertex(ca.user, cb.user, tf));
    }
    out_.keys.push_back(w_.kx[lx] | w_.ky[ly] | w_.kz[lz] | std::uint64_t(axis));  // edgeKey(g0 + l, axis)
    const std::uint32_t id = vertexCount_++;                                       // == out_.positions.size() - 1
    ca.vert[axis] = id + 1;
    return id;
  }

  // Each crossed edge's vertex is looked up (or made) once per cube, in first-use order along the
  // case's triangles (the order walking the triangles would make them in), then the triangles
  // are written from those.
  void polygonize(const mc::CaseTable& cs, Corner<Policy>* cp[8], int x, int y, int z) {
#if defined(FLUID_SURFACE_IN_AVX2_COPY)
    // Zeroed first, so that the permutes below never read an unset lane (ids past the case's edges
    // are computed but never picked).
    alignas(32) std::uint32_t vid[16];
    _mm256_store_si256(reinterpret_cast<__m256i*>(vid), _mm256_setzero_si256());
    _mm256_store_si256(reinterpret_cast<__m256i*>(vid + 8), _mm256_setzero_si256());
#else
    std::uint32_t vid[12];
#endif
    const int ne = cs.edgeCount;
    for (int u = 0; u < ne; ++u) vid[u] = vertexOn(cp, cs.firstCorner[u], x, y, z);
    const int nt = cs.triangleCount;
    // out_.indices is grown ahead in steps of 256 (one bulk zero-fill instead of a resize per
    // cube); nIndices_ is its used length, and march() trims it to that at the end. 40 = 3 x the
    // most triangles of one case (12), rounded up to the AVX2 path's groups of 8.
    const std::size_t first = nIndices_;
    if (out_.indices.size() < first + 40) [[unlikely]]
      out_.indices.resize(first + 256 + 40);
    nIndices_ = first + 3 * std::size_t(nt);
    std::uint32_t* dst = out_.indices.data() + first;
    const std::uint8_t* slot = cs.slot.data();
#if defined(FLUID_SURFACE_IN_AVX2_COPY)
    if (!su_.flip) {
      // The AVX2 copy: eight triangle corners at a time pick their vertex ids from vid with two
      // 8-lane permutes (slot < 8: the low half, else the high half), the same ids as the loop
      // below. A group may run past the case's 3 nt slots (into the table's padding and the
      // index storage's slack); what it writes there is overwritten or trimmed.
      const __m256i lo = _mm256_load_si256(reinterpret_cast<const __m256i*>(vid));
      const __m256i hi = _mm256_load_si256(reinterpret_cast<const __m256i*>(vid + 8));
      for (int i = 0; i < 3 * nt; i += 8) {
        const __m256i idx = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(slot + i)));
        const __m256 a = _mm256_castsi256_ps(_mm256_permutevar8x32_epi32(lo, idx));
        const __m256 h = _mm256_castsi256_ps(_mm256_permutevar8x32_epi32(hi, idx));
        const __m256 pick = _mm256_castsi256_ps(_mm256_slli_epi32(idx, 28));  // bit 3 -> sign
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + i), _mm256_castps_si256(_mm256_blendv_ps(a, h, pick)));
      }
      return;
    }
#endif
    const int b = su_.flip ? 2 : 1, c = su_.flip ? 1 : 2;  // flipped winding: swap the last two
    for (int tri = 0; tri < nt; ++tri, slot += 3, dst += 3) {
      dst[0] = vid[slot[0]];
      dst[1] = vid[slot[b]];
      dst[2] = vid[slot[c]];
    }
  }

  // After one visit of slab z (the triangles from index `first` on are all of that slab): their
  // slab tags for the exact order, or one run per stretch of consecutive triangles of one slab
  // (what buildRuns makes), extended when the previous visit ended with the same slab.
  void closeSlabVisit(int z, std::size_t first) {
    const std::size_t count = nIndices_ - first;
    if (count == 0) return;
    const std::int32_t slab = std::int32_t(g0_[2] + z);
    if (su_.exact) {
      out_.triSlab.insert(out_.triSlab.end(), count / 3, slab);
    } else {
      if (out_.runs.size() == runBase_ || out_.runs.back().slab != slab)
        out_.runs.push_back(SurfaceSlabRun{slab, IndexRange{std::uint32_t(first), 0}});
      out_.runs.back().indices.count += std::uint32_t(count);
    }
  }

  // Exact order (§5): one index range per slab, slabs in sweep order (stable counting sort), and
  // within a slab the triangles sorted by the depth of their centroid along the view direction,
  // farthest first (the paper's "cubes within each slice ... sorted by distance to viewer").
  void sortBySlab() {
    const std::size_t nt = out_.triSlab.size();
    if (nt == 0) return;
    const std::int32_t base = std::int32_t(g0_[2]);
    auto& count = w_.slabCount;
    std::fill(count.begin(), count.end(), 0u);
    for (std::int32_t s : out_.triSlab) ++count[std::size_t(s - base) + 1];
    for (int i = 0; i < nz_; ++i) count[i + 1] += count[i];
    auto& keyed = out_.depthScratch;
    keyed.resize(nt);
    for (std::size_t i = 0; i < nt; ++i) {
      const std::uint32_t* t = &out_.indices[3 * i];
      double depth = 0;
      for (int a = 0; a < 3; ++a) {
        const double c = (double(out_.positions[t[0]][a]) + out_.positions[t[1]][a] + out_.positions[t[2]][a]) / 3.0;
        depth += (c - su_.eyeRel[a]) * su_.view[a];
      }
      const std::uint32_t dst = count[std::size_t(out_.triSlab[i] - base)]++;
      keyed[dst] = {float(-depth), std::uint32_t(i)};  // ascending key = farthest first
    }
    // count[s] is now the end of slab s; sort each slab's range by depth (ties: emission order).
    std::uint32_t begin = 0;
    for (int sl = 0; sl < nz_; ++sl) {
      const std::uint32_t end = count[std::size_t(sl)];
      std::sort(keyed.begin() + begin, keyed.begin() + end);
      begin = end;
    }
    auto& tmp = out_.sortScratch;
    tmp.resize(nt * 3);
    for (std::size_t i = 0; i < nt; ++i)
      std::memcpy(&tmp[3 * i], &out_.indices[3 * keyed[i].second], 3 * sizeof(std::uint32_t));
    out_.indices.swap(tmp);
    std::sort(out_.triSlab.begin(), out_.triSlab.end());
  }
};
