#!/bin/sh
# Regenerates docs/sph.md from the fluid/sph benchmarks. Usage (from the repository root, after a
# Release build in build/dev):   tests/bench/sph_docs.sh [BOX_SECONDS]
# BOX_SECONDS is the simulated window of the dambreak_box runs (default 2, as in SPlisHSPlasH's
# figures; shorter windows are cheaper but cover less of the flow).
set -eu
BENCH=build/dev/tests/bench/bench_sph
BOX_SECONDS=${1:-2}
OUT=docs/sph.md
mkdir -p docs
tmp=$(mktemp -d)
"$BENCH" accuracy --csv docs/sph_accuracy.csv > "$tmp/accuracy.md"
scripts/plots/sph_accuracy.py docs/sph_accuracy.csv docs/sph_accuracy.png
"$BENCH" front > "$tmp/front.md"
"$BENCH" throughput --steps 20 > "$tmp/throughput.md"
"$BENCH" seeds --from 1 --to 300 > "$tmp/seeds.txt"
"$BENCH" dambreak_box --seconds "$BOX_SECONDS" --threads 12 > "$tmp/box.md"
# The game aim on the game's own fountain (content/scenes/fountain.json as the game builds it); the
# second row is the same scene with fluid::SphParams' defaults for the four solver knobs.
GAME_DEFAULTS="cfl=0.4,max_time_step=0.005,density_error=0.0005,force_bound=0.0025"
build/dev/tests/bench/bench_game_fountain --threads 12 --config "$GAME_DEFAULTS" > "$tmp/fountain.md"
# How much CPU a two-thread run gets on this machine right now (200 % = two idle cores).
share=$( { /usr/bin/time -f %P "$BENCH" steps --steps 20 --threads 2 > /dev/null; } 2>&1 | tail -1 )
# Load-independent cost: instructions of 8 dambreak_box steps (1 thread) under callgrind. The
# toggle names stepSph exactly: a pattern like 'fluid::stepSph*' also matches the step's lambdas,
# and callgrind toggles collection off again inside every one that is not inlined.
TOGGLE='fluid::stepSph(fluid::SphWorld&, float, fluid::SphStepStats*)'
WCSPH_SET="--set cfl=0.1 --set sound_speed=22"
if command -v valgrind > /dev/null; then
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" --toggle-collect="$TOGGLE" \
    "$BENCH" steps --steps 8 --threads 1 > "$tmp/cg.txt" 2> "$tmp/cg.err"
  instructions=$(sed -n 's/.*Collected : *\([0-9]*\).*/\1/p' "$tmp/cg.err")
  # shellcheck disable=SC2086
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cgw.out" --toggle-collect="$TOGGLE" \
    "$BENCH" steps --solver wcsph --steps 8 --threads 1 $WCSPH_SET > "$tmp/cgw.txt" 2> "$tmp/cgw.err"
  instructions_wcsph=$(sed -n 's/.*Collected : *\([0-9]*\).*/\1/p' "$tmp/cgw.err")
fi
{
  cat tests/bench/sph_docs_head.md
  echo
  echo "## Accuracy against time (dam break, 2 s)"
  echo
  echo "Command: \`$BENCH accuracy --csv docs/sph_accuracy.csv\` (machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg) at the end); chart: \`scripts/plots/sph_accuracy.py docs/sph_accuracy.csv docs/sph_accuracy.png\`."
  echo
  cat "$tmp/accuracy.md"
  echo
  echo "![mean density error against CPU seconds per simulated second](sph_accuracy.png)"
  echo
  echo "## Dam-break front against experiment"
  echo
  echo "Command: \`$BENCH front\` (the surge front, the 99.5th percentile of x, of \`fluiddemo simulate --scene dambreak --set width=0.05715 --set height_ratio=2\` in a box 12 a long, against Martin & Moyce 1952 figure 3, n^2 = 2, a = 2.25 in; T = t sqrt(2 g / a); a positive error is ahead of the experiment; bounds asserted in tests/sph/test_dambreak_experiment.cpp: every point within -10 % .. +20 %, mean |error| <= 12 %)."
  echo
  cat "$tmp/front.md"
  echo
  cat tests/bench/sph_docs_compression.md
  echo
  echo "## dambreak_box against SPlisHSPlasH"
  echo
  echo "Command: \`$BENCH dambreak_box --seconds $BOX_SECONDS --threads 12\` (simulated 0 -> $BOX_SECONDS s; density error sampled at 30 fps frames)."
  echo
  cat "$tmp/box.md"
  echo
  echo "## Game aim: 10k-particle fountain"
  echo
  echo "Command: \`build/dev/tests/bench/bench_game_fountain --threads 12 --config \"$GAME_DEFAULTS\"\` (the game's fountain, \`content/scenes/fountain.json\` built by \`game::initSphFluid\` with \`sph_fluid.max_particles=10000\`: the basin filled at load, the pump running the jet for 2 s once per configuration, then 60 frames of 1/60 s stepped as the game steps them, jet running; the first rows use the scene file's solver knobs, the others SphParams' defaults)."
  echo
  cat "$tmp/fountain.md"
  echo
  echo "## Machine share and instruction count"
  echo
  echo "- parallel share: \`/usr/bin/time -f %P $BENCH steps --steps 20 --threads 2\` reported $share CPU."
  if [ -n "${instructions:-}" ]; then
    echo "- callgrind: \`valgrind --tool=callgrind --toggle-collect='$TOGGLE' $BENCH steps --steps 8 --threads 1\` counted $instructions instructions in stepSph ($(cat "$tmp/cg.txt"))."
    echo "- callgrind, WCSPH: the same with \`steps --solver wcsph --steps 8 --threads 1 $WCSPH_SET\` counted $instructions_wcsph instructions ($(cat "$tmp/cgw.txt"))."
  fi
  echo
  echo "## Randomised stability sweep"
  echo
  echo "Command: \`$BENCH seeds --from 1 --to 300\` (the randomised runs of \`tests/sph/randomised_runs.hpp\`, 16 runs x 200 steps per seed; the unit test runs one fixed seed and must pass; a listed run broke a bound at that step)."
  echo
  echo '```'
  cat "$tmp/seeds.txt"
  echo '```'
  echo
  echo "## Throughput"
  echo
  echo "Command: \`$BENCH throughput --steps 20\` (block of water falling in the 4 x 3 x 1.5 m tank, median of 20 steps after 5 warm-up steps; the neighbour search share is grid, re-sort and list building: for WCSPH the Verlet-list rebuilds, while the per-step filtering of the Verlet lists to the support runs inside the density pass)."
  echo
  cat "$tmp/throughput.md"
  echo
  echo "## Status against the performance bar of issue 4"
  echo
  echo "Command: \`python3 tests/bench/sph_bar_status.py BOX FOUNTAIN\` over the dambreak_box and game-aim tables above (SPlisHSPlasH's figures quoted from issue 4)."
  echo
  python3 tests/bench/sph_bar_status.py "$tmp/box.md" "$tmp/fountain.md"
  cat tests/bench/sph_docs_tail.md
} > "$OUT"
rm -rf "$tmp"
echo "wrote $OUT"
