#!/usr/bin/env bash
# replay_outputs.sh FLUIDDEMO SOURCE_DIR WORK_DIR
# The replay command's files and refusals, end to end through the executable (issue 16):
#  - --csv has the documented columns, one row per frame, the state hash on checkpoint rows only;
#  - --png is a PNG of the requested size (IHDR), --screenshot-at writes the frame at the viewport size;
#  - outputs are never replaced without --force (exit 2), and are with it;
#  - --compare of a CSV with itself gives ratios of 1;
#  - a wrong checkpoint hash exits 1 naming the step and the subsystem;
#  - --no-render --mesh meshes every frame without GL, --pace holds the frame rate, and both need
#    --no-render;
#  - play --record writes a replay that replays to its recorded checkpoints, and refuses to overwrite.
set -euo pipefail
exe="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}"
replay="$src/content/replays/crate_yard_tour.replay"
fail() { echo "replay_outputs: FAIL: $*" >&2; exit 1; }

"$exe" replay "$replay" --headless --no-ui --width 160 --height 90 --frames 150 --csv "$work/f.csv" \
  --png "$work/f.png" --plot-width 640 --plot-height 360 --screenshot-at "60:$work/s60.png" > "$work/out.txt"
grep -q "^frame .*p50\|^phase  *p50 ms  *p95 ms  *p99 ms  *max ms" "$work/out.txt" || fail "no percentile table"
grep -q "checkpoints: 1 matched of 4" "$work/out.txt" || fail "checkpoint 150 not matched"

"$exe" scene-keys --columns > "$work/columns.md"
/usr/bin/env python3 - "$work" <<'PY'
import csv, struct, sys, pathlib
work = pathlib.Path(sys.argv[1])
rows = list(csv.reader(open(work / "f.csv")))
# The phases, then every effect's declared columns as `scene-keys --columns` lists them, then the hash.
declared = [line.split("`")[1] for line in open(work / "columns.md") if line.startswith("| `")]
assert "particles" in declared and "triangles" in declared and "blasts" in declared, declared
want = "frame,step,input_ms,physics_ms,fluid_ms,meshing_ms,render_ms,ui_ms,frame_ms".split(",") + declared + ["state_hash"]
assert rows[0] == want, rows[0]
body = rows[1:]
assert len(body) == 150, len(body)
assert [int(r[1]) for r in body] == list(range(1, 151)), "one step per frame"
hashed = [int(r[1]) for r in body if r[-1]]
assert hashed == [150], hashed
assert all(float(r[8]) > 0 for r in body), "frame times"
# The crate yard has no surface to mesh: no triangles, no meshing worker time.
tri, worker = want.index("triangles"), want.index("mesh_worker_ms")
assert all(int(r[tri]) == 0 and float(r[worker]) == 0 for r in body), "a surface in the crate yard"
def png_size(path):
    data = open(path, "rb").read(24)
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    return struct.unpack(">II", data[16:24])
assert png_size(work / "f.png") == (640, 360), png_size(work / "f.png")
assert png_size(work / "s60.png") == (160, 90), png_size(work / "s60.png")
print("replay_outputs: csv 150 rows, plot 640x360, screenshot 160x90")
PY

# Never overwrite without --force; with it, do.
set +e
"$exe" replay "$replay" --headless --no-ui --width 160 --height 90 --frames 5 --csv "$work/f.csv" > "$work/o2.txt" 2>&1
code=$?
set -e
[ "$code" -eq 2 ] && grep -q "f.csv: exists (pass --force" "$work/o2.txt" || fail "--csv overwrote or wrong exit ($code)"
"$exe" replay "$replay" --headless --no-ui --width 160 --height 90 --frames 5 --csv "$work/f.csv" --force > /dev/null
[ "$(wc -l < "$work/f.csv")" -eq 6 ] || fail "--force did not replace the CSV"

"$exe" replay --compare "$work/f.csv" "$work/f.csv" > "$work/cmp.txt"
grep -Eq "^frame +[0-9.]+ +[0-9.]+ +1\.000 " "$work/cmp.txt" || fail "--compare of a file with itself is not 1.000"

# A wrong checkpoint hash: exit 1, naming file:line, the step and the subsystem.
sed 's/^checkpoint 150 \([0-9a-f]*\) rigid_bodies=[0-9a-f]*/checkpoint 150 \1 rigid_bodies=0000000000000000/' \
  "$replay" > "$work/bad.replay"
set +e
"$exe" replay "$work/bad.replay" --no-render > "$work/bad.txt" 2>&1
code=$?
set -e
[ "$code" -eq 1 ] || fail "wrong hash exit $code"
grep -q "bad.replay:[0-9]*: checkpoint at step 150 failed: first differing subsystem 'rigid_bodies'" "$work/bad.txt" \
  || fail "wrong hash message: $(cat "$work/bad.txt")"

# --no-render --mesh: the fountain's surface meshed every frame without GL (triangles and the worker's
# time in the rows, the checkpoints as in a rendered run); --mesh alone is refused.
fountain="$src/content/replays/fountain_tour.replay"
"$exe" replay "$fountain" --no-render --mesh --frames 160 --csv "$work/m.csv" > "$work/m.txt"
grep -q "checkpoints: 1 matched of 5" "$work/m.txt" || fail "--no-render --mesh: $(tail -1 "$work/m.txt")"
/usr/bin/env python3 - "$work/m.csv" <<'PY' || fail "--no-render --mesh rows"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 160, len(rows)
assert all(float(r["triangles"]) > 1000 for r in rows[1:]), [r["triangles"] for r in rows[:5]]
assert sum(float(r["mesh_worker_ms"]) for r in rows) > 0 and sum(float(r["meshing_ms"]) for r in rows) > 0
assert all(float(r["render_ms"]) == 0 for r in rows)
PY
set +e
"$exe" replay "$fountain" --mesh --frames 1 > "$work/m2.txt" 2>&1
code=$?
set -e
[ "$code" -eq 2 ] && grep -q -- "--mesh goes with --no-render" "$work/m2.txt" || fail "--mesh without --no-render ($code)"
# --pace 5: 12 frames take at least 11 frame periods (2.2 s; unpaced they and the load take under 1 s
# here); --pace alone is refused.
start=$(date +%s%N)
"$exe" replay "$fountain" --no-render --mesh --pace 5 --frames 12 > /dev/null
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
[ "$elapsed_ms" -ge 2200 ] || fail "--pace 5 ran 12 frames in $elapsed_ms ms"
set +e
"$exe" replay "$fountain" --pace 60 --frames 1 > "$work/m3.txt" 2>&1
code=$?
set -e
[ "$code" -eq 2 ] && grep -q -- "--pace goes with --no-render" "$work/m3.txt" || fail "--pace without --no-render ($code)"

# play --record -> replay.
"$exe" play crate_yard --headless --no-ui --width 160 --height 90 --frames 130 --record "$work/r.replay" > /dev/null
grep -q "^end 130$" "$work/r.replay" || fail "recording has no end 130"
"$exe" replay "$work/r.replay" --no-render > "$work/r.txt"
grep -q "checkpoints: 3 matched of 3" "$work/r.txt" || fail "recorded replay: $(tail -1 "$work/r.txt")"
set +e
"$exe" play crate_yard --headless --frames 1 --record "$work/r.replay" > "$work/r2.txt" 2>&1
code=$?
set -e
[ "$code" -eq 2 ] && grep -q "exists (pass --force" "$work/r2.txt" || fail "--record overwrote ($code)"
echo "replay_outputs: ok"
