#!/bin/bash
# fluiddemo's GL paths on a real GPU: the headless GL tests and the two tour replays with rendering
# (their per-frame CSVs and a screenshot each), then the GPU benchmarks. Made to run from the bundle
# that scripts/gpu_bundle.sh packs (as .gpurun/run.sh, on a machine with an NVIDIA driver and none of
# our packages; EGL through glvnd, SDL's offscreen driver). Results go to $OUT (default /tmp/gpu_check).
#   usage: .gpurun/run.sh     (after scripts/gpu_bundle.sh; copy .gpurun, .gl and the repository)
cd "$(dirname "$0")/.." || exit 1  # the repository root
OUT=${OUT:-/tmp/gpu_check}
mkdir -p "$OUT"
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
nvidia_egl=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f $nvidia_egl ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_egl
export LD_LIBRARY_PATH=$PWD/.gpurun/lib SDL_VIDEODRIVER=offscreen
# The test binaries find content/ and shaders/ through the source path they were built in.
src=$(cat .gpurun/source_dir)
[ -n "$src" ] && [ ! -e "$src" ] && mkdir -p "$(dirname "$src")" && ln -sfn "$PWD" "$src"
B=.gpurun/bin
: >"$OUT/gl_tests.txt"
{
  nvidia-smi -L
  echo "cores: $(nproc); $(ldd --version | head -1)"
  for t in gl_engine gl_gpu_particles gl_fluid_render gl_goo_texture gl_fluid_methods; do
    echo "=== $t"
    # Every line to the log; failures and the summary to the screen.
    timeout 120 $B/$t --gtest_brief=1 >/tmp/gl_test.txt 2>&1
    echo "exit $?"
    { echo "=== $t"; cat /tmp/gl_test.txt; } >>"$OUT/gl_tests.txt"
    grep -v '^\[ metric' /tmp/gl_test.txt | tail -25
  done
  echo "=== fountain_tour (rendered)"
  timeout 150 $B/fluiddemo replay content/replays/fountain_tour.replay --csv "$OUT/gpu_fountain_tour.csv" \
    --screenshot-at 600:"$OUT/gpu_fountain_600.png" 2>&1 | tail -22
  echo "=== blob_tour (rendered)"
  timeout 100 $B/fluiddemo replay content/replays/blob_tour.replay --csv "$OUT/gpu_blob_tour.csv" \
    --screenshot-at 400:"$OUT/gpu_blob_400.png" 2>&1 | tail -22
  echo "=== bench_gpu_particles"
  timeout 60 $B/bench_gpu_particles --reps 9 2>&1 | tail -14
  echo "=== bench_fluid_render"
  timeout 120 $B/bench_fluid_render --frames 20 --sizes 1280x720 --counts 2500,13000,50000 2>&1 | tail -14
} 2>&1 | tee "$OUT/gpu_check_log.txt"
