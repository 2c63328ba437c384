#!/usr/bin/env python3
"""Two builds of fluiddemo over one replay, interleaved: simulation + meshing p95 per run and mode.

    python3 scripts/replay_ab.py BEFORE_FLUIDDEMO AFTER_FLUIDDEMO content/replays/fountain_tour.replay \\
        fluid_surface.async [ROUNDS [MODES]]

Each round runs the modes of scripts/replay_budget.py (MODES: comma-separated, default
async,paced,bare) once with each build, BEFORE first in even rounds and AFTER first in odd ones
(so neither always runs first), so both builds see the same load; this
shared machine's noise shows between runs more than within one, so the table gives every run's p95
(simulation + meshing on the main thread, as the budget table) and their median, and the main
thread's meshing p95 (with asynchronous meshing: the hand-over and the wait for the worker).
Build BEFORE from the older commit (e.g. `git worktree add /tmp/before OLD` and build its
fluiddemo target).
"""
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from replay_budget import mode_label, percentile, run_modes  # noqa: E402


def p95_per_run(rows, value):
    runs = sorted({r["run"] for r in rows})
    return [percentile([value(r) for r in rows if r["run"] == run], 0.95) for run in runs]


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    before, after, replay, async_key = sys.argv[1:5]
    rounds = int(sys.argv[5]) if len(sys.argv) > 5 else 4
    if rounds < 1:
        sys.exit(f"replay_ab: ROUNDS must be at least 1, got {rounds}")
    # run_modes refuses an unknown mode at the first call, before any run.
    modes = [m.strip() for m in sys.argv[6].split(",")] if len(sys.argv) > 6 else ["async", "paced", "bare"]
    builds = {"before": before, "after": after}
    frames = {(build, mode): [] for build in builds for mode in modes}
    load_before = os.getloadavg()[0]
    for round_ in range(rounds):
        order = list(builds.items()) if round_ % 2 == 0 else list(builds.items())[::-1]
        for build, binary in order:
            command, got = run_modes(binary, replay, async_key, rounds=1, only=modes)
            for mode, rows in got.items():
                frames[(build, mode)] += [dict(row, run=round_) for row in rows]
    both = lambda r: float(r["physics_ms"]) + float(r["fluid_ms"]) + float(r["meshing_ms"])
    lines = ["| mode | build | simulation + meshing p95 ms, each run | median of the runs | "
             "meshing (main thread) p95 ms, each run |", "|---|---|---|---|---|"]
    for mode in modes:
        for build in builds:
            rows = frames[(build, mode)]
            runs = p95_per_run(rows, both)
            main_thread = p95_per_run(rows, lambda r: float(r["meshing_ms"]))
            lines.append(f"| {mode_label(mode, async_key)} | {build} | {' / '.join(f'{v:.2f}' for v in runs)} | "
                         f"**{statistics.median(runs):.2f}** | {' / '.join(f'{v:.2f}' for v in main_thread)} |")
    lines += ["", f"`python3 scripts/replay_ab.py {' '.join(sys.argv[1:])}`: {rounds} rounds of "
              f"`{' '.join(command)}` with each build's mode flags, the builds interleaved in each, "
              f"{len(frames[('after', modes[0])]) // rounds} frames per run, on {len(os.sched_getaffinity(0))} cores, load average "
              f"{load_before:.1f} before and {os.getloadavg()[0]:.1f} after."]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
