#!/usr/bin/env python3
"""The blob street's edges (issue 35 item 3): four building fronts closing the street around the
sewer, so the player and the monster keep to it and no grey void shows from the street. Writes
content/models/blob_front_{west,east,south,north}.obj in world coordinates (like the level's other
models, scripts/generate_content.py): each a closed box, founded 0.2 m under the street, drawn by
the renderer, a static Bullet mesh (game/world/level.cpp) and a baked depth-map collider
(content/colliders/blob_monster.colliders). One box per model, so each collider's axis maps see one
convex solid (a ring of walls in one model would read as solid inside from the side views).

The street inside them: x in [-STREET_X, STREET_X], z in [STREET_Z_SOUTH, STREET_Z_NORTH]; the north
front stands 2.55 m behind the wall the monster coats (z 3.75 .. 4.25). The scene's camera bounds
(content/scenes/blob_monster.json) keep the player 0.4 m inside these faces."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = os.path.join(ROOT, "content", "models")

STREET_X = 7.0          # inner faces of the west and east fronts (m): the crates' ring (radius <= 6 m) fits inside
STREET_Z_SOUTH = -9.5   # inner face of the south front
STREET_Z_NORTH = 6.8    # inner face of the north front: an alley behind the coat wall (z 3.75 .. 4.25) holds crates
THICKNESS = 0.6
HEIGHT = 6.0            # above the street: taller than the camera's view of them from inside
FOUNDATION = 0.2        # below the street top (y = 0), so nothing slips under
TILE = 2.5              # texture repeat (m), as the level's stone


def box(lo, hi):
    """A closed axis-aligned box as OBJ text lines: outward normals, uv in metres / TILE."""
    v, vt, vn, f = [], [], [], []
    for axis in range(3):
        for side in (0, 1):
            n = [0.0, 0.0, 0.0]
            n[axis] = 1.0 if side else -1.0
            u_axis, v_axis = [(2, 1), (0, 2), (0, 1)][axis]
            ids = []
            for cu, cv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = hi[axis] if side else lo[axis]
                p[u_axis] = hi[u_axis] if cu else lo[u_axis]
                p[v_axis] = hi[v_axis] if cv else lo[v_axis]
                v.append(p)
                vt.append([p[u_axis] / TILE, p[v_axis] / TILE])
                vn.append(n)
                ids.append(len(v))
            a, b, c, d = ids
            # Wind each face counter-clockwise seen from outside (its normal).
            e1 = [v[b - 1][i] - v[a - 1][i] for i in range(3)]
            e2 = [v[c - 1][i] - v[a - 1][i] for i in range(3)]
            g = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            if sum(g[i] * n[i] for i in range(3)) < 0:
                b, d = d, b
            f += [(a, b, c), (a, c, d)]
    return v, vt, vn, f


def write(name, comment, lo, hi):
    v, vt, vn, f = box(lo, hi)
    path = os.path.join(MODELS, name)
    with open(path, "w") as out:
        out.write("# " + comment + " (scripts/blob_street_walls.py)\n")
        for p in v:
            out.write("v %.4f %.4f %.4f\n" % tuple(p))
        for t in vt:
            out.write("vt %.4f %.4f\n" % tuple(t))
        for n in vn:
            out.write("vn %.1f %.1f %.1f\n" % tuple(n))
        for a, b, c in f:
            out.write("f %d/%d/%d %d/%d/%d %d/%d/%d\n" % (a, a, a, b, b, b, c, c, c))
    return path


def main():
    x, zs, zn, t, h, y0 = STREET_X, STREET_Z_SOUTH, STREET_Z_NORTH, THICKNESS, HEIGHT, -FOUNDATION
    written = [
        write("blob_front_west.obj", "blob street: the west building front", [-x - t, y0, zs - t], [-x, h, zn + t]),
        write("blob_front_east.obj", "blob street: the east building front", [x, y0, zs - t], [x + t, h, zn + t]),
        write("blob_front_south.obj", "blob street: the south building front", [-x, y0, zs - t], [x, h, zs]),
        write("blob_front_north.obj", "blob street: the north building front", [-x, y0, zn], [x, h, zn + t]),
    ]
    print("blob_street_walls: wrote " + ", ".join(os.path.relpath(p, ROOT) for p in written))


if __name__ == "__main__":
    main()
