#!/usr/bin/env python3
"""Plots a `fluiddemo replay --csv` file: per-phase frame time over the replay, stacked, with the
16.7 ms (60 fps) and 33.3 ms (30 fps) lines and the frame total on top. Needs matplotlib (Debian
python3-matplotlib, installed by scripts/setup-deps.sh).

    scripts/plot_frame_times.py IN.csv OUT.png [--width 1200] [--height 600] [--title T] [--force]

The PNG is exactly WIDTH x HEIGHT pixels. OUT.png is never replaced without --force.
"""
import argparse
import csv
import os
import sys

PHASES = ["input", "physics", "fluid", "meshing", "render", "ui"]


def read_rows(path):
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        needed = ["step", "frame_ms"] + [p + "_ms" for p in PHASES]
        missing = [c for c in needed if c not in (reader.fieldnames or [])]
        if missing:
            raise SystemExit(f"{path}: missing column(s) {', '.join(missing)} (not a fluiddemo replay CSV?)")
        rows = []
        for line, row in enumerate(reader, start=2):
            try:
                rows.append({c: float(row[c]) for c in needed})
            except (TypeError, ValueError):
                raise SystemExit(f"{path}:{line}: a value in {needed} is not a number")
    if not rows:
        raise SystemExit(f"{path}: no rows")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv")
    parser.add_argument("png")
    parser.add_argument("--width", type=int, default=1200)
    parser.add_argument("--height", type=int, default=600)
    parser.add_argument("--title", default="")
    parser.add_argument("--force", action="store_true")
    args = parser.parse_args()
    if os.path.exists(args.png) and not args.force:
        raise SystemExit(f"{args.png} exists (pass --force to replace it)")
    if not (100 <= args.width <= 10000 and 100 <= args.height <= 10000):
        raise SystemExit("--width/--height must be in [100, 10000]")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("matplotlib is missing (Debian: apt-get install python3-matplotlib; "
                         "or set FLUIDDEMO_PYTHON to a Python that has it)")
    rows = read_rows(args.csv)
    steps = [r["step"] for r in rows]
    dpi = 100
    fig, ax = plt.subplots(figsize=(args.width / dpi, args.height / dpi), dpi=dpi)
    series = [[r[p + "_ms"] for r in rows] for p in PHASES]
    ax.stackplot(steps, series, labels=PHASES, linewidth=0)
    ax.plot(steps, [r["frame_ms"] for r in rows], color="black", linewidth=0.6, label="frame total")
    for ms, label in ((1000 / 60, "16.7 ms (60 fps)"), (1000 / 30, "33.3 ms (30 fps)")):
        ax.axhline(ms, color="black", linestyle="--", linewidth=0.8, zorder=4)
        ax.text(steps[0], ms, " " + label, va="bottom", fontsize=8, color="black", zorder=5,
                bbox=dict(facecolor="white", alpha=0.7, linewidth=0, pad=1))
    ax.set_xlabel("simulation step (one per frame)")
    ax.set_ylabel("ms per frame")
    ax.set_xlim(steps[0], steps[-1] if steps[-1] > steps[0] else steps[0] + 1)
    ax.set_ylim(bottom=0)
    if args.title:
        ax.set_title(args.title)
    ax.legend(loc="upper right", fontsize=8, ncol=4)
    fig.tight_layout()
    # No bbox_inches="tight": that would change the pixel size asked for.
    fig.savefig(args.png, dpi=dpi)
    return 0


if __name__ == "__main__":
    sys.exit(main())
