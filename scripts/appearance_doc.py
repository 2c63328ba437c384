#!/usr/bin/env python3
"""Writes docs/appearance.md (issue 36 item 4): what each appearance knob (kernel, k_r, lambda,
depth filter, foam rate) buys and costs, per water renderer, with every figure from this run.

    /usr/bin/python3 scripts/appearance_doc.py --fluiddemo build/dev/game/fluiddemo \
        [--out docs/appearance.md] [--images docs/images] [--quick]

Needs Debian's python3 with numpy and matplotlib (no pip). Deterministic inputs (seeded numpy
generators); timings vary with the machine's load, which the page prints beside them.

What it does:
  1. writes the particle sets it needs as .xyz into a temporary directory: a jittered flat pool,
     a ball, a one-particle-thick sheet, two thin jets (one and two-by-two particles wide), and
     2,500 / 13,000 / 50,000 particles grown from tests/data/fountain.xyz for timing;
  2. the mesh renderer: `fluiddemo mesh --in SET --out X.ply` per kernel configuration; from the
     .ply (numpy): the RMS angle of the pool's top vertex normals from vertical, the ball's
     radius error, components and through-holes (genus, Euler characteristic) of the sheet and
     jets, volumes by the divergence theorem;
  3. the image renderers (screen_space, raycast, voxel): `fluiddemo render --silhouette` masks of
     the same sets against `--method none` (the backdrop alone): the ball's radius from the mask's
     area, components of the water mask and enclosed background holes, area change (the image
     renderers' stand-in for volume);
  4. the screen_space flat pool normals and the filter step test from the GL test
     gl_screen_space_aniso (its printed figures, run here);
  5. ms per frame at 2.5k / 13k / 50k particles per renderer and configuration (interleaved);
  6. foam off / on: `fluiddemo smoke` on copies of the fountain scene with the foam rates set;
  7. pictures: the fountain tour replay's frame after a blast, per renderer and kernel, and the
     two depth filters; the foam frames; the silhouette masks (docs/images/appearance_*.png).
Hand-written prose: tests/bench/appearance_docs_*.md; the tables go between them.

The pure pieces (PLY reader, welding, components / holes / volume, mask labelling, the
continuum iso radius) are tested by tests/scripts/test_appearance_doc.py.
"""
import argparse
import collections
import json
import math
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
TEMPLATES = ROOT / "tests" / "bench"
FOV_Y_DEG = 45.0  # fluiddemo render's perspective (game/commands/render_command.cpp)

# --------------------------------------------------------------------------------------------
# Pure pieces (tested)
# --------------------------------------------------------------------------------------------

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "<i2", "int16": "<i2",
              "ushort": "<u2", "uint16": "<u2", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
              "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8"}


def read_ply(path):
    """A binary little-endian triangle PLY (as `fluiddemo mesh` writes) -> (vertices (n,3) float64,
    normals (n,3) or None, triangles (m,3) int64). Vertex properties of any scalar types; the face
    element one list property of triangles."""
    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if header[0] != "ply" or "format binary_little_endian 1.0" not in header:
        raise ValueError(f"{path}: not a binary little-endian PLY")
    elements = []  # (name, count, [(prop, dtype) or (prop, (count_dtype, item_dtype))])
    for line in header:
        words = line.split()
        if words and words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words and words[0] == "property":
            if words[1] == "list":
                elements[-1][2].append((words[4], (_PLY_TYPES[words[2]], _PLY_TYPES[words[3]])))
            else:
                elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
    at = end
    vertices = normals = triangles = None
    for name, count, props in elements:
        if all(not isinstance(t, tuple) for _, t in props):
            dtype = np.dtype([(p, t) for p, t in props])
            rows = np.frombuffer(data, dtype=dtype, count=count, offset=at)
            at += dtype.itemsize * count
            if name == "vertex":
                vertices = np.stack([rows[a].astype(np.float64) for a in ("x", "y", "z")], axis=1)
                if all(a in rows.dtype.names for a in ("nx", "ny", "nz")):
                    normals = np.stack([rows[a].astype(np.float64) for a in ("nx", "ny", "nz")], axis=1)
        else:
            if len(props) != 1 or name != "face":
                raise ValueError(f"{path}: unsupported element {name}")
            count_t, item_t = props[0][1]
            dtype = np.dtype([("n", count_t), ("i", item_t, 3)])
            rows = np.frombuffer(data, dtype=dtype, count=count, offset=at)
            if count and not (rows["n"] == 3).all():
                raise ValueError(f"{path}: faces other than triangles")
            triangles = rows["i"].astype(np.int64)
            at += dtype.itemsize * count
    if vertices is None or triangles is None:
        raise ValueError(f"{path}: no vertex or face element")
    return vertices, normals, triangles


def write_ply(path, vertices, triangles, normals=None):
    """The inverse of read_ply (float vertices, optional normals, uchar/uint triangle lists)."""
    v = np.asarray(vertices, dtype="<f4")
    cols = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if normals is not None:
        cols += [("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")]
    rows = np.zeros(len(v), dtype=cols)
    rows["x"], rows["y"], rows["z"] = v[:, 0], v[:, 1], v[:, 2]
    if normals is not None:
        n = np.asarray(normals, dtype="<f4")
        rows["nx"], rows["ny"], rows["nz"] = n[:, 0], n[:, 1], n[:, 2]
    faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<u4", 3)])
    faces["n"] = 3
    faces["i"] = np.asarray(triangles)
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(v)}"]
    header += [f"property float {c}" for c, _ in cols]
    header += [f"element face {len(faces)}", "property list uchar uint vertex_indices", "end_header"]
    pathlib.Path(path).write_bytes(("\n".join(header) + "\n").encode() + rows.tobytes() + faces.tobytes())


def weld(vertices, triangles, tolerance):
    """Merges vertices closer than about `tolerance` (same cell of a lattice of that edge) ->
    (vertices, triangles) with shared indices; degenerate triangles dropped."""
    keys = np.round(np.asarray(vertices) / tolerance).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    t = inverse[np.asarray(triangles)]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return np.asarray(vertices)[first], t[keep]


def _union_find_components(n, pairs):
    parent = np.arange(n)

    def find(a):
        root = a
        while parent[root] != root:
            root = parent[root]
        while parent[a] != root:
            parent[a], a = root, parent[a]
        return root

    for a, b in pairs:
        ra, rb = find(int(a)), find(int(b))
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return np.array([find(i) for i in range(n)])


def mesh_topology(vertices, triangles):
    """Components, boundary and non-manifold edges and through-holes of a triangle mesh with shared
    vertex indices. Per component χ = V − E + F; a closed orientable component of genus g has
    χ = 2 − 2g, so its holes (tunnels through it) are g = (2 − χ)/2. Returns a dict: components,
    boundary_edges, nonmanifold_edges, holes (summed over closed components), genus (per closed
    component), open_components."""
    t = np.asarray(triangles, dtype=np.int64)
    if len(t) == 0:
        return dict(components=0, boundary_edges=0, nonmanifold_edges=0, holes=0, genus=[], open_components=0)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    unique_edges, edge_count = np.unique(edges, axis=0, return_counts=True)
    used = np.unique(t)
    label = _union_find_components(int(t.max()) + 1, unique_edges)
    comp_of_vertex = label[used]
    comps = np.unique(comp_of_vertex)
    v_per = collections.Counter(comp_of_vertex.tolist())
    e_comp = label[unique_edges[:, 0]]
    e_per = collections.Counter(e_comp.tolist())
    f_per = collections.Counter(label[t[:, 0]].tolist())
    boundary_comp = collections.Counter(e_comp[edge_count == 1].tolist())
    genus, open_components = [], 0
    for c in comps.tolist():
        chi = v_per[c] - e_per[c] + f_per[c]
        if boundary_comp[c]:
            open_components += 1
        else:
            genus.append((2 - chi) // 2)
    return dict(components=len(comps), boundary_edges=int((edge_count == 1).sum()),
                nonmanifold_edges=int((edge_count > 2).sum()), holes=int(sum(genus)), genus=genus,
                open_components=open_components)


def mesh_volume(vertices, triangles):
    """Enclosed volume by the divergence theorem: Σ v0 · (v1 × v2) / 6 (outward-oriented triangles)."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles)
    return float(np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6.0)


def vertex_normals(vertices, triangles):
    """Area-weighted vertex normals (for meshes written without normals)."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles)
    face = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, t[:, k], face)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)


