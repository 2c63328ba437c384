#!/usr/bin/python3
"""Draws docs/sph_accuracy.png from the CSV of `bench_sph accuracy --csv FILE`: mean density error
against CPU seconds per simulated second (log-log), one curve per knob sweep (the knob rising along
it) and the single runs with other knob sets as labelled points.

Usage: scripts/plots/sph_accuracy.py docs/sph_accuracy.csv docs/sph_accuracy.png"""

import sys

import loglog


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    csv_path, png_path = argv[1], argv[2]
    rows = loglog.read_rows(csv_path, ["sweep", "point", "cpu_s_per_sim_s", "mean_density_error_pct"])
    series = []
    for sweep, members in loglog.group(rows, "sweep").items():
        points = [(loglog.number(r, "cpu_s_per_sim_s", csv_path), loglog.number(r, "mean_density_error_pct", csv_path),
                   r["point"]) for r in members]
        # A sweep varies one knob: its runs are joined; "other knobs" runs are separate points.
        series.append({"label": sweep, "points": points, "connect": "other" not in sweep})
    fig, ax = loglog.plt.subplots(figsize=(9, 5.5))
    skipped = loglog.draw_series(ax, series, "Dam break, 2 s: density error against compute time",
                                 "CPU seconds per simulated second", "mean density error (%, over 30 fps frames)")
    if skipped:
        print("%s: %d runs with a zero error or time are not drawn" % (csv_path, skipped))
    loglog.save(fig, png_path)


if __name__ == "__main__":
    main(sys.argv)
