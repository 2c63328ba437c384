#include "fluid/surface/mc_tables.hpp"

#include <algorithm>
#include <cassert>

namespace fluid::mc {
namespace {

struct V3 {
  double x, y, z;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cornerPos(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }
V3 edgeMid(int e) {
  V3 p = cornerPos(kEdgeBase[e]);
  (&p.x)[kEdgeAxis[e]] += 0.5;
  return p;
}
int edgeBetween(int a, int b) {
  const int base = std::min(a, b);
  const int diff = a ^ b;
  const int axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
  for (int e = 0; e < 12; ++e)
    if (kEdgeBase[e] == base && kEdgeAxis[e] == axis) return e;
  assert(false);
  return -1;
}

// Faces holding edge e: (axis u, side = bit u of its base corner) for both u != its axis.
bool shareFace(int e0, int e1) {
  for (int u = 0; u < 3; ++u) {
    if (u == kEdgeAxis[e0] || u == kEdgeAxis[e1]) continue;
    if (((kEdgeBase[e0] >> u) & 1) == ((kEdgeBase[e1] >> u) & 1)) return true;
  }
  return false;
}

CaseTable buildCase(int cube) {
  CaseTable t;
  auto inside = [cube](int c) { return (cube >> c) & 1; };
  for (int e = 0; e < 12; ++e) {
    const int a = kEdgeBase[e], b = a | (1 << kEdgeAxis[e]);
    if (inside(a) != inside(b)) t.edgeMask |= std::uint16_t(1u << e);
  }
  int next[12];
  std::fill(next, next + 12, -1);
  for (int axis = 0; axis < 3; ++axis) {
    const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    for (int side = 0; side < 2; ++side) {
      const int ring[4] = {side << axis, (side << axis) | (1 << u), (side << axis) | (1 << u) | (1 << v),
                           (side << axis) | (1 << v)};
      V3 normal{0, 0, 0};
      (&normal.x)[axis] = side ? 1.0 : -1.0;
      int crossed = 0;
      for (int i = 0; i < 4; ++i) crossed += inside(ring[i]) != inside(ring[(i + 1) % 4]);
      if (crossed == 0) continue;
      t.faceMask |= std::uint8_t(1u << (2 * axis + side));
      // Segments as (edgeP, edgeQ, inside reference point).
      struct Seg {
        int p, q;
        V3 ref;
      } segs[2];
      int nseg = 0;
      if (crossed == 2) {
        int ends[2], n = 0;
        V3 ref{0, 0, 0};
        int nin = 0;
        for (int i = 0; i < 4; ++i) {
          if (inside(ring[i]) != inside(ring[(i + 1) % 4])) ends[n++] = edgeBetween(ring[i], ring[(i + 1) % 4]);
          if (inside(ring[i])) {
            const V3 c = cornerPos(ring[i]);
            ref = {ref.x + c.x, ref.y + c.y, ref.z + c.z};
            ++nin;
          }
        }
        ref = {ref.x / nin, ref.y / nin, ref.z / nin};
        segs[nseg++] = {ends[0], ends[1], ref};
      } else {
        // Ambiguous face: cut off each inside corner on its own (the face rule above).
        for (int i = 0; i < 4; ++i) {
          if (!inside(ring[i])) continue;
          segs[nseg++] = {edgeBetween(ring[(i + 3) % 4], ring[i]), edgeBetween(ring[i], ring[(i + 1) % 4]),
                          cornerPos(ring[i])};
        }
      }
      for (int s = 0; s < nseg; ++s) {
        int p = segs[s].p, q = segs[s].q;
        const V3 P = edgeMid(p), Q = edgeMid(q);
        // Orientation giving outward (towards lower field), counter-clockwise loops.
        if (dot(cross(sub(Q, P), sub(segs[s].ref, P)), normal) > 0) std::swap(p, q);
        assert(next[p] == -1);
        next[p] = q;
      }
    }
  }
  bool used[12] = {};
  int tri = 0;
  for (int e = 0; e < 12; ++e) {
    if (!((t.edgeMask >> e) & 1) || used[e]) continue;
    int loop[12], n = 0;
    for (int cur = e; !used[cur]; cur = next[cur]) {
      assert(cur >= 0);
      used[cur] = true;
      loop[n++] = cur;
    }
    // Fan apex: a diagonal between two crossings on the same cube face would lie in that face
    // and be shared with the neighbour cube's patch (an edge of four triangles). Pick an apex
    // whose diagonals all cross the cube's interior.
    int apex = -1;
    for (int r = 0; r < n && apex < 0; ++r) {
      bool ok = true;
      for (int i = 2; i + 1 < n && ok; ++i) ok = !shareFace(loop[r], loop[(r + i) % n]);
      if (ok) apex = r;
    }
    assert(apex >= 0);
    if (apex < 0) apex = 0;
    for (int i = 1; i + 1 < n; ++i) {
      t.edges[3 * tri + 0] = std::uint8_t(loop[apex]);
      t.edges[3 * tri + 1] = std::uint8_t(loop[(apex + i) % n]);
      t.edges[3 * tri + 2] = std::uint8_t(loop[(apex + i + 1) % n]);
      ++tri;
    }
  }
  t.triangleCount = std::uint8_t(tri);
  return t;
}

Tables buildTables() {
  Tables tables;
  for (int cube = 0; cube < 256; ++cube) tables.cases[0][cube] = buildCase(cube);
  for (int octant = 0; octant < 8; ++octant) {
    const V3 view{octant & 1 ? -1.0 : 1.0, octant & 2 ? -1.0 : 1.0, octant & 4 ? -1.0 : 1.0};
    for (int cube = 0; cube < 256; ++cube) {
      const CaseTable& base = tables.cases[0][cube];
      int order[12];
      double depth[12];
      const int nt = std::min<int>(base.triangleCount, 12);  // at most 12 by construction
      for (int i = 0; i < nt; ++i) {
        order[i] = i;
        V3 c{0, 0, 0};
        for (int k = 0; k < 3; ++k) {
          const V3 m = edgeMid(base.edges[3 * i + k]);
          c = {c.x + m.x, c.y + m.y, c.z + m.z};
        }
        depth[i] = dot(c, view);
      }
      // Farthest along the view direction first; ties keep their order (a stable insertion sort
      // of at most 12 items; std::stable_sort here drew a false -Warray-bounds from GCC 12 in the
      // ASan build).
      for (int i = 1; i < nt; ++i) {
        const int v = order[i];
        int j = i;
        for (; j > 0 && depth[v] > depth[order[j - 1]]; --j) order[j] = order[j - 1];
        order[j] = v;
      }
      CaseTable sorted = base;
      for (int i = 0; i < nt; ++i)
        for (int k = 0; k < 3; ++k) sorted.edges[3 * i + k] = base.edges[3 * order[i] + k];
      tables.cases[octant][cube] = sorted;
    }
  }
  for (auto& octant : tables.cases)
    for (CaseTable& t : octant) {
      int local[12];
      for (int& l : local) l = -1;
      t.edgeCount = 0;
      for (int i = 0; i < 3 * t.triangleCount; ++i) {
        const int e = t.edges[i];
        if (local[e] < 0) {
          local[e] = t.edgeCount;
          t.firstCorner[t.edgeCount] = std::uint8_t(kEdgeBase[e] | (kEdgeAxis[e] << 3));
          t.firstUse[t.edgeCount++] = std::uint8_t(e);
        }
        t.slot[i] = std::uint8_t(local[e]);
      }
    }
  return tables;
}

}  // namespace

const Tables& tables() {
  static const Tables kTables = buildTables();
  return kTables;
}

}  // namespace fluid::mc
