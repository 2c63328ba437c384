#!/usr/bin/env bash
# Regenerates docs/render.md (tables by bench_fluid_render) and its pictures: the fountain scene
# with each fluid_surface.method (docs/images/fountain_*.png, also shown in README.md) and the
# bench's static set (docs/images/render_*.png). llvmpipe: about 10 minutes on 2 cores.
#   usage: tests/bench/render_docs.sh [BUILD_DIR (default build/dev)] [TIMED_FRAMES (default 1)]
set -euo pipefail
build=${1:-build/dev}
frames=${2:-1}
cd "$(dirname "$0")/../.."
export SDL_VIDEODRIVER=offscreen
for method in mesh screen_space raycast; do
  "$build/game/fluiddemo" play fountain --headless --frames 240 --width 640 --height 360 \
    --set fluid_surface.method=$method --screenshot docs/images/fountain_$method.png > /dev/null
done
{
  cat tests/bench/render_docs_head.md
  echo
  echo "Command: \`tests/bench/render_docs.sh $build $frames\` (load average at the start: $(cut -d' ' -f1 /proc/loadavg))"
  echo
  "$build/tests/bench/bench_fluid_render" --frames "$frames" --png docs/images
  echo
  cat tests/bench/render_docs_tail.md
} > docs/render.md.tmp
mv docs/render.md.tmp docs/render.md
