#!/usr/bin/env bash
# cli_exit_codes.sh FLUIDDEMO SOURCE_DIR WORK_DIR
# The one exit-code rule (game/commands.hpp, README "Command line") over every subcommand's
# failure modes, through the real executable, from a folder that is not the repository root:
#   2  usage: an unknown subcommand or flag, a bad value (--set included), a missing required
#      argument, an output that exists without --force, a PNG output not named .png, a
#      --screenshot-at step the run never reaches;
#   1  failure: an input that is missing or bad (scene, replay, particles, model, collider), an
#      output folder that cannot be created or written in (with strerror's reason).
# Output checks come before any work: those rows also check that no run summary was printed.
set -u
exe="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
cd "$work" || exit 1
export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}"
replay="$src/content/replays/crate_yard_tour.replay"
failures=0

# row CODE REGEX ARGS...: fluiddemo ARGS exits with CODE and prints a line matching REGEX.
row() {
  local want="$1" pattern="$2"; shift 2
  local out code
  out="$("$exe" "$@" 2>&1)"; code=$?
  if [ "$code" -ne "$want" ] || ! printf '%s\n' "$out" | grep -Eq -- "$pattern"; then
    echo "FAIL: fluiddemo $* -> exit $code (expected $want), output:"
    printf '%s\n' "$out" | sed 's/^/    /' | tail -5
    failures=$((failures + 1))
    return
  fi
  echo "ok   $want  fluiddemo $*"
}
# before_run CODE REGEX ARGS...: as row, and nothing ran (no run summary, no replay checkpoints).
before_run() {
  local out
  row "$@"
  shift 2
  out="$("$exe" "$@" 2>&1)"
  if printf '%s\n' "$out" | grep -Eq "^(checkpoints:|fluiddemo: scene|scene .* simulated|smoke .* (ok|FAIL))"; then
    echo "FAIL: fluiddemo $* ran before refusing"
    failures=$((failures + 1))
  fi
}

printf keep > exists.png; printf keep > exists.csv; printf keep > exists.replay; printf keep > exists.obj
printf keep > exists.colliders; printf keep > afile  # a file where a folder is expected: ENOTDIR
printf '{\n  "scene": {"step_hz": 60, "step_hz": 30},\n  "effects": {}\n}\n' > duplicate.json
printf '{\n  "scene": {"step_hz": 60,, },\n  "effects": {}\n}\n' > syntax.json
printf 'fluiddemo_replay 1\nbogus record\n' > bad.replay
mkdir -p sim_done && printf keep > sim_done/stats.csv
notdir="cannot create the folder afile: Not a directory"

# main
row 2 "unknown subcommand 'bogus'" bogus
# play
row 2 "--frames" play --frames -3
row 2 "unknown key 'nozzle'" play fountain --set camera.nozzle=1
row 1 "unknown scene 'nosuchscene'" play nosuchscene
row 1 "duplicate.json: scene.step_hz: the key appears twice" play duplicate.json
row 1 "syntax.json: invalid JSON: parse error at line 2, column 27: syntax error while parsing object key - unexpected ','; expected string literal$" \
  play syntax.json
before_run 2 "--screenshot exists.png: exists \(pass --force" play --headless --frames 1 --screenshot exists.png
before_run 2 "--screenshot shot.jpg: only PNG is written" play --headless --frames 1 --screenshot shot.jpg
before_run 1 "--screenshot afile/x.png: $notdir" play --headless --frames 1 --screenshot afile/x.png
before_run 2 "--record exists.replay: exists \(pass --force" play --headless --frames 1 --record exists.replay
before_run 1 "--record afile/r.replay: $notdir" play --headless --frames 1 --record afile/r.replay
# smoke
row 2 "excludes" smoke --all --scene fountain
row 2 "--frames" smoke --frames 0
before_run 1 "--out afile/shots: cannot write in it: Not a directory" smoke --scene crate_yard --out afile/shots
row 1 "smoke nosuchscene +FAIL +unknown scene" smoke --scene nosuchscene
# soak
row 2 "--seconds" soak --seconds 0
row 2 "unknown key 'nozzle'" soak --scene crate_yard --set camera.nozzle=1
row 1 "unknown scene 'nosuchscene'" soak --scene nosuchscene
# replay
row 2 "a replay FILE is required" replay
row 2 "The following arguments were not expected: --fps 30$" replay "$replay" --fps 30
row 2 "--update-hashes .* needs --force" replay "$replay" --update-hashes
row 1 "nosuch.replay: cannot open: No such file or directory" replay nosuch.replay
row 1 "bad.replay:2:" replay bad.replay
row 1 "nosuch.csv" replay --compare nosuch.csv nosuch.csv
before_run 2 "--csv exists.csv: exists \(pass --force" replay "$replay" --no-render --frames 5 --csv exists.csv
before_run 1 "--csv afile/x.csv: $notdir" replay "$replay" --no-render --frames 5 --csv afile/x.csv
before_run 1 "--png afile/x.png: $notdir" replay "$replay" --no-render --frames 5 --png afile/x.png
before_run 2 "--png plot.jpg: only PNG is written" replay "$replay" --no-render --frames 5 --png plot.jpg
before_run 2 "--screenshot-at shot.jpg: only PNG is written" replay "$replay" --headless --frames 5 --screenshot-at 3:shot.jpg
before_run 2 "--screenshot-at 5000:s.png: the run ends at step 10 \(--frames\)" \
  replay "$replay" --headless --frames 10 --screenshot-at 5000:s.png
