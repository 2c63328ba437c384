#!/usr/bin/env bash
# Regenerates docs/render.md and its pictures with one command:
#  1. the committed fountain tour (content/replays/fountain_tour.replay) replayed once per
#     fluid_surface.method at 640x360 and 1280x720 (`fluiddemo replay --set`, render-only keys, so
#     every checkpoint still gates), plus once with the water hidden (the water-free frames the
#     masks are taken against); per-frame CSVs and screenshots go through
#     tests/bench/render_replay_table.py (p50/p95 frame and render ms, PSNR and water-mask IoU vs mesh);
#     docs/images/fountain_*.png (also in README.md) are the 640x360 frames at the last step;
#  2. bench_fluid_render's static 2.5k / 13k / 50k particle sets (docs/images/render_*.png).
# The replays render only their first REPLAY_FRAMES steps: llvmpipe takes seconds per ray-cast frame.
#   usage: tests/bench/render_docs.sh [BUILD_DIR (build/dev)] [TIMED_FRAMES (1)] [REPLAY_FRAMES (300)]
set -euo pipefail
build=${1:-build/dev}
frames=${2:-1}
replay_frames=${3:-300}
cd "$(dirname "$0")/../.."
export SDL_VIDEODRIVER=offscreen
PYTHON=/usr/bin/python3
[ -x "$PYTHON" ] || PYTHON=python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
exe="$build/game/fluiddemo"
steps="$((replay_frames / 2)) $((replay_frames * 3 / 4)) $replay_frames"
sizes="640x360 1280x720"
for size in $sizes; do
  for method in none mesh screen_space raycast; do
    sets=(--set "fluid_surface.method=$method")
    [ "$method" = none ] && sets=(--set fluid_surface.method=screen_space --set fluid_surface.visible=false)
    shots=()
    for s in $steps; do shots+=(--screenshot-at "$s:$tmp/$size.$method.$s.png"); done
    before=$(cut -d' ' -f1-3 /proc/loadavg)
    "$exe" replay content/replays/fountain_tour.replay --headless --no-ui --set graphics.preset=high \
      --width "${size%x*}" --height "${size#*x}" \
      --frames "$replay_frames" "${sets[@]}" "${shots[@]}" --csv "$tmp/$size.$method.csv" > "$tmp/$size.$method.txt"
    echo "$before / $(cut -d' ' -f1-3 /proc/loadavg)" > "$tmp/$size.$method.load"
  done
done
last=${steps##* }
for method in mesh screen_space raycast; do cp "$tmp/640x360.$method.$last.png" "docs/images/fountain_$method.png"; done
renderer=$(sed -n 's/^renderer: //p' "$tmp/640x360.mesh.txt")
{
  cat tests/bench/render_docs_head.md
  echo
  echo "Command: \`tests/bench/render_docs.sh $build $frames $replay_frames\`; GL: $renderer; the first"
  echo "$replay_frames steps of the tour (of 1200; the pool starts full, crates are thrown from step 120, the first explosive at step 420),"
  echo "one step per frame, every frame rendered; PSNR and IoU on the frames after steps $(echo "$steps" | sed 's/ / \/ /g')."
  echo
  "$PYTHON" tests/bench/render_replay_table.py "$tmp" "$sizes" "$steps"
  echo
  cat tests/bench/render_docs_sets.md
  echo
  echo "Command: \`tests/bench/render_docs.sh $build $frames $replay_frames\` (load average at the start: $(cut -d' ' -f1-3 /proc/loadavg))"
  echo
  "$build/tests/bench/bench_fluid_render" --frames "$frames" --png docs/images
  echo
  echo "Load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo
  cat tests/bench/render_docs_tail.md
  # The large sets' section (tests/bench/render_sets_docs.sh) has its own command: kept as it is.
  if grep -q '^<!-- render_sets_docs.sh begin -->' docs/render.md; then
    echo
    sed -n '/^<!-- render_sets_docs.sh begin -->/,/^<!-- render_sets_docs.sh end -->/p' docs/render.md
  fi
} > docs/render.md.tmp
mv docs/render.md.tmp docs/render.md
