#!/usr/bin/env python3
"""The graphics presets measured (issue 35 item 5): the fountain tour replayed at 1280x720 with each
preset, the runs interleaved (low, medium, high, low, ...), frame and render p50 per preset from the
replay CSVs, and a picture of each preset at the same step (written at 1280x720, stored at 640x360).

Usage: /usr/bin/python3 scripts/preset_table.py FLUIDDEMO REPLAY [README]
Without README the table is printed; with it, the section between <!-- presets begin --> and
<!-- presets end --> is replaced and the pictures go to docs/images/preset_<name>.png.
Needs python3-pil for the pictures' downscale.
"""
import csv
import os
import subprocess
import sys
import tempfile

PRESETS = ["low", "medium", "high"]
SIZE = (1280, 720)
FRAMES = 600  # the tour's first 10 s: the walk, two crates, the jet running
SHOT_STEP = 590
ROUNDS = 2
SKIP = 60  # the first second (shader compiles, first meshes) is not the steady frame


def median(values):
    values = sorted(values)
    n = len(values)
    return 0.5 * (values[(n - 1) // 2] + values[n // 2])


def run(fluiddemo, replay, preset, csv_path, png_path):
    cmd = [fluiddemo, "replay", replay, "--headless", "--no-ui", "--width", str(SIZE[0]), "--height", str(SIZE[1]),
           "--threads", "2", "--frames", str(FRAMES), "--set", f"graphics.preset={preset}", "--csv", csv_path,
           "--force"]
    if png_path:
        cmd += ["--screenshot-at", f"{SHOT_STEP}:{png_path}"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"preset_table: {' '.join(cmd)} failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
    # "renderer: NAME (graphics PRESET, scene WxH)": the run's own account of what it drew at.
    line = next((line.split(": ", 1)[1] for line in done.stdout.splitlines() if line.startswith("renderer: ")), "? (?)")
    renderer, graphics = line.rsplit(" (", 1)
    return list(csv.DictReader(open(csv_path)))[SKIP:], renderer, graphics.rstrip(")").split("scene ")[-1]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    fluiddemo, replay = sys.argv[1:3]
    readme = sys.argv[3] if len(sys.argv) > 3 else None
    load_before = os.getloadavg()[0]
    rows = {p: [] for p in PRESETS}
    drawn_at = {}
    renderer = "?"
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(ROUNDS):
            for preset in PRESETS:
                png = os.path.join(tmp, f"{preset}.png") if round_ == 0 else None
                got, renderer, drawn_at[preset] = run(fluiddemo, replay, preset,
                                                      os.path.join(tmp, f"{preset}{round_}.csv"), png)
                rows[preset] += got
        if readme:
            from PIL import Image
            for preset in PRESETS:
                Image.open(os.path.join(tmp, f"{preset}.png")).resize((640, 360), Image.LANCZOS).save(
                    os.path.join(os.path.dirname(os.path.abspath(readme)), "docs", "images", f"preset_{preset}.png"))
    lines = [f"`fluiddemo replay {replay} --headless --no-ui --width {SIZE[0]} --height {SIZE[1]} --threads 2 "
             f"--frames {FRAMES} --set graphics.preset=P --csv OUT.csv`, {ROUNDS} runs per preset interleaved, "
             f"frames {SKIP}..{FRAMES - 1} of each; renderer {renderer}:", "",
             "| preset | scene rendered at | frame p50 (ms) | render p50 (ms) | simulation p50 (ms) | triangles p50 | "
             "sprites p50 |", "|---|---|---|---|---|---|---|"]
    for preset in PRESETS:
        r = rows[preset]
        frame = median([float(x["frame_ms"]) for x in r])
        render = median([float(x["render_ms"]) for x in r])
        sim = median([float(x["physics_ms"]) + float(x["fluid_ms"]) for x in r])
        tris = median([float(x["triangles"]) for x in r])
        sprites = median([float(x["sprites"]) for x in r])
        lines.append(f"| {preset} | {drawn_at[preset]} | {frame:.1f} | {render:.1f} | {sim:.1f} | {tris:.0f} | {sprites:.0f} |")
    lines += ["", "| low | medium | high |", "|---|---|---|",
              "| " + " | ".join(f"![{p}](docs/images/preset_{p}.png)" for p in PRESETS) + " |", "",
              f"Pictures: step {SHOT_STEP} of the same runs, written at {SIZE[0]}x{SIZE[1]} and stored at 640x360. "
              f"Written by `/usr/bin/python3 scripts/preset_table.py {' '.join(sys.argv[1:4])}` on {len(os.sched_getaffinity(0))} "
              f"cores, load average {load_before:.1f} before and {os.getloadavg()[0]:.1f} after."]
    if not readme:
        print("\n".join(lines))
        return
    begin, end = "<!-- presets begin -->", "<!-- presets end -->"
    text = open(readme).read()
    if begin not in text or end not in text:
        sys.exit(f"preset_table: {readme} has no {begin} ... {end} section")
    head, rest = text.split(begin, 1)
    open(readme, "w").write(head + "\n".join([begin, ""] + lines + ["", end]) + rest.split(end, 1)[1])
    print(f"preset_table: written to {readme}")


if __name__ == "__main__":
    main()