def rms_angle_from_vertical_deg(normals):
    n = np.asarray(normals, dtype=np.float64)
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    angle = np.degrees(np.arccos(np.clip(n[:, 1], -1.0, 1.0)))
    return float(np.sqrt(np.mean(angle ** 2))) if len(angle) else float("nan")


def read_surface_csv(path):
    """`fluiddemo render --surface-out` CSV -> (points (n,3), normals (n,3)), world space."""
    lines = pathlib.Path(path).read_text().splitlines()[1:]
    if not lines:
        return np.zeros((0, 3)), np.zeros((0, 3))
    rows = np.loadtxt(lines, delimiter=",", ndmin=2)
    return rows[:, 2:5], rows[:, 5:8]


def pool_top_mask(points, pool, margin):
    """The points on the pool's upper half and at least `margin` inside its x/z sides: its top,
    for the mesh's vertices and the image renderers' first surface alike."""
    lo, hi = pool.min(0), pool.max(0)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return (p[:, 1] > 0.5 * (lo[1] + hi[1])) & (p[:, 0] > lo[0] + margin) & (p[:, 0] < hi[0] - margin) \
        & (p[:, 2] > lo[2] + margin) & (p[:, 2] < hi[2] - margin)


def pool_top_normal_rms(points, normals, pool, margin):
    """RMS angle from vertical (degrees) of the normals over the pool's top (pool_top_mask) ->
    (rms, count)."""
    top = pool_top_mask(points, pool, margin)
    return rms_angle_from_vertical_deg(np.asarray(normals).reshape(-1, 3)[top]), int(top.sum())


def label_mask(mask, diagonal):
    """Connected components of a boolean image (4-neighbours, or 8 with `diagonal`) ->
    (labels int array, 0 = outside the mask; count). Breadth-first, pure Python."""
    mask = np.asarray(mask, dtype=bool)
    h, w = mask.shape
    labels = np.zeros((h, w), dtype=np.int32)
    steps = [(-1, 0), (1, 0), (0, -1), (0, 1)]
    if diagonal:
        steps += [(-1, -1), (-1, 1), (1, -1), (1, 1)]
    count = 0
    flat = mask.tolist()
    lab = labels.tolist()
    for y0 in range(h):
        row = flat[y0]
        for x0 in range(w):
            if not row[x0] or lab[y0][x0]:
                continue
            count += 1
            lab[y0][x0] = count
            queue = collections.deque([(y0, x0)])
            while queue:
                y, x = queue.popleft()
                for dy, dx in steps:
                    yy, xx = y + dy, x + dx
                    if 0 <= yy < h and 0 <= xx < w and flat[yy][xx] and not lab[yy][xx]:
                        lab[yy][xx] = count
                        queue.append((yy, xx))
    return np.array(lab, dtype=np.int32), count


def mask_topology(mask):
    """Water components (8-connected) and holes: background regions (4-connected, the dual
    connectivity) that touch no image border, i.e. enclosed by water."""
    mask = np.asarray(mask, dtype=bool)
    _, components = label_mask(mask, diagonal=True)
    back, n_back = label_mask(~mask, diagonal=False)
    border = set(np.unique(np.concatenate([back[0], back[-1], back[:, 0], back[:, -1]])).tolist()) - {0}
    return components, n_back - len(border)


def kernel_value(r, rc):
    """The mesh's and ray caster's field per particle: f = (u − 1/2)², u = r²/(2 Rc²), 0 beyond Rc."""
    u = np.asarray(r, dtype=np.float64) ** 2 / (2.0 * rc * rc)
    return np.where(u < 0.5, (u - 0.5) ** 2, 0.0)


def continuum_field(s, ball_radius, density, rc, samples=4000):
    """The isotropic field at distance s from the centre of a uniform ball of particles
    (`density` per unit volume): ∫ k(r) · (area of the sphere of radius r about the point that
    lies inside the ball) dr · density."""
    r = (np.arange(samples) + 0.5) * (rc / samples)
    if s < 1e-12:
        inside = np.where(r < ball_radius, 4.0 * np.pi * r * r, 0.0)
    else:
        c = np.clip((s * s + r * r - ball_radius * ball_radius) / (2.0 * s * r), -1.0, 1.0)
        inside = 2.0 * np.pi * r * r * (1.0 - c)
    return float(density * np.sum(kernel_value(r, rc) * inside) * (rc / samples))


def continuum_iso_radius(ball_radius, spacing, rc, threshold):
    """Where the continuum field of a uniform ball (one particle per spacing³) falls to the iso
    value: the radius an exact isotropic surface of that ball would have (bisection)."""
    density = 1.0 / spacing ** 3
    lo, hi = 0.0, ball_radius + rc
    if continuum_field(lo, ball_radius, density, rc) < threshold:
        return float("nan")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if continuum_field(mid, ball_radius, density, rc) > threshold:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def sphere_radius_from_mask_area(area_px, distance, height_px, fov_y_deg=FOV_Y_DEG):
    """A sphere centred on the view axis at `distance` covers a disc of angular radius asin(R/D):
    its radius in pixels is tan(α) / tan(fov/2) · H/2. Inverts that for the mask's area."""
    r_px = math.sqrt(area_px / math.pi)
    alpha = math.atan(r_px * math.tan(math.radians(fov_y_deg) / 2.0) / (height_px / 2.0))
    return distance * math.sin(alpha)


# --------------------------------------------------------------------------------------------
# Particle sets
# --------------------------------------------------------------------------------------------

D = 1.0  # particle spacing of the figure sets
JITTER = 0.15  # uniform jitter, ± this many spacings per axis (the GL test's flat pool)


def _jitter(rng, points):
    return points + rng.uniform(-JITTER * D, JITTER * D, size=points.shape)


def figure_sets():
    """name -> particles (n,3), the figure sets at spacing D, each from its own seed."""
    sets = {}
    g = np.stack(np.meshgrid(np.arange(24), np.arange(4), np.arange(24), indexing="ij"), -1).reshape(-1, 3)
    sets["pool"] = _jitter(np.random.default_rng(3), g * D)
    a = np.arange(-8, 9)
    g = np.stack(np.meshgrid(a, a, a, indexing="ij"), -1).reshape(-1, 3).astype(np.float64)
    g = g[np.linalg.norm(g, axis=1) <= 8.0]
    sets["ball"] = _jitter(np.random.default_rng(4), g * D)
    g = np.stack(np.meshgrid(np.arange(40), np.arange(40), [0], indexing="ij"), -1).reshape(-1, 3)
    sets["sheet"] = _jitter(np.random.default_rng(5), g * D)
    g = np.stack([np.arange(60), np.zeros(60), np.zeros(60)], -1)
    sets["jet1"] = _jitter(np.random.default_rng(6), g * D)
    g = np.stack(np.meshgrid(np.arange(60), [0, 1], [0, 1], indexing="ij"), -1).reshape(-1, 3)
    sets["jet2"] = _jitter(np.random.default_rng(7), g * D)
    for k in sets:
        sets[k] = sets[k].astype(np.float64)
    return sets


SET_WORDS = {
    "pool": "flat pool, 24 × 4 × 24",
    "ball": "ball, radius 8 d",
    "sheet": "sheet, 40 × 40 × 1",
    "jet1": "jet, 60 × 1 × 1",
    "jet2": "jet, 60 × 2 × 2",
}


