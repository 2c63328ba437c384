// Internal: the dense scan (SurfaceFieldRoute::denseScan). Part of BlockMesher's class body,
// included by block_mesher.inl (twice, see there): no include guard and no includes on purpose.
//
// The slice splat sums every corner of a slice at once, so once a slice's planes are summed, §4
// seeding plus Alg. 1's walk (todo lists, a corner cache per slice, eight cache lookups per cube)
// cost more than looking at every interior cube. This scans them instead, slab by slab in sweep
// order, with the row idea of Flying Edges (Schroeder, Maynard & Geveci 2015): each slice row's
// inside corners (f > T) become a bit mask, and a row of cubes is crossed where the four masks of
// its corner rows are neither all set nor all clear, so only crossed cubes are visited. Their
// corners, vertices (makeVertexAt's bits, from the value and analytic gradient planes) and
// triangles (the same case tables) are those the walk makes, so the triangle set and every
// vertex's bits are the other routes'; only the order of the triangles within a slab (row order
// here) and of the vertices differs. Each slice is summed once, when the scan reaches it, into one
// of two slices (Worker::denseField: the two slices of Alg. 1, §4; no block volume, no seeding ring).
// Every crossed interior cube is found, so no seam propagation is needed (the route runs in every
// block of the extraction), and so are the components the §4 seeds cannot reach (fields of
// several particles above T away from each one's nearest corner): the dense oracle's triangles.

  // kValue (a template argument of the scan's functions, so the exact route's inner loops carry no
  // test of it): SurfaceFieldRoute::valueScan, whose slices are value planes (block_value_splat.inl).
  //
  // Slice z's four planes (value, df/dx, df/dy, df/dz; Worker::planeFloats each), by parity; with
  // kValue its value plane, by z & 3.
  template <bool kValue>
  const float* densePlanes(int z) const {
    if constexpr (kValue)
      return w_.valueField[std::size_t(z & 3)].data();
    else
      return w_.denseField[std::size_t(z & 1)].data();
  }
  // What slice z's last splat wrote: the slice is 0 outside it.
  template <bool kValue>
  const std::array<std::int16_t, 4>& denseRectOf(int z) const {
    if constexpr (kValue)
      return w_.valueRect[std::size_t(z & 3)];
    else
      return w_.denseRect[std::size_t(z & 1)];
  }
  // Sums slice z into its slot (splatSliceInto, or splatValueInto).
  template <bool kValue>
  void denseSumSlice(int z) {
    if constexpr (kValue)
      splatValueInto(w_.valueField[std::size_t(z & 3)].data(), z, w_.valueRect[std::size_t(z & 3)]);
    else
      splatSliceInto(w_.denseField[std::size_t(z & 1)].data(), z, w_.denseRect[std::size_t(z & 1)]);
  }
  // Corner (x, y) of slice z: from its planes, or with kValue by central differences.
  template <bool kValue>
  void denseCorner(int z, int x, int y, Corner<Policy>& c) const {
    if constexpr (kValue)
      cornerCentral(z, x, y, c);
    else
      cornerFromPlanes(densePlanes<false>(z), x, y, c);
  }

  // Inside bits of slice z's rows y0 .. y1 (a word per 64 corners, bit x = corner x), all columns
  // 0 .. nx. The value plane's rows are planeStride >= nx + 1 floats and the gradient planes follow
  // it (valueScan's value slices have 8 floats of slack after the last row instead), so the 8-wide
  // loads past a row's end stay inside the slice; their bits are masked off.
  // Rows and columns outside what the slice's splat wrote are 0, so not above T > 0.
  template <bool kValue>
  void denseSliceBits(int z, int y0, int y1, std::uint64_t* bits) const {
    const float* plane = densePlanes<kValue>(z);
    const std::array<std::int16_t, 4>& rect = denseRectOf<kValue>(z);
    const std::size_t words = w_.denseWords;
#if defined(__SSE2__)
    const __m128 t = _mm_set1_ps(su_.threshold);
#endif
    const std::uint64_t lastMask = (nx_ + 1) % 64 == 0 ? ~0ull : (1ull << ((nx_ + 1) % 64)) - 1;
    const int x0 = rect[2] & ~7, x1 = std::min<int>(rect[3], nx_);
    for (int y = y0; y <= y1; ++y) {
      const float* row = plane + std::size_t(y) * std::size_t(w_.planeStride);
      std::uint64_t* out = bits + std::size_t(y) * words;
      for (std::size_t i = 0; i < words; ++i) out[i] = 0;
      if (y < rect[0] || y > rect[1]) continue;
      for (int x = x0; x <= x1; x += 8) {
#if defined(__SSE2__)
        const unsigned lo = unsigned(_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(row + x), t)));
        const unsigned hi = unsigned(_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(row + x + 4), t)));
        const unsigned eight = lo | (hi << 4);
