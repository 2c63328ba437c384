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
// §4 seeding asks for inside/outside at corners along short descents before the march: a ring of
// value-only slices (Worker::seedRing) serves them, filled the same way; the seeds' starts rise
// with the particles' z, so each slice is summed once there.
//
// Masked lanes add +0.0f, which leaves every sum unchanged: values are >= 0 and a gradient sum
// that starts at +0 and only adds never becomes -0 (round to nearest gives -0 only for -0 + -0).

  // GCC vector extensions: 8 floats, 8 int32 and 4 doubles (two SSE registers each in the
  // portable copy, one AVX register in the AVX2 one; the same IEEE operations lane by lane, no FMA).
  using SplatF8 = float __attribute__((vector_size(32)));
  using SplatI8 = std::int32_t __attribute__((vector_size(32)));
  using SplatD4 = double __attribute__((vector_size(32)));
  using SplatU8 = std::uint32_t __attribute__((vector_size(32)));
  using SplatI4 = std::int32_t __attribute__((vector_size(16)));

  // Block setup for the route: the block particles' float records (CacheParticle, as the cache has
  // them), the offsets table float(d S) and the corners' x coordinates over the padded plane rows.
  void prepareSplat(std::span<const Particle> particles) {
    const int m = su_.m;
    offsetRange_ = m + 2;
    w_.splatOffsets.resize(std::size_t(2 * offsetRange_ + 17));
    for (int d = -offsetRange_; d <= offsetRange_ + 16; ++d)
      w_.splatOffsets[std::size_t(d + offsetRange_)] = float(double(d) * su_.s);
    w_.splatCx.resize(std::size_t(nx_ + 1 + 2 * m + 16));
    for (int i = -m; i <= nx_ + m + 15; ++i) w_.splatCx[std::size_t(i + m)] = double(g0_[0] + i) * su_.s;
    w_.local.resize(particles.size());
    for (std::uint32_t li = 0; li < particles.size(); ++li) {
      const Particle& p = particles[li];
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
  }

  // Sums slice z's field into `planes` (value, then with kGrad df/dx, df/dy, df/dz; Worker::planeFloats
  // each, cleared first). Returns the number of particle terms added.
  template <bool kGrad>
  std::uint64_t splatSlice(float* planes, int z) {
    const std::size_t pf = w_.planeFloats;
    std::fill(planes, planes + (kGrad ? 4 : 1) * pf, 0.0f);
    if (z < 1 || z > nz_ - 1) return 0;  // outer slices stay 0 (§3)
    const int m = su_.m, stride = w_.planeStride;
    const CacheParticle* parts = w_.local.data();
    const std::size_t n = w_.local.size();
    // Local anchors along z that can reach slice z (reach <= m); -na[2] is non-decreasing in li.
    const CacheParticle* first =
        std::partition_point(parts, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) < z - m; });
    const CacheParticle* last =
        std::partition_point(first, parts + n, [&](const CacheParticle& p) { return -int(p.na[2]) <= z + m; });
    const float* off = w_.splatOffsets.data() + offsetRange_;
    const double* cxPad = w_.splatCx.data() + m;  // cxPad[x] = double(g0 + x) S for x in [-m, nx + m + 15]
    const SplatI8 iota = {0, 1, 2, 3, 4, 5, 6, 7};
    const unsigned xSpan = unsigned(nx_ - 2);  // inner columns 1 .. nx - 1: unsigned(x - 1) <= nx - 2
    SplatI8 counted = {};
    for (const CacheParticle* cp = first; cp != last; ++cp) {
      const Particle& p = particles_[std::size_t(cp - parts)];
      const double dzd = w_.cz[z] - p.z, dz2d = dzd * dzd;
      if (!(dz2d < p.rc2)) continue;  // (dx^2 + dy^2) + dz^2 >= dz^2 in rounded arithmetic too
      const int r = particleReach(p, su_.s);
      const int ax = -cp->na[0], ay = -cp->na[1];
      const float dzf = off[z + cp->na[2]] - cp->rest[2], dz2f = dzf * dzf;
      const int y0 = std::max(1, ay - r), y1 = std::min(ny_ - 1, ay + r);
      const int xw = ax - r, vectors = (2 * r + 8) / 8;  // columns ax - r .. ax + r (blockSpan's reach)
      const float k = cp->k, s = cp->s, s4 = cp->s4, rest0 = cp->rest[0];
      for (int y = y0; y <= y1; ++y) {
        const double dyd = w_.cy[y] - p.y, dy2d = dyd * dyd;
        if (!(dy2d + dz2d < p.rc2)) continue;
        const float dyf = off[y + cp->na[1]] - cp->rest[1], dy2f = dyf * dyf;
        float* row = planes + std::size_t(y) * std::size_t(stride) + std::size_t(w_.planePad + xw);
        for (int v = 0; v < vectors; ++v) {
          const int x = xw + 8 * v;
          // The exact predicate of influences(), lane by lane in double.
          SplatD4 cxa, cxb;
          std::memcpy(&cxa, cxPad + x, sizeof cxa);
          std::memcpy(&cxb, cxPad + x + 4, sizeof cxb);
          const SplatD4 dxa = cxa - p.x, dxb = cxb - p.x;
          const auto ina = ((dxa * dxa + dy2d) + dz2d) < p.rc2;
          const auto inb = ((dxb * dxb + dy2d) + dz2d) < p.rc2;
          const SplatI4 ma = __builtin_convertvector(ina, SplatI4), mb = __builtin_convertvector(inb, SplatI4);
          const SplatI8 inDisc = __builtin_shufflevector(ma, mb, 0, 1, 2, 3, 4, 5, 6, 7);
          const SplatI8 inBlock = (SplatI8)((SplatU8)(iota + (x - 1)) <= xSpan);
          const SplatI8 mask = inDisc & inBlock;
          counted -= mask;
          SplatF8 offs;
          std::memcpy(&offs, off + (x - ax), sizeof offs);
          const SplatF8 dxf = offs - rest0;
          // accumulateDz2S4's expressions: w = ((dx dx + dy dy) + dz dz) k - 1/2, f += s w^2,
          // grad += (4 s w) k (dx, dy, dz).
          const SplatF8 dxy2 = dxf * dxf + dy2f;
          const SplatF8 wv = (dxy2 + dz2f) * k - 0.5f;
          float* at = row + 8 * v;
          SplatF8 acc;
          std::memcpy(&acc, at, sizeof acc);
          acc += (SplatF8)((SplatI8)(s * (wv * wv)) & mask);
          std::memcpy(at, &acc, sizeof acc);
          if constexpr (kGrad) {
            const SplatF8 g = (s4 * wv) * k;
            float* gp[3] = {at + pf, at + 2 * pf, at + 3 * pf};
            const SplatF8 terms[3] = {g * dxf, g * dyf, g * dzf};
            for (int a = 0; a < 3; ++a) {
              std::memcpy(&acc, gp[a], sizeof acc);
              acc += (SplatF8)((SplatI8)terms[a] & mask);
              std::memcpy(gp[a], &acc, sizeof acc);
            }
          }
        }
      }
    }
    std::uint64_t terms = 0;
    for (int i = 0; i < 8; ++i) terms += std::uint32_t(counted[i]);
    return terms;
  }

  // Seeding's field at corner (x, y, z) from the ring of value slices (the full sum: (f > T) as
  // sumUntilAbove decides it).
  float seedFieldAt(int x, int y, int z) {
    const std::size_t slots = w_.ringZ.size();
    const std::size_t slot = std::size_t(z) % slots;
    float* plane = w_.seedRing.data() + slot * w_.planeFloats;
    if (w_.ringZ[slot] != z) {
      looked_ += splatSlice<false>(plane, z);
      w_.ringZ[slot] = z;
    }
    return plane[std::size_t(y) * std::size_t(w_.planeStride) + std::size_t(w_.planePad + x)];
  }

  // A corner of slice `slice` from its planes.
  void cornerFromPlanes(const Slice<Policy>& slice, int x, int y, Corner<Policy>& c) const {
    const std::size_t at = std::size_t(y) * std::size_t(w_.planeStride) + std::size_t(w_.planePad + x);
    const float* f = slice.field.data();
    const std::size_t pf = w_.planeFloats;
    c.value = f[at];
    c.g[0] = f[at + pf];
    c.g[1] = f[at + 2 * pf];
    c.g[2] = f[at + 3 * pf];
    c.user = {};
  }