def timing_sets(counts):
    """The bench_fluid_render sets: tests/data/fountain.xyz's first 2500 particles; more: copies
    tiled on a square grid in x/z (cells 1.2 × its extent). File units (Rc = 3)."""
    base = np.loadtxt(ROOT / "tests" / "data" / "fountain.xyz")
    lo, hi = base.min(0), base.max(0)
    cell = (hi - lo) * 1.2
    out = {}
    for n in counts:
        side = int(math.ceil(math.sqrt(n / len(base))))
        parts, have, t = [], 0, 0
        while have < n:
            k = min(len(base), n - have)
            parts.append(base[:k] + np.array([(t % side) * cell[0], 0.0, (t // side) * cell[2]]) - lo)
            have += k
            t += 1
        out[n] = np.vstack(parts)
    return out


def write_xyz(path, points):
    np.savetxt(path, points, fmt="%.6f")


# --------------------------------------------------------------------------------------------
# Running fluiddemo
# --------------------------------------------------------------------------------------------

ENV = dict(os.environ, SDL_VIDEODRIVER="offscreen", SDL_AUDIODRIVER="dummy")
LOG = []  # commands run, for --verbose


def run(cmd, check=True, timeout=1800):
    LOG.append(" ".join(map(str, cmd)))
    done = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=ENV, timeout=timeout)
    if check and done.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")
    return done


def load_average():
    return " ".join(pathlib.Path("/proc/loadavg").read_text().split()[:3])


def help_options(fluiddemo, sub):
    text = run([fluiddemo, sub, "--help"]).stdout
    return set(re.findall(r"(--[a-z][a-z0-9-]*)", text)), text


class Kernel:
    """One configuration of the appearance knobs (what fluiddemo's --kernel ... flags say)."""

    def __init__(self, key, label, kernel="isotropic", kr=4.0, lam=0.9, ss_filter="bilateral"):
        self.key, self.label, self.kernel, self.kr, self.lam, self.ss_filter = key, label, kernel, kr, lam, ss_filter

    def flags(self, options):
        """The flags for a subcommand with these `options`; None when it lacks one this needs."""
        out = []
        if self.kernel == "anisotropic":
            if "--kernel" not in options:
                return None
            out += ["--kernel", "anisotropic"]
            for flag, value in (("--kr", self.kr), ("--ks", 1), ("--kn", 25), ("--lambda", self.lam)):
                if flag not in options:
                    return None
                out += [flag, f"{value:g}"]
        elif "--kernel" in options:
            out += ["--kernel", "isotropic"]
        if self.ss_filter != "bilateral":
            if "--ss-filter" not in options:
                return None
            out += ["--ss-filter", self.ss_filter]
        return out


def kernel_configs(quick):
    ks = [Kernel("iso", "isotropic"), Kernel("aniso", "anisotropic (k_r 4, λ 0.9)", "anisotropic")]
    if not quick:
        ks += [Kernel("kr2", "anisotropic, k_r 2", "anisotropic", kr=2.0),
               Kernel("kr8", "anisotropic, k_r 8", "anisotropic", kr=8.0),
               Kernel("lam0", "anisotropic, λ 0", "anisotropic", lam=0.0)]
    return ks


def filter_configs(quick):
    ks = [Kernel("nr_aniso", "narrow_range, anisotropic", "anisotropic", ss_filter="narrow_range")]
    if not quick:
        ks.insert(0, Kernel("nr_iso", "narrow_range, isotropic", ss_filter="narrow_range"))
    return ks


IMAGE_METHODS = ["screen_space", "raycast", "voxel"]
STRETCHED = re.compile(r"anisotropic kernels: (\d+) of (\d+) stretched")
MESH_STRETCHED = re.compile(r"anisotropic kernels\s+(\d+) of (\d+) stretched, ([\d.]+) ms")


def render_stage_ms(stdout):
    """Sum of a `fluiddemo render` run's per-frame stages (the top-level ones: anisotropy CPU,
    extraction, upload, draw; not the spacing estimate or the voxel draw's own sub-stages), and the
    anisotropy pass's ms alone."""
    total, aniso = 0.0, 0.0
    for line in stdout.splitlines():
        m = re.match(r"^  (\S[^\n]*?)\s+(-?[\d.]+) ms(?: \(CPU\))?$", line)
        if not m or m.group(1).startswith(("spacing estimate", "all frames", "GPU memory")):
            continue
        total += float(m.group(2))
        if m.group(1).startswith("anisotropy"):
            aniso += float(m.group(2))
    return total, aniso


# --------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------


def mesh_figures(fluiddemo, mesh_options, sets, paths, tmp, configs):
    """config key -> set name -> dict of figures (or None: not available)."""
    out = {}
    ball = sets["ball"]
    centre = ball.mean(0)
    pool = sets["pool"]
    for cfg in configs:
        flags = cfg.flags(mesh_options)
        out[cfg.key] = None if flags is None else {}
        if flags is None:
            continue
        for name, path in paths.items():
            ply = tmp / f"mesh_{cfg.key}_{name}.ply"
            done = run([fluiddemo, "mesh", "--in", path, "--out", ply, "--rc", 2 * D, "--cube", 0.5 * D,
                        "--threshold", 0.2, "--force", "--stats", *flags])
            v, n, t = read_ply(ply)
            vol = mesh_volume(v, t)
            wv, wt = weld(v, t, 1e-4 * D)
            st = MESH_STRETCHED.search(done.stdout)
            fig = dict(volume=vol, topology=mesh_topology(wv, wt), triangles=len(t),
                       stretched=(int(st.group(1)), int(st.group(2))) if st else None)
            if n is None:
                n = vertex_normals(wv, wt)
                v = wv
            if name == "pool":
                fig["normal_rms"], fig["top_vertices"] = pool_top_normal_rms(v, n, pool, 3.0 * D)
            if name == "ball":
                r = np.linalg.norm(v - centre, axis=1)
                fig["radius_mean"] = float(r.mean())
                fig["radius_rms_about_mean"] = float(r.std())
            out[cfg.key][name] = fig
    return out


def camera_for(name, points):
    """Eye, look-at and distance per set for the masks: the ball from 7 radii (+z), the sheet nearly
    face-on (+z), the jets from the side (+z); the eye just above the backdrop's floor
    (render_command.cpp / backdrop.cpp: floor at min(lo.y, 0) − 3 × radius), so every ray through
    the water climbs and meets the wall or the sky, never the floor (`--method none` draws the
    floor over the wall without a depth test: below the horizon it differs from the renderers'
    backdrop)."""
    lo, hi = points.min(0), points.max(0)
    c = 0.5 * (lo + hi)
    dist = {"ball": 56.0, "sheet": 60.0}.get(name, 85.0) * D
    if name == "ball":
        c = points.mean(0)
    floor_y = min(lo[1], 0.0) - 3.0 * 0.65 * D
    eye = np.array([c[0], floor_y + 0.5 * D, c[2] + dist])
    return eye, c, float(np.linalg.norm(eye - c))


MASK_SIZE = 400


def ascending_rays(eye, look, width, height, fov_y_deg=FOV_Y_DEG):
    """Pixels (row 0 at the top) whose view ray climbs: glm::lookAt with up +y, perspective fov."""
    f = (look - eye) / np.linalg.norm(look - eye)
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    t = math.tan(math.radians(fov_y_deg) / 2.0)
    x = ((np.arange(width) + 0.5) / width * 2.0 - 1.0) * t * width / height
    y = (1.0 - (np.arange(height) + 0.5) / height * 2.0) * t
    dy = f[1] + x[None, :] * r[1] + y[:, None] * u[1]
    return dy > 1e-3


def read_png(path):
    import matplotlib.image as mpimg
    return mpimg.imread(str(path))[:, :, :3]


def silhouette_mask(image, backdrop, valid):
    """Water: pixels differing from the backdrop alone by more than 6/255 (RGB summed), among the
    `valid` ones."""
    return (np.abs(image - backdrop).sum(axis=2) > 6.0 / 255.0) & valid


def pool_camera(points):
    """The flat pool seen from 40° above its middle, the whole top in view."""
    lo, hi = points.min(0), points.max(0)
    look = np.array([0.5 * (lo[0] + hi[0]), hi[1], 0.5 * (lo[2] + hi[2])])
    eye = look + np.array([0.0, 20.0 * D, 24.0 * D])
    return eye, look


def pool_surface_figures(fluiddemo, method, cfg, flags, pool, path, tmp):
    """The renderer's own first-surface normals over the pool's top (`fluiddemo render
    --surface-out`): dict(normal_rms, pixels, png), or None when the binary refuses."""
    eye, look = pool_camera(pool)
    png = tmp / f"pool_{method}_{cfg.key}.png"
    csv = tmp / f"pool_{method}_{cfg.key}.csv"
    done = run([fluiddemo, "render", "--in", path, "--method", method, "--out", png, "--surface-out", csv,
                "--force", "--width", MASK_SIZE, "--height", MASK_SIZE, "--radius", 0.65 * D,
                "--camera", ",".join(f"{x:.6g}" for x in eye), "--look-at", ",".join(f"{x:.6g}" for x in look),
                *flags], check=False)
    if done.returncode != 0:
        return None
    points, normals = read_surface_csv(csv)
    rms, pixels = pool_top_normal_rms(points, normals, pool, 3.0 * D)
    m = STRETCHED.search(done.stdout)
    return dict(normal_rms=rms, pixels=pixels, png=png, dropped=0,
                stretched=(int(m.group(1)), int(m.group(2))) if m else None)


def image_figures(fluiddemo, render_options, sets, paths, tmp, configs_by_method):
    """method -> config key -> set name -> dict (or None: the binary refuses or ignores the
    combination)."""
    out, backdrops, cams, valid = {}, {}, {}, {}
    for name, path in paths.items():
        if name == "pool":
            continue
        eye, look, dist = camera_for(name, sets[name])
        cams[name] = (eye, look, dist)
        png = tmp / f"none_{name}.png"
        run([fluiddemo, "render", "--in", path, "--method", "none", "--out", png, "--force", "--silhouette",
             "--width", MASK_SIZE, "--height", MASK_SIZE, "--radius", 0.65 * D,
             "--camera", ",".join(f"{x:.6g}" for x in eye), "--look-at", ",".join(f"{x:.6g}" for x in look)])
        backdrops[name] = read_png(png)
        valid[name] = ascending_rays(eye, look, MASK_SIZE, MASK_SIZE)
    for method, configs in configs_by_method.items():
        out[method] = {}
        for cfg in configs:
            flags = cfg.flags(render_options)
            if flags is None:
                out[method][cfg.key] = None
                continue
            res = {}
            for name in cams:
                eye, look, dist = cams[name]
                png = tmp / f"mask_{method}_{cfg.key}_{name}.png"
                done = run([fluiddemo, "render", "--in", paths[name], "--method", method, "--out", png, "--force",
                            "--silhouette", "--width", MASK_SIZE, "--height", MASK_SIZE, "--radius", 0.65 * D,
                            "--camera", ",".join(f"{x:.6g}" for x in eye),
                            "--look-at", ",".join(f"{x:.6g}" for x in look), *flags], check=False)
                if done.returncode != 0:
                    res = None
                    break
                mask = silhouette_mask(read_png(png), backdrops[name], valid[name])
                comps, holes = mask_topology(mask)
                m = STRETCHED.search(done.stdout)
                dropped = re.search(r"dropped (\d+)", done.stdout)
                fig = dict(area=int(mask.sum()), components=comps, holes=holes, png=png,
                           stretched=(int(m.group(1)), int(m.group(2))) if m else None,
                           dropped=int(dropped.group(1)) if dropped else 0,
                           touches_edge=bool(mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any()))
                if name == "ball":
                    fig["radius"] = sphere_radius_from_mask_area(mask.sum(), dist, MASK_SIZE)
                res[name] = fig
            if res is not None:
                res["pool"] = pool_surface_figures(fluiddemo, method, cfg, flags, sets["pool"], paths["pool"], tmp)
                if res["pool"] is None:
                    res = None
            out[method][cfg.key] = res
    # A kernel the renderer ignores: no "stretched" note and the very same masks as isotropic.
    for method in out:
        iso = out[method].get("iso")
        for key, res in out[method].items():
            if key == "iso" or res is None or iso is None:
                continue
            cfg = next(c for c in configs_by_method[method] if c.key == key)
            if cfg.kernel != "anisotropic":
                continue
            noted = any(f["stretched"] for f in res.values())
            same = all(np.array_equal(read_png(res[n]["png"]), read_png(iso[n]["png"])) for n in res)
            if not noted and same:
                out[method][key] = "ignored"
    return out


def gl_test_figures(gl_test):
    """Runs gl_screen_space_aniso (its printed figures) -> (stdout lines kept, flat pool dict)."""
    if not gl_test or not pathlib.Path(gl_test).exists():
        return None, None
    done = run([gl_test], check=False)
    lines = [l for l in done.stdout.splitlines() if l and not l.startswith(("[", "Running main", "Note:"))]
    pool = {}
    for l in lines:
        m = re.match(r"\s*(\d+) bilateral rounds: isotropic ([\d.]+) deg .*anisotropic ([\d.]+) deg", l)
        if m:
            pool[int(m.group(1))] = (float(m.group(2)), float(m.group(3)))
    status = "passed" if done.returncode == 0 else f"FAILED (exit {done.returncode})"
    return (lines, status), pool


# --------------------------------------------------------------------------------------------
# Timing
# --------------------------------------------------------------------------------------------


def timing(fluiddemo, mesh_options, render_options, tpaths, configs_by_method, reps, frames, mesh_reps):
    """(method, config key, count) -> dict(ms, aniso_ms) or None (not available). Each repetition
    runs every configuration of a size once, in an order rotated per repetition; the smaller of the
    repetitions is kept (the least disturbed by the other jobs on the machine)."""
    jobs = []
    for method, configs in configs_by_method.items():
        for cfg in configs:
            jobs.append((method, cfg))
    results = {}
    for count, path in tpaths.items():
        for rep in range(reps):
            order = jobs[rep % len(jobs):] + jobs[:rep % len(jobs)]
            if rep % 2:
                order = order[::-1]
            for method, cfg in order:
                key = (method, cfg.key, count)
                if method == "mesh":
                    flags = cfg.flags(mesh_options)
                    if flags is None:
                        results[key] = None
                        continue
                    done = run([fluiddemo, "mesh", "--in", path, "--out", pathlib.Path(path).with_suffix(".ply"),
                                "--force", "--rc", 3, "--cube", 0.75, "--reps", mesh_reps, "--stats", *flags])
                    m = re.search(r"median ([\d.]+) ms", done.stdout)
                    a = MESH_STRETCHED.search(done.stdout)
                    aniso = float(a.group(3)) if a else None
                    ms = float(m.group(1)) + (aniso or 0.0)
                else:
                    flags = cfg.flags(render_options)
                    if flags is None:
                        results[key] = None
                        continue
                    done = run([fluiddemo, "render", "--in", path, "--method", method, "--frames", frames,
                                "--out", pathlib.Path(path).with_suffix(f".{method}.png"), "--force", *flags],
                               check=False)
                    if done.returncode != 0:
                        results[key] = None
                        continue
                    ms, aniso = render_stage_ms(done.stdout)
                    if cfg.kernel == "anisotropic" and not STRETCHED.search(done.stdout):
                        results[key] = "ignored"
                        continue
                prev = results.get(key)
                if isinstance(prev, dict) and prev["ms"] <= ms:
                    continue
                results[key] = dict(ms=ms, aniso_ms=aniso)
    return results


# --------------------------------------------------------------------------------------------
# Foam and pictures
# --------------------------------------------------------------------------------------------

FOAM_CAMERA = {"position": [0.3, 3.4, 3.6], "pitch_degrees": -30}


def foam_runs(fluiddemo, tmp, frames, reps, width, height):
    """Copies of content/scenes/fountain.json with the foam rates set (and a camera over the
    dish), `fluiddemo smoke` for `frames` frames each: ms per frame (the smaller of `reps`
    interleaved runs) and the last frame."""
    scene = json.loads((ROOT / "content" / "scenes" / "fountain.json").read_text())
    rates = [("off", 0, 0), ("default", 60, 20), ("double", 120, 40)]
    out = {k: dict(ta=a, wc=b, ms=None, png=None) for k, a, b in rates}
    for key, a, b in rates:
        s = json.loads(json.dumps(scene))
        s["effects"]["sprite_particles"].update(foam_trapped_air_rate=a, foam_wave_crest_rate=b)
        s["camera"].update(FOAM_CAMERA)
        (tmp / f"foam_{key}.json").write_text(json.dumps(s, indent=1))
    for rep in range(reps):
        order = rates if rep % 2 == 0 else rates[::-1]
        for key, _, _ in order:
            d = tmp / f"foam_{key}_{rep}"
            d.mkdir(exist_ok=True)
            done = run([fluiddemo, "smoke", "--scene", tmp / f"foam_{key}.json", "--frames", frames,
                        "--width", width, "--height", height, "--out", d])
            ms = float(re.search(r"([\d.]+) ms/frame", done.stdout).group(1))
            if out[key]["ms"] is None or ms < out[key]["ms"]:
                out[key]["ms"] = ms
            out[key]["png"] = d / f"foam_{key}.png"
            out[key].setdefault("pngs", []).append(d / f"foam_{key}.png")
    off = read_png(out["off"]["png"])
    for key in out:
        img = read_png(out[key]["png"])
        out[key]["pixels"] = int((np.abs(img - off).sum(axis=2) > 30.0 / 255.0).sum())
        pngs = out[key]["pngs"]
        out[key]["repeatable"] = all(np.array_equal(read_png(p), img) for p in pngs)
    return out


def replay_pictures(fluiddemo, tmp, shots, step, width, height):
    """(label, method, kernel, filter) -> PNG of the fountain tour's frame after `step` steps."""
    out = {}
    replay = ROOT / "content" / "replays" / "fountain_tour.replay"
    for key, method, kernel, ss_filter in shots:
        png = tmp / f"replay_{key}.png"
        sets = ["--set", "graphics.preset=high", "--set", f"fluid_surface.method={method}",
                "--set", f"fluid_surface.kernel={kernel}", "--set", f"fluid_surface.ss_filter={ss_filter}"]
        t0 = time.time()
        done = run([fluiddemo, "replay", replay, "--headless", "--no-ui", "--width", width, "--height", height,
                    "--frames", step, "--screenshot-at", f"{step}:{png}", "--force", *sets], check=False)
        out[key] = dict(png=png if done.returncode == 0 and png.exists() else None, seconds=time.time() - t0,
                        error=None if done.returncode == 0 else (done.stderr.strip().splitlines() or ["?"])[-1],
                        checkpoint=(re.search(r"checkpoints: [^\n]*", done.stdout) or [None])[0])
    return out


def crop(image, box):
    """box: (x0, y0, x1, y1) as fractions of the width and height."""
    if image is None:
        return None
    h, w = image.shape[:2]
    return image[int(box[1] * h):int(box[3] * h), int(box[0] * w):int(box[2] * w)]


def crop_to_water(image, margin=12):
    """The silhouette image cut to its dark (water) pixels' bounding box and a margin (display only)."""
    ys, xs = np.nonzero(image.max(axis=2) < 0.2)
    if len(ys) == 0:
        return image
    h, w = image.shape[:2]
    return image[max(ys.min() - margin, 0):min(ys.max() + margin + 1, h), max(xs.min() - margin, 0):min(xs.max() + margin + 1, w)]


REPLAY_CROP = (0.27, 0.11, 0.73, 0.70)  # the fountain in the tour's frame after step 560


def replay_montages(images, pics, pic_step):
    """appearance_kernels.png and appearance_filter.png from the replay pictures -> (pairs that are
    pixel-identical, [(a, b, pixels differing, pixels)])."""
    def full(key):
        return read_png(pics[key]["png"]) if pics.get(key) and pics[key]["png"] else None

    def img(key):
        return crop(full(key), REPLAY_CROP)

    pictures_same, pictures_diff = [], []
    for a, b in [("mesh_iso", "mesh_aniso"), ("screen_space_iso", "screen_space_aniso"),
                 ("raycast_iso", "raycast_aniso"), ("voxel_iso", "voxel_aniso"),
                 ("screen_space_iso", "screen_space_iso_narrow"),
                 ("screen_space_aniso", "screen_space_aniso_narrow")]:
        ia, ib = full(a), full(b)
        if ia is not None and ib is not None:
            if np.array_equal(ia, ib):
                pictures_same.append((a, b))
            pictures_diff.append((a, b, int((np.abs(ia - ib).sum(axis=2) > 30.0 / 255.0).sum()), ia.shape[0] * ia.shape[1]))
    panels = []
    for method in ["mesh", "screen_space", "raycast", "voxel"]:
        for k in ("iso", "aniso"):
            key = f"{method}_{k}"
            label = f"{method}, {'isotropic' if k == 'iso' else 'anisotropic'}"
            if any(b == key for _, b in pictures_same):
                label += " (= isotropic: key not used)"
            panels.append((img(key), label))
    montage(images / "appearance_kernels.png", panels, 2,
            f"fountain tour after step {pic_step}, cropped: fluid_surface.kernel")
    montage(images / "appearance_filter.png",
            [(img("screen_space_iso"), "screen_space, isotropic, bilateral"),
             (img("screen_space_iso_narrow"), "screen_space, isotropic, narrow_range"),
             (img("screen_space_aniso"), "screen_space, anisotropic, bilateral"),
             (img("screen_space_aniso_narrow"), "screen_space, anisotropic, narrow_range")], 2,
            f"fountain tour after step {pic_step}, cropped: fluid_surface.ss_filter")
    return pictures_same, pictures_diff


def first_blast_step(fluiddemo, tmp, frames):
    """The first step of the fountain tour with a blast (`replay --no-render --csv`, column blasts)."""
    import csv
    out = tmp / "blasts.csv"
    run([fluiddemo, "replay", ROOT / "content" / "replays" / "fountain_tour.replay", "--no-render", "--frames", frames,
         "--csv", out, "--force"])
    with open(out) as f:
        for row in csv.DictReader(f):
            if float(row.get("blasts") or 0) > 0:
                return int(row["step"])
    return None


def montage(path, panels, columns, title=None, panel_width=4.0):
    """panels: [(image array or None, label)], row-major; labelled, no axes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = (len(panels) + columns - 1) // columns
    first = next(img for img, _ in panels if img is not None)
    aspect = first.shape[0] / first.shape[1]
    fig, axes = plt.subplots(rows, columns, figsize=(panel_width * columns, panel_width * aspect * rows + 0.45 * rows),
                             squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (img, label) in zip(axes.flat, panels):
        if img is not None:
            ax.imshow(img, interpolation="nearest")
        else:
            ax.text(0.5, 0.5, "not available", ha="center", va="center", transform=ax.transAxes)
        ax.set_title(label, fontsize=10)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)


# --------------------------------------------------------------------------------------------
# The page
# --------------------------------------------------------------------------------------------


def fmt(x, digits=2, signed=False):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return f"{x:+.{digits}f}" if signed else f"{x:.{digits}f}"


def pct_change(a, b):
    return None if a is None or b is None or b == 0 else 100.0 * (a / b - 1.0)


def topo_cell(fig):
    t = fig["topology"]
    cell = f"{t['components']} / {t['holes']}"
    if t["boundary_edges"] or t["nonmanifold_edges"]:
        cell += f" (open: {t['boundary_edges']} boundary, {t['nonmanifold_edges']} non-manifold edges)"
    return cell


def stretched_cell(figs, names):
    return ", ".join(f"{figs[s]['stretched'][0]}/{figs[s]['stretched'][1]}" if figs[s].get("stretched") else "–"
                     for s in names)


def na(why):
    return f"not available ({why})"


def summary_table(ctx):
    """The page's first table: isotropic → anisotropic (defaults) per renderer, from the tables below."""
    L = ["## In short", "",
         "Isotropic → anisotropic kernels (k_r 4, λ 0.9), each renderer, from the tables below (d: particle "
         "spacing; the flat pool's normals: the mesh's vertex normals, the image renderers' own per-pixel normals "
         "read back by `fluiddemo render --surface-out`).", "",
         "| renderer | flat pool normals RMS | ball radius error | sheet holes | pieces of jet 1 wide / 2 × 2 | volume (mesh) / area (images) of the ball "
         f"| ms per frame at {ctx['counts'][1]:,} particles |",
         "|---|---|---|---|---|---|---|"]
    mid = ctx["counts"][1]
    d_rvol = ctx["r_vol"]

    def arrow(a, b, f):
        return f"{f(a)} → {f(b)}" if b is not None else f"{f(a)} → not available"

    def ms(method, key):
        r = ctx["timing"].get((method, key, mid))
        return r["ms"] if isinstance(r, dict) else None

    mesh = ctx["mesh"]
    iso, an = mesh.get("iso"), mesh.get("aniso")
    if iso:
        L.append("| mesh | " + " | ".join([
            arrow(iso["pool"]["normal_rms"], an and an["pool"]["normal_rms"], lambda x: f"{x:.2f}°"),
            arrow(iso["ball"]["radius_mean"] - d_rvol, an and an["ball"]["radius_mean"] - d_rvol, lambda x: f"{x:+.2f} d"),
            arrow(iso["sheet"]["topology"]["holes"], an and an["sheet"]["topology"]["holes"], str),
            arrow(f"{iso['jet1']['topology']['components']} / {iso['jet2']['topology']['components']}",
                  an and f"{an['jet1']['topology']['components']} / {an['jet2']['topology']['components']}", str),
            (f"{pct_change(an['ball']['volume'], iso['ball']['volume']):+.1f} %" if an else "not available"),
            arrow(ms("mesh", "iso"), ms("mesh", "aniso"), lambda x: "–" if x is None else f"{x:.1f}")]) + " |")
    for method in IMAGE_METHODS:
        figs = ctx["images"][method]
        i, a = figs.get("iso"), figs.get("aniso")
        if not isinstance(i, dict):
            continue
        a = a if isinstance(a, dict) else None
        normals = arrow(i["pool"]["normal_rms"], a and a["pool"]["normal_rms"], lambda x: f"{x:.2f}°")
        L.append(f"| {method} | {normals} | " + " | ".join([
            arrow(i["ball"]["radius"] - d_rvol, a and a["ball"]["radius"] - d_rvol, lambda x: f"{x:+.2f} d"),
            arrow(i["sheet"]["holes"], a and a["sheet"]["holes"], str),
            arrow(f"{i['jet1']['components']} / {i['jet2']['components']}",
                  a and f"{a['jet1']['components']} / {a['jet2']['components']}", str),
            (f"{pct_change(a['ball']['area'], i['ball']['area']):+.1f} %" if a else "not available"),
            arrow(ms(method, "iso"), ms(method, "aniso"), lambda x: "–" if x is None else f"{x:.1f}")]) + " |")
    L.append("")
    return L


def write_page(args, ctx):
    L = []
    head = (TEMPLATES / "appearance_docs_head.md").read_text()
    L.append(head.rstrip("\n"))
    L.append("")
    cmd = f"/usr/bin/python3 scripts/appearance_doc.py --fluiddemo {args.fluiddemo_shown}" + (" --quick" if args.quick else "")
    L.append(f"Command: `{cmd}` (commit {ctx['commit']}; {ctx['seconds'] / 60:.1f} min on this machine; "
             f"load average at the start {ctx['load_start']}, at the end {ctx['load_end']}; GL: {ctx['gl_name']}).")
    L.append("")
    sets, d_rvol, d_riso = ctx["sets"], ctx["r_vol"], ctx["r_iso"]

    L.extend(summary_table(ctx))
    # ---------------- mesh figures
    L.append("## Figures: the mesh (marching slices)")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_sets.md").read_text().rstrip("\n"))
    L.append("")
    L.append(f"Sets (spacing d = 1, jitter ±{JITTER} d uniform per axis, seeded): "
             + "; ".join(f"{SET_WORDS[k]} ({len(v):,} particles)" for k, v in sets.items())
             + f". The ball's own radius (its particles' volume, N d³ = 4/3 π R³) is R = {d_rvol:.3f} d; "
             f"the isotropic field of a uniform ball of that radius falls to T at {d_riso:.3f} d "
             f"({d_riso - d_rvol:+.3f} d: where an exact isotropic surface of it lies).")
    L.append("")
    if ctx["mesh_kernel_help"]:
        L.append(f"`fluiddemo mesh --help` on `--kernel-radius`: \"{ctx['mesh_kernel_help']}\" (here --rc 2: r = 3 d).")
        L.append("")
    L.append("Command per set and row: `fluiddemo mesh --in SET.xyz --out X.ply --rc 2 --cube 0.5 --threshold 0.2 --stats "
             "[--kernel anisotropic --kr K --ks 1 --kn 25 --lambda L]`; figures from the .ply (scripts/appearance_doc.py).")
    L.append("")
    L.append("| configuration | pool: top normals RMS from vertical | ball: radius error (mean / RMS about the mean) "
             "| sheet: components / holes | jet 1 wide | jet 2 × 2 | volume vs isotropic: pool / ball / sheet "
             "| stretched (pool, ball, sheet, jet 1, jet 2) |")
    L.append("|---|---|---|---|---|---|---|---|")
    mf = ctx["mesh"]
    iso = mf.get("iso")
    for cfg in ctx["kernel_configs"]:
        f = mf.get(cfg.key)
        if f is None:
            L.append(f"| {cfg.label} | " + " | ".join([na("this fluiddemo mesh has no --kernel")] + ["–"] * 6) + " |")
            continue
        vols = " / ".join(fmt(pct_change(f[s]["volume"], iso[s]["volume"] if iso else None), 1, True) + " %"
                          for s in ("pool", "ball", "sheet"))
        L.append(f"| {cfg.label} | {fmt(f['pool']['normal_rms'])}° ({f['pool']['top_vertices']} vertices) "
                 f"| {fmt(f['ball']['radius_mean'] - d_rvol, 3, True)} d / {fmt(f['ball']['radius_rms_about_mean'], 3)} d "
                 f"| {topo_cell(f['sheet'])} | {topo_cell(f['jet1'])} | {topo_cell(f['jet2'])} | {vols} "
                 f"| {stretched_cell(f, ('pool', 'ball', 'sheet', 'jet1', 'jet2'))} |")
    L.append("")
    L.append("Top normals: the mesher's vertex normals (the field's gradient) of the vertices above the pool's "
             "mid-height and more than 3 d inside its sides. Radius: distance of the ball's vertices from its "
             "particles' mean, against R. Components / holes: vertices welded by position (1e-4 d), components by "
             "shared edges, holes = genus (2 − χ)/2 of each closed component (χ = V − E + F), summed; "
             "a closed sheet is one component with 0 holes.")
    L.append("")

    # ---------------- image renderer figures
    L.append("## Figures: screen_space, raycast, voxel (silhouettes)")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_images.md").read_text().rstrip("\n"))
    L.append("")
    pool_eye, pool_look = (",".join(f"{x:.6g}" for x in v) for v in pool_camera(figure_sets()["pool"]))
    L.append(f"Command per set and row: `fluiddemo render --in SET.xyz --method M --silhouette --width {MASK_SIZE} "
             f"--height {MASK_SIZE} --radius 0.65 --camera E --look-at C [--kernel anisotropic --kr K --ks 1 --kn 25 "
             f"--lambda L] [--ss-filter narrow_range]`, and `--method none` (the backdrop alone) for the mask. The pool: "
             f"`fluiddemo render --in pool.xyz --method M --surface-out pool.csv --width {MASK_SIZE} --height {MASK_SIZE} "
             f"--radius 0.65 --camera {pool_eye} --look-at {pool_look} [kernel flags]` (seen from 40° above), the RMS angle "
             f"from vertical of the per-pixel normals the renderer shades with, over the pixels whose surface point lies "
             f"on the pool's upper half and 3 d inside its sides (the mesh's rule).")
    L.append("")
    L.append("| renderer | configuration | pool: top normals RMS from vertical | ball: radius error "
             "| sheet: components / holes | jet 1 wide | jet 2 × 2 "
             "| area vs isotropic: ball / sheet / jet 2 × 2 | stretched (ball, sheet, jet 1, jet 2) |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    imf = ctx["images"]
    for method in IMAGE_METHODS:
        iso = imf[method].get("iso")
        for cfg in ctx["configs_by_method"][method]:
            r = imf[method].get(cfg.key)
            if r is None or r == "ignored":
                why = "refused by this fluiddemo render" if r is None else \
                    "this fluiddemo render ignores --kernel for it: same masks, no kernels computed"
                L.append(f"| {method} | {cfg.label} | {na(why)} | – | – | – | – | – | – |")
                continue
            areas = " / ".join(
                (fmt(pct_change(r[s]["area"], iso[s]["area"]), 1, True) + " %") if isinstance(iso, dict) else "–"
                for s in ("ball", "sheet", "jet2"))
            st = stretched_cell(r, ("ball", "sheet", "jet1", "jet2"))
            dropped = [f"{s} {r[s]['dropped']:,}" for s in ("ball", "sheet", "jet1", "jet2") if r[s]["dropped"]]
            if dropped:
                st += "; records dropped: " + ", ".join(dropped)
            L.append(f"| {method} | {cfg.label} | {fmt(r['pool']['normal_rms'])}° ({r['pool']['pixels']:,} px) "
                     f"| {fmt(r['ball']['radius'] - d_rvol, 3, True)} d "
                     f"| {r['sheet']['components']} / {r['sheet']['holes']} "
                     f"| {r['jet1']['components']} / {r['jet1']['holes']} | {r['jet2']['components']} / {r['jet2']['holes']} "
                     f"| {areas} | {st} |")
    L.append("")
    L.append("Radius: the ball's mask area as a disc, turned into the radius of a sphere at the camera's distance "
             "(the view axis through its centre, 45° field of view), against R. Pixels whose view ray descends are "
             "left out of every mask (there `--method none` draws the floor over the wall, unlike the renderers). Components: 8-connected water pixels; holes: "
             "4-connected background regions touching no image border. The area change is the image renderers' "
             "stand-in for volume (a projection: it says how much thicker or thinner the water is drawn, not its volume).")
    L.append("")
    L.append("![silhouette masks](images/appearance_masks.png)")
    L.append("")
    L.append("`docs/images/appearance_masks.png`: the masks above (water dark), isotropic and anisotropic (k_r 4, λ 0.9) "
             "per renderer; columns ball, sheet face-on, jet 1 wide, jet 2 × 2 (from the side).")
    L.append("")

    # ---------------- screen_space normals from the GL test
    L.append("## Figures: screen_space normals and the filters (GL test)")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_gltest.md").read_text().rstrip("\n"))
    L.append("")
    gl_out, gl_pool = ctx["gl"]
    if gl_out is None:
        L.append(f"Not run: no GL test binary at `{args.gl_test}` (build the target gl_screen_space_aniso).")
    else:
        lines, status = gl_out
        L.append(f"Command: `{args.gl_test_shown}` ({status}), its printed figures:")
        L.append("")
        L.append("```")
        L.extend(lines)
        L.append("```")
        if gl_pool:
            L.append("")
            L.append("| renderer | flat pool top normals RMS from vertical: isotropic | anisotropic | ratio |")
            L.append("|---|---|---|---|")
            for rounds, (a, b) in sorted(gl_pool.items()):
                L.append(f"| screen_space, {rounds} bilateral rounds{' (the game’s)' if rounds == 3 else ''} "
                         f"| {a:.2f}° | {b:.2f}° | {b / a:.2f} |")
            mesh = ctx["mesh"]
            if mesh.get("iso"):
                a = mesh["iso"]["pool"]["normal_rms"]
                b = mesh["aniso"]["pool"]["normal_rms"] if mesh.get("aniso") else None
                L.append(f"| mesh (the table above) | {a:.2f}° | {fmt(b)}{'°' if b is not None else ''} "
                         f"| {fmt(b / a if b is not None else None)} |")
            imf = ctx["images"]
            for method in IMAGE_METHODS:
                i, a = imf[method].get("iso"), imf[method].get("aniso")
                if not isinstance(i, dict):
                    continue
                b = a["pool"]["normal_rms"] if isinstance(a, dict) else None
                c = i["pool"]["normal_rms"]
                L.append(f"| {method}, `fluiddemo render --surface-out` (the table above) | {c:.2f}° "
                         f"| {fmt(b)}{'°' if b is not None else ''} | {fmt(b / c if b is not None else None)} |")
    L.append("")

    # ---------------- timing
    L.append("## Cost: ms per frame")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_timing.md").read_text().rstrip("\n"))
    L.append("")
    L.append(f"Commands: `fluiddemo mesh --in SET.xyz --out X.ply --rc 3 --cube 0.75 --reps {ctx['mesh_reps']} --stats [kernel flags]` "
             f"(the warm median of the extraction plus the kernels' one pass as `--stats` reports it; all hardware threads) and `fluiddemo render --in SET.xyz --method M --frames {ctx['frames']} "
             f"[kernel flags]` (640×360, llvmpipe: software rasterisation on the CPU; the sum of the per-frame stages: "
             f"anisotropy (CPU), upload, draw). Each configuration ran {ctx['reps']} time(s), interleaved with the "
             f"others of its size; the smaller is shown. Load average before the timings {ctx['load_timing'][0]}, "
             f"after {ctx['load_timing'][1]}.")
    L.append("")
    counts = ctx["counts"]
    L.append("| renderer | configuration | " + " | ".join(f"{c:,} particles: ms (anisotropy ms)" for c in counts) + " |")
    L.append("|---|---|" + "---|" * len(counts))
    tm = ctx["timing"]
    for method, configs in ctx["timing_configs"].items():
        for cfg in configs:
            cells = []
            for c in counts:
                r = tm.get((method, cfg.key, c))
                if r is None:
                    cells.append("not available")
                elif r == "ignored":
                    cells.append("not available (kernel ignored)")
                else:
                    cells.append(f"{r['ms']:.1f}" + (f" ({r['aniso_ms']:.1f})" if r["aniso_ms"] else ""))
            L.append(f"| {method} | {cfg.label} | " + " | ".join(cells) + " |")
    L.append("")

    # ---------------- foam
    L.append("## Foam and bubbles: off / on")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_foam.md").read_text().rstrip("\n"))
    L.append("")
    foam = ctx["foam"]
    L.append(f"Command: `fluiddemo smoke --scene FOAM.json --frames {ctx['foam_frames']} --width {ctx['foam_size'][0]} "
             f"--height {ctx['foam_size'][1]} --out DIR`, FOAM.json = content/scenes/fountain.json with "
             f"`sprite_particles.foam_trapped_air_rate` / `foam_wave_crest_rate` as below and the camera "
             f"`{json.dumps(FOAM_CAMERA)}`; {ctx['foam_reps']} interleaved run(s) each, the smaller ms shown "
             f"(the whole frame: simulation, foam potentials, sprites, water, llvmpipe).")
    L.append("")
    L.append("| foam rates (trapped air / wave crest, per s) | ms per frame | pixels differing from foam off in the last frame | same frame in every run |")
    L.append("|---|---|---|---|")
    for key in ("off", "default", "double"):
        f = foam[key]
        L.append(f"| {f['ta']:g} / {f['wc']:g}{' (the default)' if key == 'default' else ''} | {f['ms']:.1f} "
                 f"| {f['pixels']:,} | {'yes' if f['repeatable'] else 'no'} |")
    L.append("")
    L.append("![foam off / on](images/appearance_foam.png)")
    L.append("")

    # ---------------- pictures
    L.append("## Pictures: the same replay frame")
    L.append("")
    pics = ctx["pictures"]
    L.append(f"Command: `fluiddemo replay content/replays/fountain_tour.replay --headless --no-ui --width {ctx['pic_size'][0]} "
             f"--height {ctx['pic_size'][1]} --frames {ctx['pic_step']} --screenshot-at {ctx['pic_step']}:X.png "
             f"--set graphics.preset=high --set fluid_surface.method=M --set fluid_surface.kernel=K "
             f"--set fluid_surface.ss_filter=F` (render-only keys: the checkpoints still gate). "
             + (f"The first explosive goes off at step {ctx['blast_step']} (`fluiddemo replay ... --no-render --csv`, "
                f"column blasts): the frame is {ctx['pic_step'] - ctx['blast_step']} steps later."
                if ctx.get("blast_step") else "No blast before this frame."))
    L.append("")
    L.append("Pixels that differ (by more than 30/255 summed over RGB) between two pictures of the same frame: "
             + "; ".join(f"`{a}` / `{b}` {n:,} of {total:,}" for a, b, n, total in ctx.get("pictures_diff", [])) + ".")
    L.append("")
    for key, p in pics.items():
        if p["png"] is None:
            L.append(f"- `{key}`: not available ({p['error']})")
    if ctx.get("pictures_note"):
        L.append(ctx["pictures_note"])
        L.append("")
    same = ctx["pictures_same"]
    for a, b in same:
        L.append(f"- `{b}` is pixel-identical to `{a}`: the game's renderer does not use that key.")
    L.append("")
    L.append("![isotropic / anisotropic per renderer](images/appearance_kernels.png)")
    L.append("")
    L.append("![bilateral / narrow range](images/appearance_filter.png)")
    L.append("")
    L.append((TEMPLATES / "appearance_docs_tail.md").read_text().rstrip("\n"))
    L.append("")
    return "\n".join(L)


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fluiddemo", required=True, help="the fluiddemo executable")
    ap.add_argument("--out", default=str(ROOT / "docs" / "appearance.md"))
    ap.add_argument("--images", default=str(ROOT / "docs" / "images"))
    ap.add_argument("--gl-test", default=None,
                    help="gl_screen_space_aniso (default: BUILD/tests/gpu/ beside BUILD/game/fluiddemo)")
    ap.add_argument("--quick", action="store_true", help="fewer configurations, sizes, frames and repetitions")
    ap.add_argument("--keep", action="store_true",
                    help="keep the temporary directory (printed), with the run's results in results.pickle")
    ap.add_argument("--page-from", metavar="PICKLE",
                    help="only rewrite --out from a kept run's results.pickle (the same run's numbers and images)")
    args = ap.parse_args(argv)
    t_start = time.time()
    fluiddemo = pathlib.Path(args.fluiddemo).resolve()
    args.fluiddemo_shown = os.path.relpath(fluiddemo, ROOT) if str(fluiddemo).startswith(str(ROOT)) else str(fluiddemo)
    if args.gl_test is None:
        args.gl_test = str(fluiddemo.parent.parent / "tests" / "gpu" / "gl_screen_space_aniso")
    gl_path = pathlib.Path(args.gl_test).resolve()
    args.gl_test_shown = os.path.relpath(gl_path, ROOT) if str(gl_path).startswith(str(ROOT)) else str(gl_path)
    if args.page_from:
        import pickle
        with open(args.page_from, "rb") as f:
            ctx = pickle.load(f)
        pathlib.Path(args.out).write_text(write_page(args, ctx))
        print(f"wrote {args.out} from {args.page_from}")
        return 0
    images = pathlib.Path(args.images)
    images.mkdir(parents=True, exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="appearance_"))
    load_start = load_average()
    commit = run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], check=False).stdout.strip() or "?"

    def say(msg):
        print(f"[{time.time() - t_start:6.0f} s] {msg}", flush=True)

    try:
        mesh_options, mesh_help = help_options(fluiddemo, "mesh")
        render_options, _ = help_options(fluiddemo, "render")
        help_lines = [l.strip() for l in mesh_help.splitlines()]
        mesh_kernel_help = next((help_lines[i + 1] for i, l in enumerate(help_lines[:-1])
                                 if l.startswith("--kernel-radius")), "")
        kcfg = kernel_configs(args.quick)
        configs_by_method = {"screen_space": kcfg + filter_configs(args.quick), "raycast": kcfg, "voxel": kcfg}
        # figure sets
        sets = figure_sets()
        paths = {}
        for name, pts in sets.items():
            paths[name] = tmp / f"{name}.xyz"
            write_xyz(paths[name], pts)
        n_ball = len(sets["ball"])
        r_vol = D * (3.0 * n_ball / (4.0 * math.pi)) ** (1.0 / 3.0)
        r_iso = continuum_iso_radius(r_vol, D, 2.0 * D, 0.2)
        say("mesh figures")
        mesh = mesh_figures(fluiddemo, mesh_options, sets, paths, tmp, kcfg)
        say("image figures")
        imgs = image_figures(fluiddemo, render_options, sets, paths, tmp, configs_by_method)
        say("GL test")
        gl = gl_test_figures(args.gl_test)
        # timing
        counts = [2500, 13000] if args.quick else [2500, 13000, 50000]
        tsets = timing_sets(counts)
        tpaths = {}
        for c, pts in tsets.items():
            tpaths[c] = tmp / f"timing_{c}.xyz"
            write_xyz(tpaths[c], pts)
        tkcfg = kernel_configs(args.quick)
        timing_configs = {"mesh": tkcfg, "screen_space": tkcfg + filter_configs(args.quick),
                          "raycast": tkcfg, "voxel": tkcfg}
        reps, frames, mesh_reps = (1, 1, 3) if args.quick else (2, 3, 5)
        say("timing")
        load_t0 = load_average()
        tm = timing(fluiddemo, mesh_options, render_options, tpaths, timing_configs, reps, frames, mesh_reps)
        load_t1 = load_average()
        # foam
        foam_frames, foam_reps = (120, 1) if args.quick else (240, 2)
        foam_size = (640, 360)
        say("foam")
        foam = foam_runs(fluiddemo, tmp, foam_frames, foam_reps, *foam_size)
        # replay pictures
        say("first blast")
        blast_step = None if args.quick else first_blast_step(fluiddemo, tmp, 900)
        pic_step, pic_size = (120, (320, 180)) if args.quick else ((blast_step or 540) + 20, (480, 270))
        shots = [("mesh_iso", "mesh", "isotropic", "bilateral"), ("mesh_aniso", "mesh", "anisotropic", "bilateral"),
                 ("screen_space_iso", "screen_space", "isotropic", "bilateral"),
                 ("screen_space_aniso", "screen_space", "anisotropic", "bilateral"),
                 ("raycast_iso", "raycast", "isotropic", "bilateral"),
                 ("raycast_aniso", "raycast", "anisotropic", "bilateral"),
                 ("voxel_iso", "voxel", "isotropic", "bilateral"), ("voxel_aniso", "voxel", "anisotropic", "bilateral"),
                 ("screen_space_iso_narrow", "screen_space", "isotropic", "narrow_range"),
                 ("screen_space_aniso_narrow", "screen_space", "anisotropic", "narrow_range")]
        say("replay pictures")
        pics = replay_pictures(fluiddemo, tmp, shots, pic_step, *pic_size)
        say("montages")
        pictures_same, pictures_diff = replay_montages(images, pics, pic_step)
        montage(images / "appearance_foam.png",
                [(read_png(foam[k]["png"]), f"foam rates {foam[k]['ta']:g} / {foam[k]['wc']:g}"
                  + (" (off)" if k == "off" else " (default)" if k == "default" else ""))
                 for k in ("off", "default", "double")], 3,
                f"fountain scene, frame {foam_frames} (fluiddemo smoke), sprite_particles foam rates", panel_width=4.5)
        mask_panels = []
        for method in IMAGE_METHODS:
            for key in ("iso", "aniso"):
                r = imgs[method].get(key)
                for name in ("ball", "sheet", "jet1", "jet2"):
                    if isinstance(r, dict):
                        mask_panels.append((crop_to_water(read_png(r[name]["png"])), f"{method} {key}: {name}"))
                    else:
                        mask_panels.append((None, f"{method} {key}: {name}"))
        montage(images / "appearance_masks.png", mask_panels, 4,
                f"silhouettes (--silhouette, {MASK_SIZE}×{MASK_SIZE}, cropped to the water)", panel_width=2.6)
        gl_renderer = "?"
        probe = run([fluiddemo, "render", "--in", paths["jet1"], "--method", "none", "--out", tmp / "probe.png",
                     "--force"], check=False)
        m = re.search(r"GL ([^\n]*)", probe.stdout)
        if m:
            gl_renderer = m.group(1)
        ctx = dict(commit=commit, seconds=time.time() - t_start, load_start=load_start, load_end=load_average(),
                   gl=gl, gl_name=gl_renderer, sets=sets, r_vol=r_vol / D, r_iso=r_iso / D, mesh=mesh, images=imgs,
                   kernel_configs=kcfg, configs_by_method=configs_by_method, mesh_kernel_help=mesh_kernel_help,
                   counts=counts, timing=tm, timing_configs=timing_configs, reps=reps, frames=frames,
                   mesh_reps=mesh_reps, load_timing=(load_t0, load_t1), foam=foam, foam_frames=foam_frames,
                   foam_reps=foam_reps, foam_size=foam_size, pictures=pics, pic_step=pic_step, pic_size=pic_size,
                   pictures_same=pictures_same, blast_step=blast_step, pictures_diff=pictures_diff)
        if args.keep:
            import pickle
            with open(tmp / "results.pickle", "wb") as f:
                pickle.dump(ctx, f)
        text = write_page(args, ctx)
        pathlib.Path(args.out).write_text(text)
        say(f"wrote {args.out}")
    finally:
        if args.keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
