"""Shared helpers of the benchmark charts (scripts/plots/*.py): read a benchmark CSV, draw labelled
log-log series with matplotlib, save a PNG whose bytes depend only on the data (no date, no version
in the metadata). Debian package: python3-matplotlib (scripts/setup-deps.sh installs it)."""

import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")  # no display: CI and the docs scripts run headless
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

# Colour-blind safe palette (Okabe & Ito), one colour per series in legend order.
COLORS = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]


def read_rows(path, required):
    """Rows of a benchmark CSV as dicts; exits with a message naming the file and the missing column."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit("%s: %s" % (path, e.strerror))
    if not rows:
        sys.exit("%s: no data rows" % path)
    for column in required:
        if column not in rows[0]:
            sys.exit("%s: no column '%s' (has %s)" % (path, column, ", ".join(rows[0].keys())))
    return rows


def number(row, column, path):
    """A finite float from `row[column]`; exits naming the file, the column and the value otherwise."""
    text = row[column]
    try:
        value = float(text)
    except ValueError:
        sys.exit("%s: column '%s': '%s' is not a number" % (path, column, text))
    if math.isnan(value):
        sys.exit("%s: column '%s' is NaN" % (path, column))
    return value


def draw_series(ax, series, title, xlabel, ylabel, legend_title=None):
    """series: list of dicts {label, points: [(x, y, point_label)], connect}. Points that a log axis
    cannot hold (<= 0 or infinite) are left out; returns how many."""
    skipped = 0
    for k, s in enumerate(series):
        pts = [(x, y, t) for x, y, t in s["points"] if 0 < x < math.inf and 0 < y < math.inf]
        skipped += len(s["points"]) - len(pts)
        if not pts:
            continue
        color, marker = COLORS[k % len(COLORS)], MARKERS[k % len(MARKERS)]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        ax.plot(xs, ys, linestyle="-" if s.get("connect", True) else "none", marker=marker, color=color,
                label=s["label"], markersize=6, linewidth=1.5)
        for x, y, t in pts:
            if t:
                ax.annotate(t, (x, y), textcoords="offset points", xytext=(5, 4), fontsize=7, color=color)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_title(title, fontsize=11)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="major", color="#cccccc", linewidth=0.8)
    ax.grid(True, which="minor", color="#eeeeee", linewidth=0.5)
    ax.legend(fontsize=8, title=legend_title, title_fontsize=8, loc="best")
    return skipped


def save(fig, path):
    fig.tight_layout()
    # No "Software" (matplotlib version) or date in the PNG: the file changes only with the data.
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)
    print("wrote %s" % path)


def group(rows, key):
    """Rows grouped by `key`, groups in order of first appearance."""
    out = {}
    for row in rows:
        out.setdefault(row[key], []).append(row)
    return out
