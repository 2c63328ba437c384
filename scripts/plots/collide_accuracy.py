#!/usr/bin/python3
"""Draws docs/collide_accuracy.png from the CSV of `bench_collide_tables --csv FILE`: per shape
(one column each) the misclassified points (top) and the mean distance error near the surface
(bottom) against ns per query, one curve per map set, one point per resolution (labelled).

Usage: scripts/plots/collide_accuracy.py docs/collide_accuracy.csv docs/collide_accuracy.png"""

import sys

import loglog


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    csv_path, png_path = argv[1], argv[2]
    rows = loglog.read_rows(csv_path, ["shape", "maps", "res", "misclass_pct", "mean_abs_dd", "ns_per_query"])
    shapes = loglog.group(rows, "shape")
    fig, axes = loglog.plt.subplots(2, len(shapes), figsize=(6 * len(shapes), 10), squeeze=False)
    skipped = 0
    for column, (shape, members) in enumerate(shapes.items()):
        misclass, distance = [], []
        for maps, runs in loglog.group(members, "maps").items():
            ns = [loglog.number(r, "ns_per_query", csv_path) for r in runs]
            res = ["%s²" % r["res"] for r in runs]
            misclass.append({"label": maps, "points": list(zip(
                ns, [loglog.number(r, "misclass_pct", csv_path) for r in runs], res))})
            distance.append({"label": maps, "points": list(zip(
                ns, [loglog.number(r, "mean_abs_dd", csv_path) for r in runs], res))})
        skipped += loglog.draw_series(axes[0][column], misclass, "%s: misclassified points" % shape,
                                      "ns per query, 1 thread", "misclassified (% of points)")
        skipped += loglog.draw_series(axes[1][column], distance, "%s: distance error near the surface" % shape,
                                      "ns per query, 1 thread", "mean |Δd| (model units)")
    if skipped:
        print("%s: %d points with zero error are not drawn" % (csv_path, skipped))
    loglog.save(fig, png_path)


if __name__ == "__main__":
    main(sys.argv)
