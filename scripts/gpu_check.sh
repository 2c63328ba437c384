#!/bin/bash
# fluiddemo's GL paths on a real GPU: the headless GL tests and the tour replays with rendering
# (their per-frame CSVs and a screenshot each), the frame budget and the mesher's two-thread gain
# on two pinned CPUs of that machine (16 vCPUs, none of them busy with other work of ours), then the
# GPU benchmarks. Made to run from the bundle
# that scripts/gpu_bundle.sh packs (as .gpurun/run.sh, on a machine with an NVIDIA driver and none of
# our packages; EGL through glvnd, SDL's offscreen driver). Results go to $OUT (default /tmp/gpu_check).
#   usage: .gpurun/run.sh [SECTION...]   (after scripts/gpu_bundle.sh; copy .gpurun, .gl and the repository)
# Sections, all by default, in this order: tests (the gl_* test binaries), tours (rendered on all
# cores), pinned (two pinned cores: the fountain tour rendered and its frame budget table,
# REPLAY_BUDGET_ROUNDS runs per mode, default 1), sweep (two pinned cores: the fountain's frame budget
# against its particle count), mesher (two pinned cores: one and two threads per block size,
# MESHER_ROUNDS rounds over MESHER_BLOCKS), render (the voxel method's Table 1 and each method on a million particles at
# 1920x1080), benches (bench_gpu_particles, bench_fluid_render).
cd "$(dirname "$0")/.." || exit 1  # the repository root
OUT=${OUT:-/tmp/gpu_check}
mkdir -p "$OUT"
tar -C .gpurun -xJf .gpurun/payload.tar.xz
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
nvidia_egl=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f $nvidia_egl ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$nvidia_egl
export LD_LIBRARY_PATH=$PWD/.gpurun/lib SDL_VIDEODRIVER=offscreen SDL_AUDIODRIVER=dummy
# The test binaries find content/ and shaders/ through the source path they were built in.
src=$(cat .gpurun/source_dir)
[ -n "$src" ] && [ ! -e "$src" ] && mkdir -p "$(dirname "$src")" && ln -sfn "$PWD" "$src"
B=.gpurun/bin
# Two logical CPUs on different physical cores (not cpu 0, which takes the interrupts): the 2-core
# budget of issue 18 item 5 and the two-thread bar of issue 20, measured where nothing else runs.
pick_two_cores() {
  local first=2 second
  local siblings=/sys/devices/system/cpu/cpu$first/topology/thread_siblings_list
  for c in $(seq 3 $(($(nproc) - 1))); do
    if ! grep -qE "(^|[,-])$c([,-]|$)" "$siblings" 2>/dev/null; then second=$c; break; fi
  done
  echo "$first,${second:-3}"
}
# The fountain's particle counts for the budget sweep (after the scene's own 2,500 of 0.04 m), each at the
# default's water volume, r = 0.04 m (2500 / N)^(1/3) (13,000: 0.023 m): bench_game_fountain fills each
# to a second of jet short of its budget, then times 300 frames.
sweep_configs() {
  local n r
  for n in 4000 6000 9000 13000; do
    r=$(awk -v n=$n 'BEGIN { printf "%.3f", 0.04 * (2500 / n) ^ (1 / 3) }')
    printf -- '--config max_particles=%s,particle_radius=%s ' "$n" "$r"
  done
}
section_tests() {
  : >"$OUT/gl_tests.txt"
  local t
  for t in $(cd $B && ls gl_*); do
    echo "=== $t"
    # Every line to the log; failures and the summary to the screen.
    timeout 120 $B/$t --gtest_brief=1 >/tmp/gl_test.txt 2>&1
    echo "exit $?"
    { echo "=== $t"; cat /tmp/gl_test.txt; } >>"$OUT/gl_tests.txt"
    grep -v '^\[ metric' /tmp/gl_test.txt | tail -25
  done
}
section_tours() {
  local tour shot
  for tour in fountain_tour:600 blob_tour:400; do
    IFS=: read -r tour shot <<<"$tour"
    echo "=== $tour (rendered, all cores)"
    timeout 150 $B/fluiddemo replay content/replays/$tour.replay --csv "$OUT/gpu_$tour.csv" \
      --screenshot-at $shot:"$OUT/gpu_${tour}_$shot.png" 2>&1 | tail -22
  done
}
section_pinned() {
  command -v taskset >/dev/null || { echo "=== pinned: no taskset, skipped"; return; }
  local cores pin tour round t set name cube reps block
  cores=$(pick_two_cores)
  pin="taskset -c $cores"
  echo "=== pinned to cpus $cores: $(lscpu 2>/dev/null | grep -m1 'Model name')"
  for tour in fountain_tour; do
    echo "=== $tour on 2 pinned cores (rendered, async meshing)"
    timeout 150 $pin $B/fluiddemo replay content/replays/$tour.replay --threads 2 \
      --csv "$OUT/pinned_$tour.csv" 2>&1 | tail -12
  done
  echo "=== fountain_tour's frame budget on 2 pinned cores (scripts/replay_budget.py, as the README's on this project's VM)"
  REPLAY_BUDGET_ROUNDS=${REPLAY_BUDGET_ROUNDS:-1} PYTHONUNBUFFERED=1 timeout 300 $pin python3 scripts/replay_budget.py $B/fluiddemo \
    content/replays/fountain_tour.replay fluid_surface.async | tee "$OUT/budget_2cores.md"
}
section_sweep() {
  command -v taskset >/dev/null || { echo "=== sweep: no taskset, skipped"; return; }
  local cores pin
  cores=$(pick_two_cores)
  pin="taskset -c $cores"
  echo "=== pinned to cpus $cores: $(lscpu 2>/dev/null | grep -m1 'Model name')"
  echo "=== bench_game_fountain, SPH + async meshing against the particle count, on 2 pinned cores (issue 18 item 5)"
  # shellcheck disable=SC2046
  timeout 300 $pin $B/bench_game_fountain --threads 2 --frames 300 --mesh 1 \
    --set sph_fluid.max_particles=2500 $(sweep_configs) 2>&1 | grep '^|'
}
section_mesher() {
  command -v taskset >/dev/null || { echo "=== mesher: no taskset, skipped"; return; }
  local cores pin round block t set name cube reps
  cores=$(pick_two_cores)
  pin="taskset -c $cores"
  echo "=== pinned to cpus $cores: $(lscpu 2>/dev/null | grep -m1 'Model name')"
  echo "=== mesher, 1 and 2 threads on 2 pinned cores, interleaved, per block size (issue 20 bar 2)"
  for round in $(seq "${MESHER_ROUNDS:-3}"); do
    for block in ${MESHER_BLOCKS:-0 64 32}; do
      for t in 1 2; do
        for set in explosion:0.6:41 spray:1:21; do
          IFS=: read -r name cube reps <<<"$set"
          printf '%s block %s threads %s round %s: ' "$name" "$block" "$t" "$round"
          $pin $B/fluiddemo mesh --in .gpurun/data/$name.xyz --cube "$cube" --reps "$reps" --threads "$t" \
            --block "$block" --out /tmp/mesh.obj --force 2>&1 | grep warm
        done
      done
    done
  done
}
# Zirr & Dachsbacher Table 1 on the GPU: the voxel method on a million-particle pool at 1920x1080 per
# tile size (the paper's 128² to 1024x512, and the whole screen), §4.3's inner cells left out, and each
# water method on the same set (scripts/make_render_sets.py; stage times are the mean of the timed frames).
section_render() {
  local set=/tmp/render_sets/pool_1000000.xyz tile method
  local keep='render |draw|splat|compress|connect|filter|normals|shade|extract|upload|tiles|splatted|memory'
  python3 scripts/make_render_sets.py /tmp/render_sets --sizes 1000000 | grep pool
  for tile in 128x128 256x256 512x512 1024x512 1920x1080; do
    echo "=== voxel, tile $tile"
    timeout 40 $B/fluiddemo render --in $set --method voxel --width 1920 --height 1080 --tile-size $tile \
      --frames 5 --out /tmp/render.png --force 2>&1 | grep -E "$keep"
  done
  echo "=== voxel, the budget's tiles, full inner cells left out"
  timeout 40 $B/fluiddemo render --in $set --method voxel --width 1920 --height 1080 --drop-inner-cells \
    --frames 5 --out /tmp/render.png --force 2>&1 | grep -E "$keep"
  for method in voxel screen_space raycast mesh; do
    echo "=== method $method"
    # At most 8 files come back: the pictures of two methods.
    local picture=/tmp/render.png
    [[ $method == voxel || $method == mesh ]] && picture="$OUT/pool1m_$method.png"
    timeout 60 $B/fluiddemo render --in $set --method $method --width 1920 --height 1080 --frames 3 \
      --out "$picture" --force 2>&1 | grep -E "$keep"
  done
}
section_benches() {
  echo "=== bench_gpu_particles"
  timeout 60 $B/bench_gpu_particles --reps 9 2>&1 | tail -14
  echo "=== bench_fluid_render"
  timeout 120 $B/bench_fluid_render --frames 20 --sizes 1280x720 --counts 2500,13000,50000 2>&1 | tail -14
}
sections=${*:-tests tours pinned sweep mesher render benches}
{
  nvidia-smi -L
  echo "cores: $(nproc); $(ldd --version | head -1); sections: $sections"
  for section in $sections; do "section_$section"; done
} 2>&1 | tee "$OUT/gpu_check_log.txt"
# At most 8 files come back from the device machine: the per-frame CSVs travel as one archive.
(cd "$OUT" && ls ./*.csv >/dev/null 2>&1 && tar czf frame_csvs.tar.gz ./*.csv && rm -f ./*.csv)
