#!/usr/bin/env python3
"""Markdown tables from what scripts/gpu_check.sh brought back from a device machine.

    python3 scripts/gpu_tables.py RUN_DIR [RUN_DIR ...]

Each RUN_DIR holds gpu_check_log.txt and frame_csvs.tar.gz (the per-frame CSVs of the rendered
replays). Prints, per run: the replays (simulation + meshing on the main thread = physics_ms +
fluid_ms + meshing_ms, render_ms, frame_ms; nearest-rank percentiles over every frame), the mesher's
one- and two-thread times on two pinned cores (the median over rounds of each round's median and the
least of the minimums), and the bench_game_fountain rows copied from the log.
"""
import csv
import io
import math
import os
import re
import statistics
import sys
import tarfile


def nearest_rank(values, q):  # the percentiles fluiddemo replay prints
    s = sorted(values)
    return s[max(1, min(len(s), math.ceil(q * len(s)))) - 1]


def replay_table(run_dir):
    lines = ["| replay (cores) | frames | most particles | most triangles | simulation + meshing p50 / p95 ms | "
             "render p50 / p95 ms | frame p50 / p95 ms |", "|---|---|---|---|---|---|---|"]
    with tarfile.open(os.path.join(run_dir, "frame_csvs.tar.gz")) as tar:
        for member in sorted(tar.getmembers(), key=lambda m: m.name):
            rows = list(csv.DictReader(io.TextIOWrapper(tar.extractfile(member))))
            name = os.path.basename(member.name)[:-4]
            label = name.replace("pinned_", "") + (" (2 pinned)" if name.startswith("pinned_") else " (all)")
            label = label.replace("gpu_", "")
            col = lambda key: [float(r[key]) for r in rows]
            sim = [float(r["physics_ms"]) + float(r["fluid_ms"]) + float(r["meshing_ms"]) for r in rows]
            pair = lambda v: f"{nearest_rank(v, 0.5):.2f} / {nearest_rank(v, 0.95):.2f}"
            lines.append(f"| {label} | {len(rows)} | {max(int(r['particles']) for r in rows):,} | "
                         f"{max(int(r['triangles']) for r in rows):,} | {pair(sim)} | {pair(col('render_ms'))} | "
                         f"{pair(col('frame_ms'))} |")
    return lines


def mesher_table(log):
    pattern = re.compile(r"^(\w+) (?:block (\d+) )?threads (\d) round \d+: .*median ([\d.]+) ms, min ([\d.]+) ms")
    runs = {}
    for line in log.splitlines():
        m = pattern.match(line)
        if m:
            runs.setdefault((m[1], int(m[2] or 0), int(m[3])), []).append((float(m[4]), float(m[5])))
    if not runs:
        return []
    lines = ["| set | block cubes (0 = auto) | rounds | 1 thread ms (median of medians / least min) | "
             "2 threads ms | 2-thread gain (medians / mins) |", "|---|---|---|---|---|---|"]
    for (name, block, threads), one in sorted(runs.items()):
        if threads != 1 or (name, block, 2) not in runs:
            continue
        two = runs[(name, block, 2)]
        m1, m2 = statistics.median(r[0] for r in one), statistics.median(r[0] for r in two)
        n1, n2 = min(r[1] for r in one), min(r[1] for r in two)
        lines.append(f"| {name} | {block} | {len(one)} | {m1:.2f} / {n1:.2f} | {m2:.2f} / {n2:.2f} | "
                     f"{m1 / m2:.2f}x / {n1 / n2:.2f}x |")
    return lines


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for run_dir in sys.argv[1:]:
        log = open(os.path.join(run_dir, "gpu_check_log.txt")).read()
        gpu = re.search(r"^GPU 0: ([^(]+)", log, re.M)
        cpu = re.search(r"Model name:\s+(.+)$", log, re.M)
        print(f"#### {run_dir}: {gpu[1].strip() if gpu else '?'}, CPU {cpu[1].strip() if cpu else 'not in the log'}\n")
        print("\n".join(replay_table(run_dir)) + "\n")
        mesher = mesher_table(log)
        if mesher:
            print("\n".join(mesher) + "\n")
        bench = [line for line in log.splitlines() if line.startswith("|") and "configuration" not in line
                 and not line.startswith("|---") and "(2)" in line]
        if bench:
            print("| bench_game_fountain configuration (threads) | particles | steps median ms | steps p95 ms | "
                  "steps + mesh wait p50 / p95 ms | mesher worker median ms |\n|---|---|---|---|---|---|")
            for line in bench:
                c = [x.strip() for x in line.strip("|").split("|")]
                print(f"| {c[0]} | {c[1]} | {c[2]} | {c[8]} | {c[10]} / {c[11]} | {c[12]} |")
            print()


if __name__ == "__main__":
    main()
