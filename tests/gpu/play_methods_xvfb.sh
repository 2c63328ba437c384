#!/bin/sh
# play_methods_xvfb.sh EXE OUT_DIR
# Issue 21's acceptance, the window half: `fluiddemo play fountain --set fluid_surface.method=M`
# for the two particle methods in a real X window (Xvfb, GL through GLX on llvmpipe): it opens a
# window, builds the method's renderer, runs its frames without a GL error and writes a non-empty
# screenshot. Skipped (exit 77) without xvfb-run; not a dependency of scripts/test.sh.
set -u
exe=$1 out=$2
command -v xvfb-run > /dev/null || { echo "xvfb-run missing: skipped"; exit 77; }
mkdir -p "$out"
for method in raycast screen_space; do
  rm -f "$out/$method.png"
  env -u SDL_VIDEODRIVER xvfb-run -a "$exe" play fountain --frames 60 --width 320 --height 180 \
    --set "fluid_surface.method=$method" --screenshot "$out/$method.png" > "$out/$method.txt" 2>&1
  code=$?
  cat "$out/$method.txt"
  [ "$code" -eq 0 ] || { echo "FAIL: $method exited $code"; exit 1; }
  grep -q ' 320x180 window$' "$out/$method.txt" || { echo "FAIL: $method did not run in a window"; exit 1; }
  if grep -Eq 'unavailable|GL error|run-time failures' "$out/$method.txt"; then
    echo "FAIL: $method reported a renderer or GL failure"
    exit 1
  fi
  [ -s "$out/$method.png" ] || { echo "FAIL: $method wrote no screenshot"; exit 1; }
done
echo "play_methods_xvfb: ok"
