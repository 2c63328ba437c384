#!/usr/bin/env bash
# Set-up + build + all tests:  scripts/test.sh
# Env: BUILD_DIR (default build/test), FLUIDDEMO_SANITIZE (address|thread), JOBS.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup-deps.sh

build_dir="${BUILD_DIR:-build/test}"
jobs="${JOBS:-$(nproc)}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DFLUIDDEMO_BUILD_TESTS=ON -DFLUIDDEMO_BUILD_BENCHMARKS=ON \
  -DFLUIDDEMO_SANITIZE="${FLUIDDEMO_SANITIZE:-}"
cmake --build "$build_dir" -j "$jobs"
# The smoke and GL tests use Mesa's software rasterizer through SDL's offscreen driver.
export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}"
# The audio effect's live device (rendered runs) uses SDL's dummy driver: no sound card is needed
# and ALSA's "cannot find card" noise stays out of the logs.
export SDL_AUDIODRIVER="${SDL_AUDIODRIVER:-dummy}"
cd "$build_dir"
ctest --output-on-failure -j "$jobs" --timeout 600
