#!/usr/bin/env python3
"""Static particle sets for `fluiddemo render` and docs/render.md's measured section (issue 37).

  make_render_sets.py OUT_DIR [--sizes 50000,1000000,4000000] [--seed 1] [--force]

Writes OUT_DIR/pool_<N>.xyz (a settled pool with a splash) and OUT_DIR/spray_<N>.xyz (a cloud of
spray) for each N. Both keep the same shape at every size, so the particle spacing shrinks as N
grows (spacing = (pool volume / N)^(1/3)) and the pictures of one view compare across sizes:
  pool:  a 4 x 0.8 x 4 m box of jittered lattice water (88 % of N), a crown splash around a rising
         column at its centre (7 %) and drops thrown from it on ballistic arcs (5 %);
  spray: droplets of 1..12 particles (spacing apart) scattered through a 3 x 1.6 x 3 m ellipsoid.
Deterministic for a seed (Python's random); plain Python, no numpy.
"""
import argparse
import math
import os
import random
import sys


def pool(n, rng, emit):
    n_bulk = int(n * 0.88)
    n_crown = int(n * 0.07)
    n_drops = n - n_bulk - n_crown
    s = (4.0 * 0.8 * 4.0 / n_bulk) ** (1.0 / 3.0)
    nx, ny = int(round(4.0 / s)), int(round(0.8 / s))
    g = rng.gauss
    for i in range(n_bulk):  # a jittered lattice, filled layer by layer from the bottom
        ix, iy, iz = i % nx, (i // nx) % ny, i // (nx * ny)
        emit(ix * s - 2.0 + s / 2 + g(0, 0.08 * s), iy * s + s / 2 + g(0, 0.08 * s), iz * s - 2.0 + s / 2 + g(0, 0.08 * s))
    for _ in range(n_crown):  # a thin rising sheet flaring out (70 %) and a central column
        ang = rng.random() * 2 * math.pi
        if rng.random() < 0.7:
            h = 0.8 + 0.6 * rng.random() ** 1.5
            r = 0.35 + 0.25 * (h - 0.8) + g(0, 0.3 * s)
        else:
            h = 0.8 + 1.1 * rng.random()
            r = 0.12 * math.sqrt(rng.random())
        emit(r * math.cos(ang), h, r * math.sin(ang))
    for _ in range(n_drops):  # drops thrown from the rim on ballistic arcs (g = 9.81)
        a = rng.random() * 2 * math.pi
        speed, up = 1.5 + 1.5 * rng.random(), 2.0 + 2.0 * rng.random()
        t = rng.random() * 2 * up / 9.81
        emit(0.6 * math.cos(a) + speed * math.cos(a) * t, max(1.3 + up * t - 4.905 * t * t, 0.85),
             0.6 * math.sin(a) + speed * math.sin(a) * t)
    return s


def spray(n, rng, emit):
    s = (4.0 * 0.8 * 4.0 / n) ** (1.0 / 3.0)
    g = rng.gauss
    left = n
    while left > 0:  # droplets of 1..12 particles in a 3 x 1.6 x 3 m ellipsoid around y = 1.2
        size = min(rng.randint(1, 12), left)
        while True:
            cx, cy, cz = rng.uniform(-1.5, 1.5), rng.uniform(-0.8, 0.8), rng.uniform(-1.5, 1.5)
            if (cx / 1.5) ** 2 + (cy / 0.8) ** 2 + (cz / 1.5) ** 2 <= 1.0:
                break
        for _ in range(size):
            emit(cx + g(0, 0.8 * s), 1.2 + cy + g(0, 0.8 * s), cz + g(0, 0.8 * s))
        left -= size
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--sizes", default="50000,1000000,4000000")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--force", action="store_true", help="replace existing files")
    args = ap.parse_args()
    try:
        sizes = [int(v) for v in args.sizes.split(",")]
    except ValueError:
        sys.exit(f"make_render_sets.py: --sizes {args.sizes}: expected integers separated by commas")
    if any(n < 100 or n > 50_000_000 for n in sizes):
        sys.exit(f"make_render_sets.py: --sizes {args.sizes}: each size must be in 100..50000000")
    os.makedirs(args.out_dir, exist_ok=True)
    for n in sizes:
        for name, make in (("pool", pool), ("spray", spray)):
            path = os.path.join(args.out_dir, f"{name}_{n}.xyz")
            if os.path.exists(path) and not args.force:
                count = sum(1 for _ in open(path))
                s = (4.0 * 0.8 * 4.0 / (int(n * 0.88) if name == "pool" else n)) ** (1.0 / 3.0)
                print(f"{path}: {count} particles, spacing {s:.4f} m (made before, kept; --force to replace)")
                continue
            lines = []
            emit = lambda x, y, z: lines.append(f"{x:.5f} {y:.5f} {z:.5f}\n")
            s = make(n, random.Random(args.seed * 1000003 + n), emit)
            with open(path + ".part", "w") as f:
                f.writelines(lines)
            os.replace(path + ".part", path)
            print(f"{path}: {len(lines)} particles, spacing {s:.4f} m")


if __name__ == "__main__":
    main()