before_run 2 "--screenshot-at 5000:s.png: the run ends at step 600," replay "$replay" --headless --screenshot-at 5000:s.png
before_run 2 "--screenshot-at expects STEP:FILE.png" replay "$replay" --headless --screenshot-at s.png
if [ "$(id -u)" -ne 0 ]; then  # root writes in a read-only folder
  mkdir -p readonly && chmod 555 readonly
  before_run 1 "--csv readonly/x.csv: cannot create it in readonly: Permission denied" \
    replay "$replay" --no-render --frames 5 --csv readonly/x.csv
  chmod 755 readonly
fi
# mesh
row 2 "--out is required" mesh --in x.xyz
row 2 "--cube: must be a positive number, got -1" mesh --in x.xyz --out m.obj --cube -1
row 2 "unknown mesh format '.stl'" mesh --in x.xyz --out m.stl
row 1 "nosuch.xyz" mesh --in nosuch.xyz --out m.obj
row 2 "--out exists.obj: exists \(pass --force" mesh --in nosuch.xyz --out exists.obj
row 1 "--out afile/m.obj: $notdir" mesh --in "$src/tests/data/blob.xyz" --out afile/m.obj
# simulate
row 2 "--scene is required" simulate --seconds 1
row 2 "--threads must be >= 0" simulate --scene dambreak --seconds 0.1 --threads -1
row 2 "unknown --solver 'bogus'" simulate --scene dambreak --seconds 0.1 --solver bogus
row 2 "nosuchscene" simulate --scene nosuchscene --seconds 0.1
before_run 2 "--out sim_done/stats.csv: exists \(pass --force" simulate --scene dambreak --seconds 0.01 --out sim_done
before_run 1 "--out afile/sim: cannot write in it: Not a directory" simulate --scene dambreak --seconds 0.01 --out afile/sim
row 0 "^simulate: no --out: frames and stats.csv are not written, only this summary$" \
  simulate --scene dambreak --seconds 0.01
# bake-collider (content resolved as play resolves it: this folder is not the repository root)
row 2 "give MODEL and --out FILE" bake-collider
row 2 "--level takes no MODEL or --out" bake-collider --level fountain --out x.colliders
row 2 "--res 2 out of range" bake-collider "$src/content/models/statue.obj" --out c.colliders --res 2
row 1 "nosuch.obj" bake-collider nosuch.obj --out c.colliders
row 2 "--out exists.colliders: exists \(pass --force" bake-collider nosuch.obj --out exists.colliders
row 1 "--out afile/c.colliders: $notdir" bake-collider "$src/content/models/statue.obj" --out afile/c.colliders
row 1 "nosuchlevel" bake-collider --level nosuchlevel --check
row 0 "statue: up to date" bake-collider --level fountain --check
# query-collider
row 2 "--points is required" query-collider c.colliders
row 1 "nosuch.colliders" query-collider nosuch.colliders --points "$src/tests/data/blob.xyz"
# scene-keys
row 2 "The following argument was not expected: extra" scene-keys extra

[ "$failures" -eq 0 ] || { echo "cli_exit_codes: $failures row(s) failed"; exit 1; }
echo "cli_exit_codes: ok"
