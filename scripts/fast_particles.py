#!/usr/bin/env python3
"""How many SPH particles set the fountain's sub-steps (issue 33's frame budget).

The solver's step is bounded by the CFL condition dt <= cfl d / v_max over the particles in the solve
(spray flies outside it), so a frame takes one sub-step only when no such particle is faster than
cfl d / (game step). The replay CSV's `sph_fast` column counts the ones that are. This runs a replay
without rendering, splits its frames into calm ones and the 120 after each blast (as
scripts/replay_budget.py does), and prints a markdown table: sub-steps per frame, the particles over
that speed and their share of the water in the solve.

Usage, from the repository root:
  python3 scripts/fast_particles.py FLUIDDEMO REPLAY [--threads 2]
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile

AFTER_BLAST = 120  # frames counted as "after a blast", as scripts/replay_budget.py


def nearest_rank(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, int(-(-q * len(ordered) // 1)) - 1))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fluiddemo")
    ap.add_argument("replay")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    env = dict(os.environ, SDL_VIDEODRIVER="offscreen", SDL_AUDIODRIVER="dummy")
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "frames.csv")
        run = subprocess.run([args.fluiddemo, "replay", args.replay, "--no-render", "--threads", str(args.threads),
                              "--csv", path], env=env, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"fast_particles: the replay failed:\n{run.stdout}{run.stderr}")
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    after = set()
    for i, row in enumerate(rows):
        if float(row["blasts"]) > 0:
            after.update(range(i, min(len(rows), i + AFTER_BLAST)))
    groups = [("calm", [i for i in range(len(rows)) if i not in after]), ("after a blast", sorted(after))]
    print(f"`python3 scripts/fast_particles.py FLUIDDEMO {args.replay} --threads {args.threads}` "
          f"({len(rows)} frames, simulation only):\n")
    print("| frames | count | SPH sub-steps per frame (mean) | frames with one sub-step | particles over cfl d / step "
          "(median) | p95 | most | their share of the water in the solve (median) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, idx in groups:
        if not idx:
            continue
        fast = [float(rows[i]["sph_fast"]) for i in idx]
        steps = [float(rows[i]["sph_steps"]) for i in idx]
        in_solve = [float(rows[i]["particles"]) - float(rows[i]["water_pump"]) - float(rows[i]["water_spray"])
                    for i in idx]
        share = statistics.median(f / n for f, n in zip(fast, in_solve) if n > 0)
        print(f"| {name} | {len(idx)} | {statistics.mean(steps):.2f} | {sum(1 for s in steps if s <= 1)} "
              f"| {statistics.median(fast):.0f} | {nearest_rank(fast, 0.95):.0f} | {max(fast):.0f} | {100 * share:.2f} % |")


if __name__ == "__main__":
    main()
