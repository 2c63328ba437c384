#!/usr/bin/env bash
# replay_truth.sh FLUIDDEMO SOURCE_DIR WORK_DIR
# The SPH health columns of the replay CSV (docs/replay.md) against the run summary, through the
# executable (issue 18 item 6): the fountain tour's first 300 steps without GL.
#  - the frames the profiler flagged (the overlay's red markers, counted in the summary's
#    "frames warned") are exactly the rows with warned = 1;
#  - a row warns exactly when a cause is in it: a speed or min-dt clamp, a NaN/inf, or a push-out
#    deeper than one particle radius (the scene's particle_radius, 40 mm);
#  - the summary's totals are the column sums; no NaN/inf anywhere; every frame ran SPH sub-steps.
set -euo pipefail
exe="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
"$exe" replay "$src/content/replays/fountain_tour.replay" --no-render --frames 300 --csv "$work/t.csv" > "$work/out.txt"
/usr/bin/env python3 - "$work" <<'PY'
import csv, re, sys, pathlib
work = pathlib.Path(sys.argv[1])
rows = list(csv.DictReader(open(work / "t.csv")))
assert len(rows) == 300, len(rows)
summary = open(work / "out.txt").read()
m = re.search(r"sph health: (\d+) sub-steps, .*pushed out of colliders (\d+) \(deepest ([0-9.]+) mm\), "
              r"speed clamps (\d+), dt held at min (\d+), dt cut to the step's end (\d+), NaN/inf (\d+); "
              r"frames warned (\d+)", summary)
assert m, summary
steps, pushed, deepest, clamps, mins, cuts, nonfinite, warned = m.groups()
col = lambda k: [float(r[k]) for r in rows]
assert sum(col("sph_steps")) == int(steps), (steps, sum(col("sph_steps")))
assert sum(col("pushed_out")) == int(pushed)
assert abs(max(col("push_depth_mm")) - float(deepest)) < 0.01, (deepest, max(col("push_depth_mm")))
assert sum(col("speed_clamps")) == int(clamps) and sum(col("dt_min_clamps")) == int(mins)
assert sum(col("dt_request_cuts")) == int(cuts)
assert int(nonfinite) == 0 and sum(col("nonfinite")) == 0, "NaN/inf"
assert all(s >= 1 for s in col("sph_steps")), "a frame without SPH sub-steps"
assert all(float(r["density_err_max"]) >= float(r["density_err_p99"]) >= 0 for r in rows)
assert all(float(r["density_err_max"]) >= float(r["density_err_mean"]) for r in rows)
flagged = [r["frame"] for r in rows if r["warned"] == "1"]
assert len(flagged) == int(warned), (flagged, warned)
def cause(r):
    return (float(r["push_depth_mm"]) > 40.0 or int(r["speed_clamps"]) > 0 or int(r["dt_min_clamps"]) > 0
            or int(r["nonfinite"]) > 0)
bad = [r["frame"] for r in rows if (r["warned"] == "1") != cause(r)]
assert not bad, bad
print(f"replay_truth: 300 frames, {steps} sub-steps, {pushed} push-outs (deepest {deepest} mm), "
      f"flagged frames {flagged}")
PY
