// Internal: the value-only slice splat and central-difference corners of SurfaceFieldRoute::valueScan.
// Part of BlockMesher's class body, included by block_mesher.inl (twice, see there): no include
// guard and no includes on purpose.
//
// The dense scan (block_dense_scan.inl) over a field summed the way the dense-lattice peer sums
// it: per slice, the block's particles in (z, index) order each add s w^2 (§2's f_i, w = r^2 k -
// 1/2) to the corners of their disc whose float r^2 = dx^2 + (dy^2 + dz^2) is below
// float(Rc_i^2), eight corners of a row at once. No gradient planes, no double predicate near Rc_i
// and no per-row disc bounds: a row is skipped when dy^2 + dz^2 alone reaches Rc_i^2, and the lane
// mask does the rest. A vertex's normal is then interpolated (§2's vertex routine) between the
// central differences of the value at its edge's two corners, as Flying Edges makes its normals,
// so each slice is summed one corner beyond the interior too, and four slices are alive (z - 1 ..
// z + 2 around slab z).
//
// A lane outside the disc adds w = 0 (masked), which leaves every sum as it is (block_slice_splat.inl).

  // The rows y0 .. y1 of one particle's disc in a slice, kVectors windows of 8 columns from
  // `at` (row y0), offX = the offsets table at the first window's first column, inX = the write
  // mask (-1 on the columns the route writes) there, offY = the offsets table at row 0 - anchor y.
  // Returns the terms added.
  template <int kVectors>
  [[gnu::always_inline]] std::uint64_t valueRows(const CacheParticle& cp, const float* offX, const std::int32_t* inX,
                                                 const float* offY, float dz2f, float rc2, int y0, int y1, float* at) {
    SplatF8 dx2[kVectors];
    SplatI8 write[kVectors];
    for (int v = 0; v < kVectors; ++v) {
      SplatF8 offs;
      std::memcpy(&offs, offX + 8 * v, sizeof offs);
      const SplatF8 dxf = offs - cp.rest[0];
      dx2[v] = dxf * dxf;
      std::memcpy(&write[v], inX + 8 * v, sizeof write[v]);
    }
    const float k = cp.k, s = cp.s, rest1 = cp.rest[1];
    const std::size_t stride = std::size_t(w_.planeStride);
    SplatI8 counted = {};
    for (int y = y0; y <= y1; ++y, at += stride) {
      const float dyf = offY[y] - rest1, dyz = dyf * dyf + dz2f;
      if (dyz >= rc2) continue;  // r^2 >= dy^2 + dz^2 on every lane (rounding is monotonic)
      for (int v = 0; v < kVectors; ++v) {
        const SplatF8 r2 = dx2[v] + dyz;
        const SplatI8 mask = (r2 < rc2) & write[v];
        counted -= mask;
        const SplatF8 wv = (SplatF8)((SplatI8)(r2 * k - 0.5f) & mask);
        SplatF8 acc;
        std::memcpy(&acc, at + 8 * v, sizeof acc);
        acc += s * (wv * wv);
        std::memcpy(at + 8 * v, &acc, sizeof acc);
      }
    }
    std::uint64_t terms = 0;
    for (int i = 0; i < 8; ++i) terms += std::uint32_t(counted[i]);
    return terms;
  }

  // Sums slice z's value into `plane` (Worker::planeFloats floats), which is 0 outside `rect`, what
  // its last splat wrote: only that is cleared first; `rect` becomes what this splat wrote.
  void splatValueInto(float* plane, int z, std::array<std::int16_t, 4>& rect) {
    const int stride = w_.planeStride;
    for (int y = rect[0]; y <= rect[1]; ++y) {
      float* row = plane + std::size_t(y) * std::size_t(stride);
      std::fill(row + rect[2], row + rect[3] + 1, 0.0f);
    }
    rect = {1, 0, 1, 0};
    if (z < 1 || z > nz_ - 1) return;  // outer slices stay 0 (§3)
    const CacheParticle* parts = w_.local.data();
    const std::size_t n = w_.local.size();
    // Local anchors along z that can reach slice z (-na[2] is non-decreasing in li).
    const int reachMax = splatReachMax_;
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < z - reachMax; });
    const CacheParticle* last =
        std::partition_point(first, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) <= z + reachMax; });
    const float* off = w_.splatOffsets.data() + offsetRange_;
    const std::int16_t* reachOf = w_.splatReach.data();
    const std::int32_t* writeAt = w_.splatInBlock.data();
    const float* rc2Of = w_.splatRc2.data();
    const int ylo = splatFirst_, yhi = splatLast_[1];
    int wy0 = ny_, wy1 = 0, wx0 = stride, wx1 = 0;  // rows and columns written
    std::uint64_t terms = 0;
    for (const CacheParticle* cp = first; cp != last; ++cp) {
      const std::size_t li = std::size_t(cp - parts);
      const float rc2 = rc2Of[li];
      const float dzf = off[z + cp->na[2]] - cp->rest[2], dz2f = dzf * dzf;
      if (dz2f >= rc2) continue;
      // Rows and columns anchor - r .. anchor + r (blockSpan's reach), in windows of 8 from xs,
      // moved into the row where the reach sticks out of it.
      const int r = reachOf[li];
      const int ax = -cp->na[0], ay = -cp->na[1];
      const int y0 = std::max(ylo, ay - r), y1 = std::min(yhi, ay + r);
      if (y0 > y1) continue;
      const int vectors = (2 * r + 8) / 8;
      const int xs = std::min(std::max(ax - r, 0), stride - 8 * vectors);
      wy0 = std::min(wy0, y0), wy1 = std::max(wy1, y1);
      wx0 = std::min(wx0, xs), wx1 = std::max(wx1, xs + 8 * vectors - 1);
      float* at = plane + std::size_t(y0) * std::size_t(stride) + std::size_t(xs);
      const float* offX = off + (xs - ax);
      const float* offY = off + cp->na[1];
      switch (vectors) {  // reach <= 3: one window (the fountain), <= 7: two, <= 11: three
        case 1: terms += valueRows<1>(*cp, offX, writeAt + xs, offY, dz2f, rc2, y0, y1, at); break;
        case 2: terms += valueRows<2>(*cp, offX, writeAt + xs, offY, dz2f, rc2, y0, y1, at); break;
        case 3: terms += valueRows<3>(*cp, offX, writeAt + xs, offY, dz2f, rc2, y0, y1, at); break;
        default:  // (reach >= 12, Rc_i / S > 11: rare) a window at a time
          for (int v = 0; v < vectors; ++v)
            terms += valueRows<1>(*cp, offX + 8 * v, writeAt + xs + 8 * v, offY, dz2f, rc2, y0, y1, at + 8 * v);
          break;
      }
    }
    if (wy0 <= wy1) rect = {std::int16_t(wy0), std::int16_t(wy1), std::int16_t(wx0), std::int16_t(wx1)};
    looked_ += terms;
  }

  // Corner (x, y) of value slice z: its value and the central differences f(+1) - f(-1) along
  // each axis (the gradient times 2 S; the vertex routine normalizes it, and both corners of an
  // edge share the factor).
  void cornerCentral(int z, int x, int y, Corner<Policy>& c) const {
    const std::size_t stride = std::size_t(w_.planeStride);
    const std::size_t at = std::size_t(y) * stride + std::size_t(w_.planePad + x);
    const float* f = densePlanes<true>(z);
    c.value = f[at];
    c.g[0] = f[at + 1] - f[at - 1];
    c.g[1] = f[at + stride] - f[at - stride];
    c.g[2] = densePlanes<true>(z + 1)[at] - densePlanes<true>(z - 1)[at];
    c.user = {};
  }
