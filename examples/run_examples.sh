#!/usr/bin/env bash
# Runs the three examples and checks what they write: run_examples.sh BIN_DIR REPO_ROOT WORK_DIR
# (WORK_DIR is emptied first). Used by ctest (in-tree build) and scripts/test.sh (outside build).
set -euo pipefail
bin="$1" repo="$2" work="$3"
rm -rf "$work" && mkdir -p "$work"

"$bin/mesh_particles" "$repo/tests/data/blob.xyz" "$work/blob.obj" 3 0.2 0.3
grep -q '^f ' "$work/blob.obj" || { echo "mesh_particles wrote no triangles" >&2; exit 1; }
# It must refuse to replace what is there.
if "$bin/mesh_particles" "$repo/tests/data/blob.xyz" "$work/blob.obj" 2>/dev/null; then
  echo "mesh_particles replaced an existing file" >&2; exit 1
fi

"$bin/dam_break" "$work/frames" 3 30
n=$(ls "$work/frames" | wc -l)
[ "$n" -eq 3 ] || { echo "dam_break wrote $n frames, expected 3" >&2; exit 1; }
lines=$(grep -c . "$work/frames/frame_0002.xyz")
[ "$lines" -gt 100 ] || { echo "dam_break frame has $lines particles" >&2; exit 1; }

out=$("$bin/bake_collider" "$repo/content/models/crate.obj" 64 0 0 0 0 0.7 0)
echo "$out"
# The unit crate: its centre is 0.5 inside, (0, 0.7, 0) is 0.2 above its top face (to a texel's
# depth quantisation).
distance() { echo "$out" | awk -v p="$1" 'index($0, p) == 1 { for (i = 1; i < NF; ++i) if ($i == "distance") { sub(",", "", $(i + 1)); print $(i + 1) } }'; }
near() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a - b < 0.002 && b - a < 0.002) }'; }
near "$(distance '(0, 0, 0):')" -0.5 || { echo "bake_collider: the crate's centre is not 0.5 inside" >&2; exit 1; }
near "$(distance '(0, 0.7, 0):')" 0.2 || { echo "bake_collider: (0, 0.7, 0) is not 0.2 outside" >&2; exit 1; }
echo "examples ok"