#else
        unsigned eight = 0;
        for (int l = 0; l < 8; ++l) eight |= unsigned(row[x + l] > su_.threshold) << l;
#endif
        out[std::size_t(x) >> 6] |= std::uint64_t(eight) << (x & 63);
      }
      out[std::size_t(nx_) >> 6] &= lastMask;
    }
  }

  // The vertex on the edge `baseAxis` (mc::CaseTable::firstCorner: base corner | axis << 3) of cube
  // (x, y) of slab z, made on first use. Ids live five to a column (x and y edges of the even
  // slice, of the odd slice, the slab's z edge): slot 5 col(x, y) + denseSlot_[z & 1][baseAxis].
  template <bool kValue>
  std::uint32_t denseVertex(unsigned baseAxis, std::size_t slot0, int x, int y, int z) {
    const std::size_t slot = slot0 + std::size_t(denseSlot_[z & 1][baseAxis]);
    std::uint32_t& id = w_.denseIds[slot];
    if (id) return id - 1;
    const unsigned base = baseAxis & 7u, axis = baseAxis >> 3;
    const int lx = x + int(base & 1), ly = y + int((base >> 1) & 1), lz = z + int(base >> 2);
    Corner<Policy> ca, cb;
    denseCorner<kValue>(lz, lx, ly, ca);
    denseCorner<kValue>(lz + int(axis == 2), lx + int(axis == 0), ly + int(axis == 1), cb);
    const std::uint32_t made = emitVertex(ca, cb, axis, lx, ly, lz);
    id = made + 1;
    w_.denseTouched[axis == 2 ? 2 : std::size_t(lz & 1)].push_back(std::uint32_t(slot));
    return made;
  }

  // denseSlot_: per slab parity and firstCorner value, the edge's slot relative to its cube's column.
  void denseSlotTable() {
    for (int parity = 0; parity < 2; ++parity)
      for (unsigned baseAxis = 0; baseAxis < 32; ++baseAxis) {
        const unsigned base = baseAxis & 7u, axis = std::min(baseAxis >> 3, 2u);
        const int bx = int(base & 1), by = int((base >> 1) & 1), bz = int(base >> 2);
        const int kind = axis == 2 ? 4 : 2 * ((parity + bz) & 1) + int(axis);
        denseSlot_[parity][baseAxis] = std::int32_t(5 * (bx + by * stride_) + kind);
      }
  }

  // Clears the vertex ids of one of the three id arrays (0, 1: the face arrays by slice parity,
  // 2: the slab's z edges): only the slots written since, not the whole array.
  void denseClearIds(int which) {
    for (std::uint32_t s : w_.denseTouched[std::size_t(which)]) w_.denseIds[s] = 0;
    w_.denseTouched[std::size_t(which)].clear();
  }

  // The block's interior cubes, slab by slab upwards (the sweep order, §5).
  void denseScan() {
    if (su_.valueOnly)
      denseScanSlabs<true>();
    else
      denseScanSlabs<false>();
  }
  template <bool kValue>
  void denseScanSlabs() {
    const auto& table = mc::tables().cases[su_.octant];
    const int ia = su_.m, ibx = su_.m + su_.b[0], iby = su_.m + su_.b[1], ibz = su_.m + su_.b[2];
    const std::size_t words = std::size_t(nx_ + 1 + 63) / 64 + 1;  // + 1: a zero word for the shifts
    const std::size_t cols = std::size_t(stride_) * std::size_t(ny_ + 1);
    w_.denseWords = words;
    denseSlotTable();
    if (w_.denseIds.size() != 5 * cols) {  // a new block shape: all ids 0, nothing to clear
      w_.denseIds.assign(5 * cols, 0u);
      for (auto& touched : w_.denseTouched) touched.clear();
    }
    for (int k = 0; k < 3; ++k) denseClearIds(k);  // what the last block left (its top face)
    const std::size_t sliceWords = words * std::size_t(ny_ + 1);
    w_.denseBits.resize(2 * sliceWords);
    // The cubes x in [ia, ibx) of a row, as a mask per word.
    w_.denseCubeMask.assign(words, 0);
    for (int x = ia; x < ibx; ++x) w_.denseCubeMask[std::size_t(x) >> 6] |= 1ull << (x & 63);
    const std::uint64_t* cubeMask = w_.denseCubeMask.data();
    std::uint64_t* bits[2] = {w_.denseBits.data(), w_.denseBits.data() + sliceWords};
    // Slices are summed one ahead of the slab's top (two ahead with valueScan, whose vertices read
    // the slices below and above their corners').
    constexpr int ahead = kValue ? 2 : 1;
    for (int z = ia - ahead + 1; z <= ia + ahead - 1; ++z) denseSumSlice<kValue>(z);
    denseSliceBits<kValue>(ia, ia, iby, bits[ia & 1]);
    std::uint64_t cubes = 0;
    for (int z = ia; z < ibz; ++z) {
      denseSumSlice<kValue>(z + ahead);
      denseSliceBits<kValue>(z + 1, ia, iby, bits[(z + 1) & 1]);
      const std::uint64_t* below = bits[z & 1];
      const std::uint64_t* above = bits[(z + 1) & 1];
      const std::size_t slabFirst = nIndices_;
      for (int y = ia; y < iby; ++y) {
        const std::uint64_t* r00 = below + std::size_t(y) * words;
        const std::uint64_t* r01 = r00 + words;
        const std::uint64_t* r10 = above + std::size_t(y) * words;
        const std::uint64_t* r11 = r10 + words;
        for (std::size_t i = 0; i + 1 < words; ++i) {
          // Bit x of a row and of the row shifted by one corner (x + 1 at bit x).
          const std::uint64_t a0 = r00[i], a1 = r01[i], a2 = r10[i], a3 = r11[i];
          const std::uint64_t s0 = (a0 >> 1) | (r00[i + 1] << 63), s1 = (a1 >> 1) | (r01[i + 1] << 63),
                              s2 = (a2 >> 1) | (r10[i + 1] << 63), s3 = (a3 >> 1) | (r11[i + 1] << 63);
          const std::uint64_t all = a0 & s0 & a1 & s1 & a2 & s2 & a3 & s3;
          const std::uint64_t any = a0 | s0 | a1 | s1 | a2 | s2 | a3 | s3;
          std::uint64_t mixed = any & ~all & cubeMask[i];
          while (mixed) {
            const int b = __builtin_ctzll(mixed);
            mixed &= mixed - 1;
            const int x = int(i * 64) + b;
            // Corner c = (x + (c & 1), y + (c >> 1 & 1), z + (c >> 2)) is bit c (mc_tables.hpp).
            const unsigned cube = unsigned((a0 >> b) & 1) | unsigned((s0 >> b) & 1) << 1 |
                                  unsigned((a1 >> b) & 1) << 2 | unsigned((s1 >> b) & 1) << 3 |
                                  unsigned((a2 >> b) & 1) << 4 | unsigned((s2 >> b) & 1) << 5 |
                                  unsigned((a3 >> b) & 1) << 6 | unsigned((s3 >> b) & 1) << 7;
            const std::size_t slot0 = 5 * col(x, y);
            writeCase(table[cube], [&](unsigned baseAxis) { return denseVertex<kValue>(baseAxis, slot0, x, y, z); });
          }
        }
      }
      cubes += std::uint64_t(ibx - ia) * std::uint64_t(iby - ia);
      closeSlabVisit(z, slabFirst);
      // Slab z + 1 shares slice z + 1's face edges; slice z's and this slab's z edges are done.
      denseClearIds(z & 1);
      denseClearIds(2);
    }
    out_.stats.cubesVisited += cubes;
    out_.stats.cornersEvaluated += std::uint64_t(ibx - ia + 1) * std::uint64_t(iby - ia + 1) * std::uint64_t(ibz - ia + 1);
    out_.indices.resize(nIndices_);
    const std::uint64_t bytes = w_.denseBits.size() * sizeof(std::uint64_t) +
                                w_.denseIds.size() * sizeof(std::uint32_t) +
                                2 * w_.denseField[0].size() * sizeof(float) + 4 * w_.valueField[0].size() * sizeof(float);
    peakCornerBytes_ = std::max(peakCornerBytes_, bytes);
  }
