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
"$BENCH" accuracy --png docs/sph_accuracy.png > "$tmp/accuracy.md"
"$BENCH" throughput --steps 20 > "$tmp/throughput.md"
"$BENCH" dambreak_box --seconds "$BOX_SECONDS" --threads 12 > "$tmp/box.md"
{
  cat tests/bench/sph_docs_head.md
  echo
  echo "## Accuracy against time (dam break, 2 s)"
  echo
  echo "Command: \`$BENCH accuracy --png docs/sph_accuracy.png\` (machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg) at the end)."
  echo
  cat "$tmp/accuracy.md"
  echo
  echo "![mean density error against CPU seconds per simulated second](sph_accuracy.png)"
  echo
  echo "## dambreak_box against SPlisHSPlasH"
  echo
  echo "Command: \`$BENCH dambreak_box --seconds $BOX_SECONDS --threads 12\` (simulated 0 -> $BOX_SECONDS s; density error sampled at 30 fps frames)."
  echo
  cat "$tmp/box.md"
  echo
  echo "## Throughput"
  echo
  echo "Command: \`$BENCH throughput --steps 20\` (block of water falling in the 4 x 3 x 1.5 m tank, median of 20 steps after 5 warm-up steps)."
  echo
  cat "$tmp/throughput.md"
  cat tests/bench/sph_docs_tail.md
} > "$OUT"
rm -rf "$tmp"
echo "wrote $OUT"
