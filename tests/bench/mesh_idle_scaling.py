#!/usr/bin/env python3
"""Two-thread speed-up of the mesher back to back and after a frame's idle (issue 20 bar 2).

A game meshes once per frame, so its mesher's threads sit idle between two meshes; `fluiddemo mesh
--reps N --idle-ms MS` times N warm meshes, each after MS of sleep. This runs the bar's sets at 1
and 2 threads, with no idle and with the given idle times, interleaved over ROUNDS rounds, and
prints a markdown table of the median of the per-run medians and the two-thread speed-up.

Usage, from the repository root after a Release build in build/dev:
  python3 tests/bench/mesh_idle_scaling.py [--rounds 6] [--reps 21] [--idle 0,5,16]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

SETS = [("explosion", 0.6), ("spray", 1.0), ("fountain", 1.0)]
WARM = re.compile(r"warm, \d+ reps +median ([0-9.]+) ms, min ([0-9.]+) ms")


def load_average():
    with open("/proc/loadavg", encoding="ascii") as f:
        return " ".join(f.read().split()[:3])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", default="build/dev/game/fluiddemo")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--reps", type=int, default=21)
    ap.add_argument("--idle", default="0,5,16", help="idle times in ms, comma-separated")
    a = ap.parse_args()
    if not os.access(a.exe, os.X_OK):
        sys.exit(f"mesh_idle_scaling: {a.exe} is not an executable (build build/dev first)")
    idles = [float(x) for x in a.idle.split(",")]
    medians = {}
    before = load_average()
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(a.rounds):
            for name, cube in SETS:
                for idle in idles:
                    for threads in (1, 2):
                        cmd = [a.exe, "mesh", "--in", f"tests/data/{name}.xyz", "--out", f"{tmp}/m.obj", "--cube",
                               str(cube), "--threads", str(threads), "--reps", str(a.reps), "--idle-ms", f"{idle:g}",
                               "--force"]
                        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
                        m = WARM.search(out)
                        if not m:
                            sys.exit(f"mesh_idle_scaling: no warm timing in the output of {' '.join(cmd)}:\n{out}")
                        medians.setdefault((name, idle, threads), []).append(float(m.group(1)))
    after = load_average()
    print(f"`python3 tests/bench/mesh_idle_scaling.py --rounds {a.rounds} --reps {a.reps} --idle {a.idle}`: "
          f"`fluiddemo mesh --threads 1|2 --reps {a.reps} --idle-ms MS` per set, idle times and thread counts "
          f"interleaved over {a.rounds} rounds; ms = median of the runs' medians.\n")
    print("| set | S | idle before each mesh (ms) | 1 thread ms | 2 threads ms | 2-thread speed-up |")
    print("|---|---|---|---|---|---|")
    for name, cube in SETS:
        for idle in idles:
            one = statistics.median(medians[(name, idle, 1)])
            two = statistics.median(medians[(name, idle, 2)])
            print(f"| {name} | {cube:g} | {idle:g} | {one:.3f} | {two:.3f} | {one / two:.2f}x |")
    print(f"\nLoad average (1, 5, 15 min): {before} before, {after} after, on {os.cpu_count()} hardware threads.")


if __name__ == "__main__":
    main()
