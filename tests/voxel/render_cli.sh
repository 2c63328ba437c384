#!/usr/bin/env bash
# render_cli.sh FLUIDDEMO SOURCE_DIR WORK_DIR [SIZE]
# `fluiddemo render` (issue 37) through the real executable, headless: bad input is refused by
# the one exit-code rule of game/commands.hpp (2 usage, 1 failure) with a message naming the
# option, file, line or value, before any drawing; then every method draws a SIZE-particle pool
# (scripts/make_render_sets.py; default 3000) and prints its stages. SIZE 1000000 is the
# acceptance run: the voxel method on a million particles (ctest render_million_voxel).
set -u
exe="$1"; src="$2"; work="$3"; size="${4:-3000}"
rm -rf "$work"; mkdir -p "$work"
cd "$work" || exit 1
export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}" SDL_AUDIODRIVER="${SDL_AUDIODRIVER:-dummy}"
failures=0

# row CODE REGEX ARGS...: fluiddemo render ARGS exits with CODE and prints a line matching REGEX.
row() {
  local want="$1" pattern="$2"; shift 2
  local out code
  out="$("$exe" render "$@" 2>&1)"; code=$?
  if [ "$code" -ne "$want" ] || ! printf '%s\n' "$out" | grep -Eq -- "$pattern"; then
    echo "FAIL: fluiddemo render $* -> exit $code (expected $want), output:"
    printf '%s\n' "$out" | sed 's/^/    /' | tail -8
    failures=$((failures + 1))
    return
  fi
  echo "ok   $want  fluiddemo render $*"
}

python3 "$src/scripts/make_render_sets.py" sets --sizes "$size" > /dev/null || { echo "FAIL: make_render_sets.py"; exit 1; }
set_file="sets/pool_$size.xyz"
if [ "$size" -le 100000 ]; then
  printf '0 0 0\n1 2\n' > truncated.xyz
  printf '0 0 0\n0.1 nan 0\n' > nan.xyz
  : > empty.xyz
  touch exists.png
  row 2 "--in is required" --out a.png
  row 2 "--out is required" --in "$set_file"
  row 1 "missing.xyz: cannot open" --in missing.xyz --out a.png
  row 1 "truncated.xyz:2" --in truncated.xyz --out a.png
  row 1 "nan.xyz:2" --in nan.xyz --out a.png
  row 1 "empty.xyz: no particles" --in empty.xyz --out a.png
  row 2 "only PNG is written" --in "$set_file" --out a.jpg
  row 2 "exists.png: exists \(pass --force" --in "$set_file" --out exists.png
  row 2 "--method: splat not in" --in "$set_file" --out a.png --method splat
  row 2 "--camera 1,2: expected three numbers" --in "$set_file" --out a.png --camera 1,2
  row 2 "--look-at 1,x,2: expected three numbers" --in "$set_file" --out a.png --look-at 1,x,2
  row 2 "same point" --in "$set_file" --out a.png --camera 1,1,1 --look-at 1,1,1
  row 2 "--radius: must be a positive number, got 0" --in "$set_file" --out a.png --radius 0
  row 2 "--width: Value 5 not in range" --in "$set_file" --out a.png --width 5
  row 2 "--surface-out: only for --method screen_space, raycast or voxel \(not mesh\)" --in "$set_file" --out a.png \
    --method mesh --surface-out s.csv
  touch exists.csv
  row 2 "--surface-out exists.csv: exists \(pass --force" --in "$set_file" --out a.png --method raycast \
    --surface-out exists.csv
  [ -e a.png ] && { echo "FAIL: a refused run wrote a.png"; failures=$((failures + 1)); }
  # --surface-out: a header and one row per water pixel, each a unit normal facing the camera.
  for m in screen_space raycast voxel; do
    row 0 "wrote surface_$m.csv" --in "$set_file" --method "$m" --out "surface_$m.png" --surface-out "surface_$m.csv" \
      --width 96 --height 64 --camera 1,7,8 --look-at 0,0.5,0
    if ! awk -F, -v cx=1 -v cy=7 -v cz=8 'NR == 1 { ok = ($0 == "x,y,px,py,pz,nx,ny,nz"); next }
        { n = sqrt($6 * $6 + $7 * $7 + $8 * $8); facing = $6 * (cx - $3) + $7 * (cy - $4) + $8 * (cz - $5)
          if (n < 0.999 || n > 1.001 || facing < 0 || $1 < 0 || $1 >= 96 || $2 < 0 || $2 >= 64) bad++; rows++ }
        END { exit !(ok && rows > 100 && bad == 0) }' "surface_$m.csv"; then
      echo "FAIL: surface_$m.csv: header, more than 100 rows, unit normals facing the camera"
      failures=$((failures + 1))
    fi
  done
  for m in none mesh screen_space raycast voxel; do
    row 0 "wrote $m.png" --in "$set_file" --method "$m" --out "$m.png" --width 96 --height 64
  done
  row 0 "voxel memory: tile grid" --in "$set_file" --method voxel --out voxel.png --force --width 96 --height 64
  row 0 "splatted [0-9]+ of $size, and [0-9]+ spheres for the full inner cells" --in "$set_file" --method voxel --out inner.png \
    --width 96 --height 64 --drop-inner-cells
  row 0 "anisotropic kernels: [0-9]+ of $size stretched" --in "$set_file" --method voxel --kernel anisotropic \
    --out aniso.png --width 96 --height 64
  row 0 "anisotropic kernels: [0-9]+ of $size stretched" --in "$set_file" --method mesh --kernel anisotropic \
    --out aniso_mesh.png --width 96 --height 64
else
  row 0 "wrote voxel.png" --in "$set_file" --method voxel --out voxel.png --width 320 --height 180
fi
if [ "$failures" -ne 0 ]; then
  echo "$failures row(s) failed"
  exit 1
fi
echo "all rows ok"
