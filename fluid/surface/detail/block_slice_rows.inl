// Internal: BlockMesher's slice-row field route (SurfaceFieldRoute::sliceRows), included inside the
// class body (see block_mesher.inl). No include guard on purpose.
//
// The field at the corners of one slice, summed by splatting instead of gathering: when Alg. 1 (or
// §4 seeding) first needs a corner of row y of slice z, every block particle whose ball meets that
// row adds its term to each corner of the row inside its ball, particle after particle in the
// block's (z, index) order. Each corner therefore receives exactly the terms the §6 lookup returns
// (the particles within Rc_i, decided by the same double predicate influences()), in the same
// order, with the same float expressions (accumulateDz2S4): the same bits as the §6 route, with no
// per-block cache to build and no column walk per corner. The inner loop runs along x over
// contiguous offsets, so it vectorises (Flying Edges' observation that a lattice row is the unit
// of work, Schroeder et al. 2015 §3, applied to the rows the surface-following sweep touches).
//
// Per slice: which particles meet which row (CSR, built when the slice becomes active, from the
// contiguous run of z-sorted particles that can reach it), and the splatted rows (value and, for
// the march, gradient: four float arrays of rowLen_ each), made on first use.

  // Rows a particle's ball can meet in slice z, widened by 1e-6 cubes (the row splat settles each
  // corner with the exact predicate, so a row too many only costs an empty span).
  void sliceRowSpan(const Particle& p, int z, int& y0, int& y1) const {
    const double dz = w_.cz[z] - p.z;
    const double h2 = p.rc2 - dz * dz;
    if (!(h2 > 0)) {  // (a + dz^2 >= dz^2 for a >= 0: no corner of this slice is within Rc_i)
      y0 = 1, y1 = 0;
      return;
    }
    const double h = std::sqrt(h2), inv = 1.0 / su_.s;
    y0 = std::max(1, iceil((p.y - h) * inv - double(g0_[1]) - 1e-6));
    y1 = std::min(ny_ - 1, ifloor((p.y + h) * inv - double(g0_[1]) + 1e-6));
  }

  // Builds slice z's row lists. Slices 0 and nz stay empty: the field is held at 0 on the expanded
  // block's outer boundary (§3), as the §6 cache clamps min_z / max_z to [1, nz - 1].
  void buildSliceRows(Slice<Policy>& slice, int z) {
    const int rows = ny_ + 1;
    slice.rowStart.assign(std::size_t(rows) + 1, 0u);
    slice.rowField.assign(std::size_t(rows), -1);
    slice.field.clear();
    slice.rowItems.clear();
    if (z < 1 || z > nz_ - 1) return;
    // The particles that can reach slice z: anchors within offsetRange_ slices (a contiguous run of
    // the z-sorted block particles, as fillSliceDz).
    const std::size_t n = w_.local.size();
    const CacheParticle* parts = w_.local.data();
    const int lo = z - offsetRange_, hi = z + offsetRange_;
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < lo; });
    const CacheParticle* last =
        std::partition_point(first, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) <= hi; });
    const std::uint32_t b = std::uint32_t(first - parts), e = std::uint32_t(last - parts);
    auto& spans = w_.rowSpans;  // scratch: each candidate's row range
    spans.resize(e - b);
    std::uint32_t* start = slice.rowStart.data();
    for (std::uint32_t li = b; li < e; ++li) {
      int y0, y1;
      sliceRowSpan(particles_[li], z, y0, y1);
      spans[li - b] = {std::int16_t(y0), std::int16_t(y1)};
      for (int y = y0; y <= y1; ++y) ++start[y + 1];
    }
    for (int y = 0; y < rows; ++y) start[y + 1] += start[y];
    slice.rowItems.resize(start[rows]);
    std::uint32_t* items = slice.rowItems.data();
    auto& cursor = w_.rowCursor;
    cursor.assign(start, start + rows);
    for (std::uint32_t li = b; li < e; ++li)  // ascending li: each row's list in (z, index) order
      for (int y = spans[li - b][0]; y <= spans[li - b][1]; ++y) items[cursor[std::size_t(y)]++] = li;
  }

  // Corners x of row y of slice z inside particle p's ball: [x0, x1] (empty when x0 > x1), from the
  // closed form, each end then settled with influences()' exact double expression (monotone in |dx|,
  // so the corners inside form one run).
  void rowSpan(const Particle& p, int y, int z, int& x0, int& x1) const {
    const double dy = w_.cy[y] - p.y, dz = w_.cz[z] - p.z;
    const double dy2 = dy * dy, dz2 = dz * dz, rc2 = p.rc2;
    const double* cx = w_.cx.data();
    auto inside = [&](int x) {
      const double dx = cx[x] - p.x;
      return (dx * dx + dy2) + dz2 < rc2;
    };
    const double h = std::sqrt(std::max(0.0, rc2 - dy2 - dz2)), inv = 1.0 / su_.s;
    int a = std::max(1, iceil((p.x - h) * inv - double(g0_[0])));
    int c = std::min(nx_ - 1, ifloor((p.x + h) * inv - double(g0_[0])));
    while (a > 1 && inside(a - 1)) --a;
    while (a <= c && !inside(a)) ++a;
    while (c < nx_ - 1 && inside(c + 1)) ++c;
    while (c >= a && !inside(c)) --c;
    x0 = a, x1 = c;
  }

  // Splats row y of slice z (rowLen_ floats per array: value, then gx, gy, gz unless kGradient is
  // false) and returns its value array.
  template <bool kGradient>
  [[gnu::noinline]] float* splatRow(Slice<Policy>& slice, int y, int z) {
    const std::size_t at = slice.field.size();
    const std::size_t len = std::size_t(rowLen_);
    slice.field.resize(at + (kGradient ? 4 : 1) * len, 0.0f);
    slice.rowField[std::size_t(y)] = std::int32_t(at);
    float* __restrict v = slice.field.data() + at;
    float* __restrict gx = v + len;
    float* __restrict gy = v + 2 * len;
    float* __restrict gz = v + 3 * len;
    const float* off = off0_;
    const std::uint32_t* items = slice.rowItems.data();
    const std::uint32_t b = slice.rowStart[std::size_t(y)], e = slice.rowStart[std::size_t(y) + 1];
    std::uint64_t looked = 0;
    for (std::uint32_t i = b; i < e; ++i) {
      const std::uint32_t li = items[i];
      int x0, x1;
      rowSpan(particles_[li], y, z, x0, x1);
      if (x0 > x1) continue;
      looked += std::uint64_t(x1 - x0 + 1);
      const CacheParticle& p = parts_[li];
      // latticeOffset() per axis (field.hpp), bit for bit, from the offsets table.
      const float dy = off[y + p.na[1]] - p.rest[1], dz = off[z + p.na[2]] - p.rest[2];
      const float dyy = dy * dy, dz2 = dz * dz, k = p.k, s = p.s, s4 = p.s4;
      const float* offX = off + p.na[0];
      const float rx = p.rest[0];
      // accumulateDz2S4 per corner, in this loop's order of particles: the same terms, order and
      // float expressions as the §6 route's evaluate<true> (no FMA: the targets have none).
      for (int x = x0; x <= x1; ++x) {
        const float dx = offX[x] - rx;
        const float w = ((dx * dx + dyy) + dz2) * k - 0.5f;
        v[x] += s * (w * w);
        if constexpr (kGradient) {
          const float g = s4 * w * k;
          gx[x] += g * dx;
          gy[x] += g * dy;
          gz[x] += g * dz;
        }
      }
    }
    looked_ += looked;
    return v;
  }

  // The value array of row y of slice z, splatted on first use.
  template <bool kGradient>
  const float* sliceRow(Slice<Policy>& slice, int y, int z) {
    const std::int32_t at = slice.rowField[std::size_t(y)];
    if (at >= 0) [[likely]]
      return slice.field.data() + at;
    return splatRow<kGradient>(slice, y, z);
  }

  // evaluate<> of the slice-row route: the corner's value and gradient read from its row.
  void evaluateFromRow(Slice<Policy>& slice, int x, int y, int z, Corner<Policy>& c) {
    const float* v = sliceRow<true>(slice, y, z);
    const std::size_t len = std::size_t(rowLen_);
    c.value = v[x];
    c.g[0] = v[len + std::size_t(x)];
    c.g[1] = v[2 * len + std::size_t(x)];
    c.g[2] = v[3 * len + std::size_t(x)];
  }

  // §4 seeding's inside test on the slice-row route: value rows only, in seeding slices that live in
  // w_.active until seedRowsDone() (the march starts with none).
  bool insideFromRows(int x, int y, int z) {
    ++out_.stats.seedEvaluations;
    Slice<Policy>*& s = w_.active[std::size_t(z)];
    if (!s) {
      s = w_.acquireSlice();
      buildSliceRows(*s, z);
      ++activeSlices_;
      activeLo_ = std::min(activeLo_, z);
      activeHi_ = std::max(activeHi_, z);
    }
    return sliceRow<false>(*s, y, z)[x] > su_.threshold;
  }
  // Particles arrive in z order, so a descent never needs a slice more than one particle reach below
  // the current start corner z0 again: slices below z0 - keep are returned as the sweep moves up
  // (a later descent that does reach one rebuilds it, with the same values).
  void seedRowsAdvance(int z0) {
    const int keep = su_.m + 2;
    while (activeSlices_ > 0 && activeLo_ < z0 - keep) freeSlice(activeLo_);
  }
  void seedRowsDone() {
    notePeak(0);
    for (int z = activeLo_; activeSlices_ > 0 && z <= activeHi_; ++z) freeSlice(z);
  }
