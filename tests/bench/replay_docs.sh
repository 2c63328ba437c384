#!/bin/sh
# Regenerates docs/replay.md (and its plots) from the committed replays. Usage, from the repository
# root after a Release build in build/dev:   tests/bench/replay_docs.sh [WIDTH HEIGHT]
# Each replay runs rendered headless at WIDTHxHEIGHT (default 640x360: llvmpipe takes ~0.4 s per 1280x720
# frame on this shared 2-core machine, so the page would take over 10 minutes) with
# --threads 1 and --threads 2; the tables give p50/p95/max per phase of every frame, the plots the
# two-thread run. The machine's load average is printed next to each run.
set -eu
EXE=build/dev/game/fluiddemo
WIDTH=${1:-640}
HEIGHT=${2:-360}
OUT=docs/replay.md
# Rendered frames per replay (0 = all).
FRAMES_fountain_tour=0
FRAMES_crate_yard_tour=0
PYTHON=/usr/bin/python3
[ -x "$PYTHON" ] || PYTHON=python3
export SDL_VIDEODRIVER=offscreen
mkdir -p docs
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
loads=""
for replay in fountain_tour crate_yard_tour; do
  eval frames=\$FRAMES_$replay
  for threads in 1 2; do
    load_before=$(cut -d' ' -f1-3 /proc/loadavg)
    png_args=""
    [ "$threads" = 2 ] && png_args="--png docs/replay_$replay.png --plot-width 1100 --plot-height 420"
    # shellcheck disable=SC2086
    "$EXE" replay "content/replays/$replay.replay" --headless --no-ui --set graphics.preset=high \
      --width "$WIDTH" --height "$HEIGHT" \
      --threads "$threads" --frames "$frames" --csv "$tmp/$replay.$threads.csv" $png_args --force \
      > "$tmp/$replay.$threads.txt"
    echo "$replay $threads $load_before $(cut -d' ' -f1-3 /proc/loadavg) $(grep '^checkpoints:' "$tmp/$replay.$threads.txt" | cut -d' ' -f2-)" >> "$tmp/runs.txt"
  done
done
renderer=$(sed -n 's/^renderer: //p' "$tmp/fountain_tour.1.txt")
"$PYTHON" - "$tmp" "$WIDTH" "$HEIGHT" "$renderer" > "$tmp/measured.md" <<'PY'
import csv, math, sys
tmp, width, height, renderer = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
PHASES = ["input", "physics", "fluid", "meshing", "render", "ui", "frame"]

def nearest_rank(values, q):  # the same percentiles as fluiddemo replay prints
    s = sorted(values)
    return s[max(1, min(len(s), math.ceil(q * len(s)))) - 1]

def table(path):
    rows = list(csv.DictReader(open(path)))
    out = {}
    for p in PHASES:
        v = [float(r[p + "_ms"]) for r in rows]
        out[p] = (nearest_rank(v, 0.5), nearest_rank(v, 0.95), max(v))
    return rows, out

runs = {}
for line in open(f"{tmp}/runs.txt"):
    f = line.split()
    runs[(f[0], f[1])] = (" ".join(f[2:5]), " ".join(f[5:8]), " ".join(f[8:]))

print("## Headline: frame time per replay")
print()
print(f"Rendered headless at {width}x{height} on {renderer}, one simulation step per frame, every frame;")
print("whole-frame milliseconds (nearest-rank percentiles over all frames, the first included).")
print()
print("| replay | frames | threads | frame p50 ms | frame p95 ms | frame max ms |")
print("|---|---|---|---|---|---|")
tables = {}
for replay in ["fountain_tour", "crate_yard_tour"]:
    for threads in ["1", "2"]:
        rows, t = table(f"{tmp}/{replay}.{threads}.csv")
        tables[(replay, threads)] = (rows, t)
        p50, p95, mx = t["frame"]
        print(f"| {replay} | {len(rows)} | {threads} | {p50:.1f} | {p95:.1f} | {mx:.1f} |")
print()
for replay in ["fountain_tour", "crate_yard_tour"]:
    print(f"## {replay}")
    print()
    n = len(tables[(replay, "1")][0])
    print(f"Command: `build/dev/game/fluiddemo replay content/replays/{replay}.replay --headless --no-ui "
          "--set graphics.preset=high "
          f"--width {width} --height {height} --threads T --frames {n} --csv OUT.csv` "
          f"({n} frames; the plot is the 2-thread run).")
    print()
    for threads in ["1", "2"]:
        before, after, checks = runs[(replay, threads)]
        print(f"- {threads} thread(s): load average {before} before, {after} after; checkpoints: {checks}")
    print()
    print("| phase | p50 ms (1 thread) | p95 ms (1) | max ms (1) | p50 ms (2 threads) | p95 ms (2) | max ms (2) |")
    print("|---|---|---|---|---|---|---|")
    for p in PHASES:
        a = tables[(replay, "1")][1][p]
        b = tables[(replay, "2")][1][p]
        print(f"| {p} | {a[0]:.2f} | {a[1]:.2f} | {a[2]:.2f} | {b[0]:.2f} | {b[1]:.2f} | {b[2]:.2f} |")
    print()
    print(f"![per-phase frame time over the {replay} replay, stacked](replay_{replay}.png)")
    print()
PY
{
  cat tests/bench/replay_docs_head.md
  echo
  echo "## Machine"
  echo
  echo "$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); load average $(cut -d' ' -f1-3 /proc/loadavg) at the end of the runs. Other work shares this machine: compare runs with \`fluiddemo replay --compare\` ratios, not across pages."
  echo
  cat "$tmp/measured.md"
} > "$OUT"
# The columns block from the effects' own lists, whatever the head's copy says.
"$PYTHON" scripts/generated_docs.py "$EXE"
echo "wrote $OUT"
