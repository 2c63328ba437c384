#!/usr/bin/env bash
# Set-up + configure + build (Release) + run:  scripts/run.sh [fluiddemo args]
# With no display the fountain runs headless for a bounded number of frames, writes a
# screenshot and prints a timing summary; with a display it opens a window.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup-deps.sh

build_dir="${BUILD_DIR:-build/release}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DFLUIDDEMO_BUILD_TESTS=OFF -DFLUIDDEMO_BUILD_BENCHMARKS=OFF
cmake --build "$build_dir" -j "${JOBS:-$(nproc)}" --target fluiddemo

if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}"
  # Nobody is listening to a run without a display: SDL's dummy audio driver, no sound card needed.
  export SDL_AUDIODRIVER="${SDL_AUDIODRIVER:-dummy}"
  if [ $# -eq 0 ]; then
    mkdir -p out
    echo "run.sh: no display; running the fountain headless (screenshot in out/fountain.png)"
    set -- play fountain --headless --frames 240 --screenshot out/fountain.png
  fi
fi
exec "$build_dir/game/fluiddemo" "$@"
