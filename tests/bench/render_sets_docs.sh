#!/usr/bin/env bash
# Writes docs/render.md's section "Particle sets of 50k to 4M: four methods" (issue 37) and its
# pictures with one command, between the markers <!-- render_sets_docs.sh begin/end --> (appended
# at the end of the page when they are missing; the rest of the page is left as it is):
#  1. scripts/make_render_sets.py makes a settled pool with a splash and a spray cloud of each SIZE
#     (kept in BUILD_DIR/render_sets between runs);
#  2. `fluiddemo render` draws each set with none (the backdrop alone), mesh, screen_space, raycast
#     and voxel at WxH, one timed frame after a warm-up, each stage ended by glFinish;
#  3. the voxel method on the 1M pool with the tile sizes of the paper's Table 1 scaled to WxH;
#  4. tests/bench/render_sets_table.py: the tables, PSNR and water-mask IoU vs the mesh, and the
#     2x2 pictures docs/images/render_sets_*.png.
# The mesh is run up to MESH_MAX particles; any run is stopped after RUN_LIMIT seconds (env, 180):
# the mesh's CPU extraction of the 4M spray took 16.5 GiB resident after 4 minutes.
#   usage: tests/bench/render_sets_docs.sh [BUILD_DIR (build/dev)] [W (480)] [H (270)] [SIZES (50000,1000000,4000000)] [MESH_MAX (4000000)]
set -euo pipefail
build=${1:-build/dev}
width=${2:-480}
height=${3:-270}
sizes=${4:-50000,1000000,4000000}
mesh_max=${5:-4000000}
run_limit=${RUN_LIMIT:-180}
cd "$(dirname "$0")/../.."
export SDL_VIDEODRIVER=offscreen SDL_AUDIODRIVER=dummy
PYTHON=/usr/bin/python3
[ -x "$PYTHON" ] || PYTHON=python3
exe="$build/game/fluiddemo"
sets_dir="$build/render_sets"
run=$(mktemp -d)
trap 'rm -rf "$run"' EXIT
start=$(date +%s)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
"$PYTHON" scripts/make_render_sets.py "$sets_dir" --sizes "$sizes" > "$run/make_sets.txt"
# timed NAME ARGS...: runs fluiddemo render, keeps its output and wall seconds; a run past
# RUN_LIMIT seconds is stopped, its peak resident memory (VmHWM) read from /proc just before.
timed() {
  local name="$1"; shift
  local t0 t1 code=0 pid hwm="" elapsed=0
  t0=$(date +%s%N)
  "$exe" render "$@" --force > "$run/$name.txt" 2>&1 &
  pid=$!
  while kill -0 "$pid" 2> /dev/null; do
    sleep 1
    elapsed=$((elapsed + 1))
    if [ "$elapsed" -ge "$run_limit" ]; then
      hwm=$(awk '/VmHWM/ {printf "%.0f", $2 / 1024}' "/proc/$pid/status" 2> /dev/null || true)
      kill -9 "$pid" 2> /dev/null || true
      break
    fi
  done
  wait "$pid" || code=$?
  t1=$(date +%s%N)
  local tenths=$(( (t1 - t0) / 100000000 ))
  local seconds="$((tenths / 10)).$((tenths % 10))"
  if [ -n "$hwm" ]; then
    echo "$seconds stopped at the ${run_limit} s limit, resident memory then $hwm MiB" > "$run/$name.seconds"
    rm -f "$run/$name.png"
  elif [ "$code" -ne 0 ]; then
    echo "$seconds failed (exit $code): $(tail -1 "$run/$name.txt")" > "$run/$name.seconds"
    rm -f "$run/$name.png"
  else
    echo "$seconds" > "$run/$name.seconds"
  fi
}
for n in ${sizes//,/ }; do
  for kind in pool spray; do
    set_name="${kind}_$n"
    for method in none mesh screen_space raycast voxel; do
      if [ "$method" = mesh ] && [ "$n" -gt "$mesh_max" ]; then
        echo "- skipped (over MESH_MAX $mesh_max)" > "$run/$set_name.$method.seconds"
        continue
      fi
      timed "$set_name.$method" --in "$sets_dir/$set_name.xyz" --method "$method" --out "$run/$set_name.$method.png" \
        --width "$width" --height "$height"
    done
  done
done
# Table 1 (the paper's tiles on 1920x1080: 128^2 .. 1024^2) on this machine, scaled to WxH.
tiles_set="$sets_dir/pool_1000000.xyz"
[ -e "$tiles_set" ] || tiles_set="$sets_dir/pool_${sizes%%,*}.xyz"
for tile in 32x32 64x64 128x128 $((width / 2))x$((height / 2)) ${width}x${height}; do
  timed "tiles.$tile" --in "$tiles_set" --method voxel --out "$run/tiles.png" --width "$width" --height "$height" \
    --tile-size "$tile"
done
timed "inner.voxel" --in "$tiles_set" --method voxel --out "$run/inner.png" --width "$width" --height "$height" \
  --drop-inner-cells
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
renderer=$(sed -n 's/^render none: .*, GL \(.*\)$/\1/p' "$run/pool_${sizes%%,*}.none.txt" | head -1)
tables=$("$PYTHON" tests/bench/render_sets_table.py "$run" docs/images)
elapsed=$(( $(date +%s) - start ))
section="$run/section.md"
{
  echo "<!-- render_sets_docs.sh begin -->"
  sed -e "s|@W@|$width|g" -e "s|@H@|$height|g" tests/bench/render_sets_docs_head.md
  echo
  echo "Command: \`RUN_LIMIT=$run_limit tests/bench/render_sets_docs.sh $build $width $height $sizes $mesh_max\` ($elapsed s in all);"
  echo "GL: $renderer; load average before / after: $load_before / $load_after. Sets:"
  echo
  sed 's/^/- /' "$run/make_sets.txt"
  echo
  echo "$tables"
  echo
  echo "Voxel with full inner cells left out (§4.3, \`--drop-inner-cells\`, cells of 3 spacings, full at 1/2 of the median occupied cell's count, each inner cell splatted as one sphere):"
  echo
  grep -E "splat|compress|particles splatted|draw " "$run/inner.voxel.txt" | sed 's/^ */- /'
  echo
  sed -e "s|@W@|$width|g" -e "s|@H@|$height|g" tests/bench/render_sets_docs_tail.md
  echo "<!-- render_sets_docs.sh end -->"
} > "$section"
"$PYTHON" - "$section" docs/render.md <<'PY'
import sys
section, page = open(sys.argv[1]).read(), sys.argv[2]
text = open(page).read()
begin, end = "<!-- render_sets_docs.sh begin -->", "<!-- render_sets_docs.sh end -->"
if begin in text and end in text:
    text = text[:text.index(begin)] + section.rstrip("\n") + text[text.index(end) + len(end):]
else:
    text = text.rstrip("\n") + "\n\n" + section
open(page + ".tmp", "w").write(text if text.endswith("\n") else text + "\n")
PY
mv docs/render.md.tmp docs/render.md
echo "docs/render.md: section written ($elapsed s)"
