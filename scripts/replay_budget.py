#!/usr/bin/env python3
"""Per-frame budget of a replay with its surfaces meshed asynchronously and synchronously.

Runs `fluiddemo replay REPLAY --headless` ROUNDS times per mode, the modes interleaved (so all see
the same load): asynchronous meshing (the default), asynchronous meshing with no renderer at all
(`--no-render --mesh`: without a GPU, llvmpipe's rasteriser threads otherwise share the cores with
the simulation and the mesher), the same held to 60 frames a second as vsync holds the game's loop
(`--pace 60`), and synchronous meshing. Prints a markdown table over all frames of
each mode: simulation (physics_ms + fluid_ms) + meshing on the main thread (meshing_ms: with async
meshing only the hand-over and the wait), the meshing worker's own time (mesh_worker_ms), the render
phase and the whole frame (llvmpipe rendering included, which measures Mesa rather than this project).

    python3 scripts/replay_budget.py build/dev/game/fluiddemo content/replays/fountain_tour.replay \\
        fluid_surface.async [README.md]

With README.md, the table replaces the section between <!-- budget NAME begin/end --> markers,
NAME the replay's file name without extension; otherwise it is printed.
"""
import csv
import os
import subprocess
import sys
import tempfile

ROUNDS = int(os.environ.get("REPLAY_BUDGET_ROUNDS", "3"))  # runs per mode
SIZE = ["--width", "320", "--height", "180"]


def percentile(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(len(values) * p))]


def run_modes(fluiddemo, replay, async_key, rounds=ROUNDS, threads=2, only=None):
    """Frames per mode ("async": the scene's default, "sync": --set ASYNC_KEY=false), interleaved;
    `only`: the names of the modes to run (all when None)."""
    # The scene's own rendering (graphics high): the budget is the scene's lattice, not llvmpipe's preset.
    base = [fluiddemo, "replay", replay, "--headless", "--no-ui", "--set", "graphics.preset=high"] + SIZE + [
        "--threads", str(threads)]
    # "bare": asynchronous meshing with no renderer at all (--no-render --mesh), so llvmpipe's
    # rasteriser threads do not take the 2 cores from the simulation and the mesher.
    # "paced": the same, frames started on the ticks of a 60 Hz clock as vsync holds the game's loop
    # on a machine with a GPU (the worker then meshes in the frame's idle time). The table rows
    # follow this order.
    modes = {"async": [], "bare": ["--no-render", "--mesh"], "paced": ["--no-render", "--mesh", "--pace", "60"],
             "sync": ["--set", f"{async_key}=false"]}
    if only is not None:
        only = set(only)
        if only - set(modes):
            sys.exit(f"replay_budget: unknown mode(s) {', '.join(sorted(only - set(modes)))}; the modes: {', '.join(modes)}")
        modes = {mode: extra for mode, extra in modes.items() if mode in only}
    frames = {mode: [] for mode in modes}
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(rounds):
            for mode, extra in modes.items():
                out = os.path.join(tmp, f"{mode}{round_}.csv")
                cmd = base + extra + ["--csv", out]
                run = subprocess.run(cmd, capture_output=True, text=True,
                                     env=dict(os.environ, SDL_VIDEODRIVER="offscreen", SDL_AUDIODRIVER="dummy"))
                if run.returncode != 0:
                    sys.exit(f"replay_budget: {' '.join(cmd)} failed (exit {run.returncode}):\n{run.stderr[-2000:]}")
                frames[mode] += [dict(row, run=round_) for row in csv.DictReader(open(out))]
    return base[1:], frames


