// Internal: the per-block marching-slices algorithm (paper Alg. 1, §3-§6), the body of
// marching_slices_impl.hpp's BlockMesher. No include guard and no includes on purpose: that
// header includes it twice, once as is and once compiled for AVX2 (namespace avx2, see there).
// The class body is split along the algorithm's phases: this file has the block setup, the slice
// caches and Alg. 1's loop (march); block_particle_cache.inl the §6 cache and the corner field
// sums, block_seeding.inl §4 seeding and seam propagation, block_output.inl vertices, triangles
// and the §5 slab order.
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
    if (su_.splat)
      prepareSplat(particles);
    else
      buildParticleCache(particles);
    const PhaseClock::time_point cached = PhaseClock::now();
    const bool scan = su_.dense;  // block_dense_scan.inl: every interior cube, no seeds
    if (!scan) {
      seed(particles);
      seedFromNeighbours();
    }
    const PhaseClock::time_point seeded = PhaseClock::now();
    if (scan)
      denseScan();
    else
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
    out_.stats.splatBlocks = su_.splat ? 1 : 0;
    out_.stats.scannedBlocks = scan ? 1 : 0;
    out_.stats.vertices = out_.vertexCount;
    if (su_.splat)  // block particles, the seeding ring and the small tables
      out_.particleBytes = std::uint64_t(w_.local.size()) * sizeof(CacheParticle) +
                           std::uint64_t(w_.seedRing.size() + w_.volume.size()) * sizeof(float) +
                           std::uint64_t(w_.splatOffsets.size()) * sizeof(float) +
                           std::uint64_t(w_.splatCx.size()) * sizeof(double) +
                           std::uint64_t(w_.splatInBlock.size()) * sizeof(std::int32_t);
    else
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
  // Anisotropic policies: the block particles' StretchTerm records, in CacheParticle order.
  const StretchTerm* stretch_ = nullptr;
  const StretchTerm& stretchOf(const CacheParticle& p) const { return stretch_[std::size_t(&p - parts_)]; }
  int lowestTodo_ = std::numeric_limits<int>::max();
  std::int32_t denseSlot_[2][32] = {};  // the dense scan's edge slots (denseSlotTable)

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

#include "fluid/surface/detail/block_particle_cache.inl"
#include "fluid/surface/detail/block_slice_splat.inl"
#include "fluid/surface/detail/block_seeding.inl"
#include "fluid/surface/detail/block_dense_scan.inl"
#include "fluid/surface/detail/block_value_splat.inl"

  Slice<Policy>* ensureSlice(int z) {
    if (!w_.active[z]) {
      w_.active[z] = w_.acquireSlice();
      if (su_.splat)
        attachPlanes(*w_.active[z], z);
      else
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
                 w_.active[i]->corners.size() * sizeof(Corner<Policy>) + w_.active[i]->dz.size() * sizeof(SliceDz) +
                 w_.active[i]->field.size() * sizeof(float);
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
    if (!cellHi.corner && (su_.splat || interior || (interiorCorner(x, y, z) && interiorCorner(x, y, z + 1))))
      return evaluatePairInto(lo, cellLo, hi, cellHi, x, y, z) - 1;
    return evaluateInto(lo, cellLo, x, y, z, interior) - 1;
  }

  // Evaluates corner (x, y, z) into the slice's corner cache; returns its index + 1. Not inlined:
  // one out-of-line copy keeps the march loop small (most corners are already cached).
  [[gnu::noinline]] std::uint32_t evaluateInto(Slice<Policy>& slice, SliceCell& cell, int x, int y, int z,
                                               bool interior) {
    Corner<Policy> c;
    if (su_.splat)
      cornerFromPlanes(slice, x, y, c);  // the full sum also at margin corners: the same sign (§3)
    else if (interior || interiorCorner(x, y, z))
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

#include "fluid/surface/detail/block_output.inl"
};
