#!/usr/bin/env python3
"""Writes the blob monster's measurements into README.md.

Behaviours (between the blob_table markers): the `[blob]` lines the unit_blob tests print (tests/blob:
each behaviour reaching its goal in a scripted headless run, asserted there as a number), then those
of any further test executables named (unit_blob_game: the hunt in the game's street, the catch).

    python3 scripts/blob_table.py build/dev/tests/blob/unit_blob [build/dev/tests/game/unit_blob_game ...] [README.md]

Cost (between the blob_cost markers): body step and step + meshing per frame from bench_blob
(250 / 1,000 / 4,000 particles, 1 and 2 threads), and step + meshing per frame in the blob replay
(fluiddemo replay content/replays/blob_tour.replay headless, the CSV's fluid_ms + meshing_ms, with
the goo meshed asynchronously and synchronously, interleaved; plus the meshing worker's time).

    python3 scripts/blob_table.py --cost build/dev/tests/bench/bench_blob build/dev/game/fluiddemo [README.md]
"""
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import replay_budget  # noqa: E402

BEGIN, END = "<!-- blob_table begin -->", "<!-- blob_table end -->"
COST_BEGIN, COST_END = "<!-- blob_cost begin -->", "<!-- blob_cost end -->"


def replace_section(readme, begin, end, lines):
    text = open(readme).read()
    if begin not in text or end not in text:
        sys.exit(f"blob_table: {readme} has no {begin} ... {end} section")
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    open(readme, "w").write(head + "\n".join([begin] + lines + [end]) + tail)


def cost(bench, fluiddemo, readme):
    load_before = os.getloadavg()[0]
    run = subprocess.run([bench, "--benchmark_format=json", "--benchmark_min_time=1"], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"blob_table: {bench} failed (exit {run.returncode}):\n{run.stderr[-2000:]}")
    cases = {}
    for b in json.loads(run.stdout)["benchmarks"]:
        m = re.match(r"BM_(BlobStep|BlobStepAndMesh)/particles:(\d+)/threads:(\d+)", b["name"])
        if m:
            cases[(m.group(1), int(m.group(2)), int(m.group(3)))] = b
    rows = ["| particles | threads | step mean ms | step p95 ms | step + mesh mean ms | step + mesh p95 ms | "
            "step + mesh CPU ms (main thread) | triangles |",
            "|---|---|---|---|---|---|---|---|"]
    for n in (250, 1000, 4000):
        for t in (1, 2):
            step, both = cases.get(("BlobStep", n, t)), cases.get(("BlobStepAndMesh", n, t))
            if step is None or both is None:
                sys.exit(f"blob_table: {bench} gave no case for {n} particles, {t} threads")
            rows.append(f"| {n:,} | {t} | {step['real_time']:.2f} | {step['p95_ms']:.2f} | {both['real_time']:.2f} | "
                        f"{both['p95_ms']:.2f} | {both['cpu_time']:.2f} | {both['triangles']:,.0f} |")
    # The blob replay, its goo meshed asynchronously (the default) and synchronously, interleaved.
    command, frames = replay_budget.run_modes(fluiddemo, "content/replays/blob_tour.replay", "blob.async")
    load_after = os.getloadavg()[0]
    lines = ["", f"Written by `python3 scripts/blob_table.py --cost {bench} {fluiddemo}` on {len(os.sched_getaffinity(0))} cores, "
             f"load average {load_before:.1f} before and {load_after:.1f} after: wall times on a shared machine, "
             "as noisy as that load says (the CPU column, the main thread's CPU time per frame, is the steadier one "
             "for 1 thread).", "",
             "The blob replay (simulation: the body's step and Bullet's crates; with async meshing the worker "
             "meshes beside the render and the next steps, off the main thread):", ""]
    lines += replay_budget.budget_table(command, frames, "blob.async")
    lines += ["", "bench_blob (a body growing four tentacles on the ground; the mesh as the game makes it, synchronously):",
              ""]
    replace_section(readme, COST_BEGIN, COST_END, lines + rows + [""])
    print(f"blob_table: cost table written to {readme}")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    if sys.argv[1] == "--cost":
        if len(sys.argv) < 4:
            sys.exit(__doc__)
        return cost(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else "README.md")
    exes = [a for a in sys.argv[1:] if not a.endswith(".md")]
    readmes = [a for a in sys.argv[1:] if a.endswith(".md")]
    readme = readmes[0] if readmes else "README.md"
    rows = []
    for exe in exes:
        run = subprocess.run([exe], capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"blob_table: {exe} failed (exit {run.returncode}):\n{run.stdout[-2000:]}{run.stderr[-2000:]}")
        for line in run.stdout.splitlines():
            m = re.match(r"\[blob\] ([^:]+): (.*)$", line)
            if m:
                rows.append((m.group(1).strip(), m.group(2).strip().replace("|", "\\|")))
    if not rows:
        sys.exit(f"blob_table: {' '.join(exes)} printed no [blob] lines")
    table = [BEGIN, "", f"Written by `python3 scripts/blob_table.py {' '.join(exes)}` (tests/blob and the blob's game "
             "tests, 1,000 particles unless named).", "",
             "| behaviour / check | measured |", "|---|---|"]
    table += [f"| {name} | {text} |" for name, text in rows]
    table += [""]
    replace_section(readme, BEGIN, END, table[1:])
    print(f"blob_table: {len(rows)} rows written to {readme}")


if __name__ == "__main__":
    main()
