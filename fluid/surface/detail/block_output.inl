// Internal: vertex and triangle output (§2 default vertex routine, §5 slab order). Part of
// BlockMesher's class body, included by block_mesher.inl (twice, see there): no include guard and no
// includes on purpose.

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
    const std::uint32_t id = emitVertex(ca, cb, axis, lx, ly, lz);
    ca.vert[axis] = id + 1;
    return id;
  }

  // Appends the vertex on the edge from local corner (lx, ly, lz) (values and gradients in ca) along
  // `axis` to its neighbour (cb); returns its id.
  std::uint32_t emitVertex(const Corner<Policy>& ca, const Corner<Policy>& cb, unsigned axis, int lx, int ly, int lz) {
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
    return vertexCount_++;                                                         // == out_.positions.size() - 1
  }

  void polygonize(const mc::CaseTable& cs, Corner<Policy>* cp[8], int x, int y, int z) {
    writeCase(cs, [&](unsigned baseAxis) { return vertexOn(cp, baseAxis, x, y, z); });
  }

  // Each crossed edge's vertex is looked up (or made) once per cube by vertexFor(firstCorner), in
  // first-use order along the case's triangles (the order walking the triangles would make them
  // in), then the triangles are written from those.
  template <class VertexFor>
  [[gnu::always_inline]] void writeCase(const mc::CaseTable& cs, VertexFor&& vertexFor) {
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
    for (int u = 0; u < ne; ++u) vid[u] = vertexFor(cs.firstCorner[u]);
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