def budget_table(command, frames, async_key, rounds=ROUNDS):
    """Markdown lines: one row per mode."""
    lines = [f"`{' '.join(command)}`, {rounds} runs per mode interleaved, {len(frames['async'])} frames each; "
             "simulation = physics_ms + fluid_ms, meshing = meshing_ms (main thread), worker = mesh_worker_ms:", "",
             "| meshing | most SPH particles | simulation + meshing p50 ms | simulation + meshing p95 ms | "
             "the same per run | simulation p95 | meshing (main thread) p95 | worker p95 ms | render p95 ms | "
             "frame p95 ms |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for mode, rows in frames.items():
        col = lambda name: [float(f[name]) for f in rows]
        sim = [float(f["physics_ms"]) + float(f["fluid_ms"]) for f in rows]
        both = [s + float(f["meshing_ms"]) for s, f in zip(sim, rows)]
        most = max(int(f["particles"]) for f in rows)
        # The machine's noise shows between runs more than within one: each run's p95 as well.
        per_run = " / ".join(f"{percentile([b for b, f in zip(both, rows) if f['run'] == r], 0.95):.2f}"
                             for r in sorted({f["run"] for f in rows}))
        lines.append(f"| {mode_label(mode, async_key)} | {f'{most:,}' if most else '-'} | {percentile(both, 0.5):.2f} | "
                     f"**{percentile(both, 0.95):.2f}** | {per_run} | {percentile(sim, 0.95):.2f} | "
                     f"{percentile(col('meshing_ms'), 0.95):.2f} | {percentile(col('mesh_worker_ms'), 0.95):.2f} | "
                     f"{percentile(col('render_ms'), 0.95):.2f} | {percentile(col('frame_ms'), 0.95):.2f} |")
    return lines


def mode_label(mode, async_key):
    return {"async": f"async (`{async_key}`, the default)",
            "bare": "async, no renderer (`--no-render --mesh`)",
            "paced": "async, no renderer, 60 frames a second (`--no-render --mesh --pace 60`)",
            "sync": f"synchronous (`--set {async_key}=false`)"}[mode]


AFTER_BLAST = 120  # frames (2 s at 60 Hz) counted as "after a blast"


def blast_windows(rows):
    """(calm, after): the frames no blast touched in the last AFTER_BLAST frames, and those it did.
    Runs are concatenated; a frame number that does not grow starts the next run."""
    calm, after = [], []
    since, last_frame = None, None
    for row in rows:
        frame = int(row["frame"])
        if last_frame is not None and frame <= last_frame:
            since = None  # a new run
        last_frame = frame
        if int(row.get("blasts", 0) or 0) > 0:
            since = 0
        (after if since is not None and since < AFTER_BLAST else calm).append(row)
        if since is not None:
            since += 1
    return calm, after


def blast_table(frames):
    """Markdown lines: SPH steps and simulation time per frame, calm and in the 2 s after a blast."""
    lines = ["| meshing | blasts | frames calm / after a blast | SPH steps per frame, calm | after a blast | "
             "steps ratio | simulation ms per frame, calm (mean) | after a blast (mean) | time ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    for mode, rows in frames.items():
        calm, after = blast_windows(rows)
        if not calm or not after:
            continue
        mean = lambda rs, f: sum(f(r) for r in rs) / len(rs)
        steps = lambda r: float(r["sph_steps"])
        sim = lambda r: float(r["physics_ms"]) + float(r["fluid_ms"])
        blasts = sum(int(r.get("blasts", 0) or 0) for r in rows)
        lines.append(f"| {mode} | {blasts} | {len(calm)} / {len(after)} | {mean(calm, steps):.2f} | "
                     f"{mean(after, steps):.2f} | {mean(after, steps) / mean(calm, steps):.2f} | "
                     f"{mean(calm, sim):.2f} | {mean(after, sim):.2f} | {mean(after, sim) / mean(calm, sim):.2f} |")
    return lines


def replace_section(path, name, lines):
    begin, end = f"<!-- budget {name} begin -->", f"<!-- budget {name} end -->"
    text = open(path).read()
    if begin not in text or end not in text:
        sys.exit(f"replay_budget: {path} has no {begin} ... {end} section")
    head, rest = text.split(begin, 1)
    open(path, "w").write(head + "\n".join([begin, ""] + lines + ["", end]) + rest.split(end, 1)[1])


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    fluiddemo, replay, async_key = sys.argv[1:4]
    load_before = os.getloadavg()[0]
    command, frames = run_modes(fluiddemo, replay, async_key)
    lines = budget_table(command, frames, async_key)
    lines += ["", f"Around the blasts (every explosive that went off, the {AFTER_BLAST} frames from it on against the "
              "other frames):", ""] + blast_table(frames)
    lines += ["", f"Written by `python3 scripts/replay_budget.py {' '.join(sys.argv[1:4])}` on {len(os.sched_getaffinity(0))} cores, "
              f"load average {load_before:.1f} before and {os.getloadavg()[0]:.1f} after."]
    if len(sys.argv) > 4:
        replace_section(sys.argv[4], os.path.splitext(os.path.basename(replay))[0], lines)
        print(f"replay_budget: written to {sys.argv[4]}")
    else:
        print("\n".join(lines))


if __name__ == "__main__":
    main()
