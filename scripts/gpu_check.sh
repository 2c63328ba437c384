#!/bin/bash
# fluiddemo's GL paths on a real GPU: the headless GL tests and the tour replays with rendering
# (their per-frame CSVs and a screenshot each), the frame budget and the mesher's two-thread gain
# on two pinned CPUs of that machine (16 vCPUs, none of them busy with other work of ours), then the
# GPU benchmarks. Made to run from the bundle
# that scripts/gpu_bundle.sh packs (as .gpurun/run.sh, on a machine with an NVIDIA driver and none of
# our packages; EGL through glvnd, SDL's offscreen driver). Results go to $OUT (default /tmp/gpu_check).
#   usage: .gpurun/run.sh [SECTION...]   (after scripts/gpu_bundle.sh; copy .gpurun, .gl and the repository)
# Sections, all by default, in this order: tests (the gl_* test binaries), tours (rendered on all
# cores), pinned (two pinned cores: the fountain tours and the fountain's frame budget against its
# particle count), mesher (two pinned cores: one and two threads per block size, MESHER_ROUNDS rounds
# over MESHER_BLOCKS), benches (bench_gpu_particles, bench_fluid_render).
cd "$(dirname "$0")/.." || exit 1  # the repository root
OUT=${OUT:-/tmp/gpu_check}
mkdir -p "$OUT"
tar -C .gpurun -xzf .gpurun/payload.tar.gz
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
  for t in gl_engine gl_gpu_particles gl_fluid_render gl_goo_texture gl_fluid_methods; do
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
section_benches() {
  echo "=== bench_gpu_particles"
  timeout 60 $B/bench_gpu_particles --reps 9 2>&1 | tail -14
  echo "=== bench_fluid_render"
  timeout 120 $B/bench_fluid_render --frames 20 --sizes 1280x720 --counts 2500,13000,50000 2>&1 | tail -14
}
sections=${*:-tests tours pinned mesher benches}
{
  nvidia-smi -L
  echo "cores: $(nproc); $(ldd --version | head -1); sections: $sections"
  for section in $sections; do "section_$section"; done
} 2>&1 | tee "$OUT/gpu_check_log.txt"
# At most 8 files come back from the device machine: the per-frame CSVs travel as one archive.
(cd "$OUT" && ls ./*.csv >/dev/null 2>&1 && tar czf frame_csvs.tar.gz ./*.csv && rm -f ./*.csv)
