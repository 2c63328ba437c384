#!/usr/bin/env python3
"""The fountain's mesh lattice candidates side by side (issue 33 item 4).

For each lattice cube edge S (fluid_surface.cube, in particle spacings) it plays the fountain tour
rendered headless up to STEP, writes the frame there and the per-frame CSV, and composes the
frames (cropped to the fountain) into one PNG through matplotlib, each titled with the surface's
triangles and the meshing worker's median and p95 time over the frames played:

    python3 scripts/mesh_lattice.py build/dev/game/fluiddemo content/replays/fountain_tour.replay \\
        docs/images/fountain_mesh_lattice.png [0.5 0.75 1.0]
"""
import csv
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

STEP = 700  # after the first blast, crates in the pool, the camera facing the basin
SIZE = (1280, 720)
CROP = (slice(110, 560), slice(280, 1000))  # rows, columns of the fountain in the frame


def percentile(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(len(values) * p))]


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    fluiddemo, replay, out = sys.argv[1:4]
    cubes = [float(c) for c in sys.argv[4:]] or [0.5, 0.75, 1.0]
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        for cube in cubes:
            png, table = os.path.join(tmp, f"s{cube}.png"), os.path.join(tmp, f"s{cube}.csv")
            subprocess.run([fluiddemo, "replay", replay, "--headless", "--no-ui", "--width", str(SIZE[0]), "--height",
                            str(SIZE[1]), "--frames", str(STEP + 1), "--threads", "2", "--set", "graphics.preset=high",
                            "--set",
                            f"fluid_surface.cube={cube}", "--screenshot-at", f"{STEP}:{png}", "--csv", table],
                           check=True, stdout=subprocess.DEVNULL)
            rows = list(csv.DictReader(open(table)))
            worker = [float(r["mesh_worker_ms"]) for r in rows[60:]]
            triangles = int(rows[STEP - 1]["triangles"])
            panels.append((cube, mpimg.imread(png)[CROP], triangles, percentile(worker, 0.5),
                           percentile(worker, 0.95)))
    fig, axes = plt.subplots(1, len(panels), figsize=(6.4 * len(panels), 4.4), dpi=100)
    for ax, (cube, image, triangles, p50, p95) in zip(axes, panels):
        ax.imshow(image)
        ax.set_axis_off()
        ax.set_title(f"S = {cube:g} spacing: {triangles:,} triangles\nworker p50 {p50:.1f} ms, p95 {p95:.1f} ms",
                     fontsize=11)
    fig.suptitle(f"{os.path.basename(replay)} at step {STEP}, fluid_surface.cube = S "
                 f"(2 threads, llvmpipe; worker times over steps 60-{STEP + 1})", fontsize=11, y=0.99)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.93))
    fig.savefig(out)
    print(f"wrote {out}")
    for cube, _, triangles, p50, p95 in panels:
        print(f"| {cube:g} | {triangles:,} | {p50:.2f} | {p95:.2f} |")


if __name__ == "__main__":
    main()
