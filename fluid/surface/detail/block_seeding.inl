// Internal: §4 seeding and the seam propagation between blocks (§3). Part of BlockMesher's class
// body, included by block_mesher.inl (twice, see there): no include guard and no includes on purpose.

  // Seeding only asks whether a corner is inside (§4).
  bool insideAt(int x, int y, int z) {
    std::uint64_t looked = 0;
    ++out_.stats.seedEvaluations;
    if (su_.splat) return seedFieldAt(x, y, z) > su_.threshold;
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

  // The particle's own term at the corner offset (ox, oy, oz) from it.
  float ownTerm(const Particle& p, float ox, float oy, float oz) const {
    if constexpr (isAnisotropic<Policy>())
      return stretchedContribution(su_.stretch[p.index], ox, oy, oz, p.strength);
    else
      return contribution(ox * ox + oy * oy, oz, p.k, p.strength);
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
    const bool ownInside = influences(p, w_.cx[x], w_.cy[y], w_.cz[z0]) && ownTerm(p, ox, oy, oz) > t;
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
      const bool ownBelow =
          below >= 1 && influences(p, w_.cx[x], w_.cy[y], w_.cz[below]) && ownTerm(p, ox, oy, ozb) > t;
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
