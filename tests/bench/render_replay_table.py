#!/usr/bin/env python3
"""The fountain tour per fluid_surface.method (docs/render.md, tests/bench/render_docs.sh).

Reads the runs render_docs.sh left in DIR: per size WxH and method M (mesh, screen_space, raycast,
and `none` = the same replay with fluid_surface.visible=false, the water-free frame),
  DIR/WxH.M.csv   the replay's per-frame CSV (docs/replay.md columns)
  DIR/WxH.M.txt   its stdout (checkpoints, the raycast pool line)
  DIR/WxH.M.load  load average before and after the run
  DIR/WxH.M.STEP.png  the frame after STEP steps (--screenshot-at)
and prints the markdown: p50/p95 of frame_ms, render_ms and meshing_ms, the checkpoints, and per
method against mesh on the same frames: PSNR over RGB and the IoU of the water masks (pixels whose
RGB differs from the water-free frame by more than 2/255 in any channel).
usage: render_replay_table.py DIR SIZES STEPS   (SIZES "640x360 1280x720", STEPS "150 225 300")
"""
import csv
import math
import re
import sys

import numpy as np
from PIL import Image

METHODS = ["mesh", "screen_space", "raycast"]


def nearest_rank(values, q):  # the percentiles fluiddemo replay prints
    s = sorted(values)
    return s[max(1, min(len(s), math.ceil(q * len(s)))) - 1]


def image(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.float64)


def psnr(a, b):
    mse = np.mean((a - b) ** 2)
    return float("inf") if mse == 0 else 10.0 * math.log10(255.0**2 / mse)


def mask(shot, backdrop):
    return np.any(np.abs(shot - backdrop) > 2.0, axis=2)


def main():
    tmp, sizes, steps = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
    print("| size | method | frames | frame p50 ms | frame p95 ms | render p50 ms | render p95 ms "
          "| meshing p50 ms | PSNR vs mesh dB | water IoU vs mesh | water pixels | checkpoints | load before / after |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    pool_lines = []
    for size in sizes:
        backdrop = {s: image(f"{tmp}/{size}.none.{s}.png") for s in steps}
        ref = {s: image(f"{tmp}/{size}.mesh.{s}.png") for s in steps}
        ref_mask = {s: mask(ref[s], backdrop[s]) for s in steps}
        for method in ["none"] + METHODS:
            rows = list(csv.DictReader(open(f"{tmp}/{size}.{method}.csv")))
            frame = [float(r["frame_ms"]) for r in rows]
            render = [float(r["render_ms"]) for r in rows]
            meshing = [float(r["meshing_ms"]) for r in rows]
            text = open(f"{tmp}/{size}.{method}.txt").read()
            checks = re.search(r"^checkpoints: (\d+) matched of (\d+)", text, re.M)
            checks = f"{checks.group(1)} matched" if checks else "?"
            load = open(f"{tmp}/{size}.{method}.load").read().strip()
            if method in ("none", "mesh"):
                psnr_text, iou_text = "-", "-"
            else:
                shots = {s: image(f"{tmp}/{size}.{method}.{s}.png") for s in steps}
                psnr_text = " / ".join(f"{psnr(shots[s], ref[s]):.2f}" for s in steps)
                ious = []
                for s in steps:
                    m = mask(shots[s], backdrop[s])
                    union = np.logical_or(m, ref_mask[s]).sum()
                    ious.append(np.logical_and(m, ref_mask[s]).sum() / union if union else 1.0)
                iou_text = " / ".join(f"{v:.3f}" for v in ious)
            if method == "none":
                pixels = "-"
            else:
                shot = ref if method == "mesh" else {s: image(f"{tmp}/{size}.{method}.{s}.png") for s in steps}
                pixels = " / ".join(str(int(mask(shot[s], backdrop[s]).sum())) for s in steps)
            name = "none (water hidden)" if method == "none" else method
            print(f"| {size} | {name} | {len(rows)} | {nearest_rank(frame, 0.5):.1f} | {nearest_rank(frame, 0.95):.1f} "
                  f"| {nearest_rank(render, 0.5):.1f} | {nearest_rank(render, 0.95):.1f} "
                  f"| {nearest_rank(meshing, 0.5):.1f} | {psnr_text} | {iou_text} | {pixels} | {checks} | {load} |")
            pool = re.search(r"^raycast: (.*)$", text, re.M)
            if method == "raycast" and pool:
                pool_lines.append(f"- {size}: {pool.group(1)}")
    print()
    print("Ray caster's fragment pool over the same runs (the `raycast:` line of `fluiddemo replay`; the pool "
          "grows to 1.25x a frame's demand, up to its bound):")
    print()
    for line in pool_lines:
        print(line)


if __name__ == "__main__":
    main()
