#!/bin/sh
# replay_set_render_only.sh EXE REPLAY_DIR OUT_DIR
# `fluiddemo replay --set` takes render-only keys: the fountain tour replayed to its first
# checkpoint (step 150) with the ray caster, and again with the water hidden, matches the committed
# hash, and the ray caster really drew (its pool line) without dropping a record; a simulation
# key, a camera key and an unknown fluid_surface key are refused, each named; the blob tour replays
# to its checkpoints with its goo meshed synchronously (blob.async=false).
set -u
exe=$1 replays=$2 out=$3
mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
run() {  # NAME EXPECTED_CODE ARGS...: runs the replay, keeps its output in $out/NAME.txt
  name=$1 code=$2
  shift 2
  "$exe" replay "$replays/fountain_tour.replay" --headless --no-ui --width 160 --height 90 "$@" > "$out/$name.txt" 2>&1
  got=$?
  cat "$out/$name.txt"
  [ "$got" -eq "$code" ] || fail "$name: exit $got, expected $code"
}
has() { grep -Eq -- "$2" "$out/$1.txt" || fail "$1: output lacks /$2/"; }

run raycast 0 --frames 150 --set fluid_surface.method=raycast
has raycast '^checkpoints: 1 matched of 5 '
has raycast '^raycast: 150 frames, most records in a frame [1-9][0-9]*, dropped 0 in 0 frames'
run hidden 0 --frames 150 --set fluid_surface.visible=false --set fluid_surface.method=screen_space
has hidden '^checkpoints: 1 matched of 5 '
run simulation_key 2 --frames 150 --set sph_fluid.viscosity=0.1
has simulation_key "--set sph_fluid.viscosity=0.1: 'sph_fluid.viscosity' is not render-only"
run camera_key 2 --frames 150 --set camera.fov_degrees=70
has camera_key "'camera.fov_degrees' is not render-only"
run unknown_key 1 --frames 150 --set fluid_surface.bogus=1
has unknown_key "unknown key 'bogus'"
# The blob's surface keys are render-only too (meshing the goo synchronously changes no checkpoint);
# its body's keys are not.
"$exe" replay "$replays/blob_tour.replay" --headless --no-ui --width 160 --height 90 --frames 300 \
  --set blob.async=false > "$out/blob_sync.txt" 2>&1 || fail "blob_sync: exit $?"
has blob_sync '^checkpoints: 2 matched of 10 '
run blob_body 2 --frames 150 --set blob.substeps=2
has blob_body "'blob.substeps' is not render-only"
echo "replay_set_render_only: ok"
