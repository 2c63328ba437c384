#!/usr/bin/python3
"""Draws the charts of docs/surface.md from the CSVs that `bench_surface --out docs/surface.md`
writes next to the page: <stem>_accuracy.png (volume error and largest vertex error against ms per
mesh, one point per cube size S) and <stem>_order.png (fraction of triangle pairs out of order
against ms per mesh; per particle set the three orderings none, b2f, b2f exact).

Usage: scripts/plots/surface_charts.py docs/surface.md   (reads docs/surface_{accuracy,order}.csv,
writes docs/surface_{accuracy,order}.png)"""

import os
import sys

import loglog


def accuracy(csv_path, png_path):
    rows = loglog.read_rows(csv_path, ["shape", "cube", "ms_per_mesh", "volume_error_pct", "max_vertex_error"])
    volume, vertex = [], []
    for shape, members in loglog.group(rows, "shape").items():
        ms = [loglog.number(r, "ms_per_mesh", csv_path) for r in members]
        labels = ["S=" + r["cube"] for r in members]
        vol = [abs(loglog.number(r, "volume_error_pct", csv_path)) for r in members]
        vtx = [loglog.number(r, "max_vertex_error", csv_path) for r in members]
        volume.append({"label": shape, "points": list(zip(ms, vol, labels))})
        vertex.append({"label": shape, "points": list(zip(ms, vtx, labels))})
    fig, (left, right) = loglog.plt.subplots(1, 2, figsize=(13, 5))
    skipped = loglog.draw_series(left, volume, "Volume error against time", "ms per mesh, 1 thread",
                                 "|volume error| (%)")
    skipped += loglog.draw_series(right, vertex, "Largest vertex error against time", "ms per mesh, 1 thread",
                                  "max vertex error (distance units of the set)")
    if skipped:
        print("%s: %d points are zero and not drawn" % (csv_path, skipped))
    loglog.save(fig, png_path)


def order(csv_path, png_path):
    rows = loglog.read_rows(csv_path, ["set", "method", "ms_per_mesh", "mean_fraction_out_of_order"])
    series = []
    for name, members in loglog.group(rows, "set").items():
        series.append({"label": name, "points": [(loglog.number(r, "ms_per_mesh", csv_path),
                                                  loglog.number(r, "mean_fraction_out_of_order", csv_path),
                                                  r["method"]) for r in members]})
    fig, ax = loglog.plt.subplots(figsize=(8, 5.5))
    skipped = loglog.draw_series(ax, series, "Back-to-front order against time", "ms per mesh, 1 thread",
                                 "fraction of triangle pairs out of order", legend_title="particle set")
    if skipped:
        print("%s: %d points are zero and not drawn" % (csv_path, skipped))
    loglog.save(fig, png_path)


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    stem = os.path.splitext(argv[1])[0]
    accuracy(stem + "_accuracy.csv", stem + "_accuracy.png")
    order(stem + "_order.csv", stem + "_order.png")


if __name__ == "__main__":
    main(sys.argv)
