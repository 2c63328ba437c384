#!/usr/bin/env bash
# simulate_cli.sh FLUIDDEMO MODE WORKDIR
#   frames:   `simulate` frames list every particle once as "x y z id" by ascending id, the same
#             id is the same particle from frame to frame (it moves less than speed cap x 1/F),
#             and nothing goes to stderr when it is not a terminal (no progress line in pipes).
#   progress: on a terminal (a pseudo-terminal from script(1)), stderr gets a progress line.
set -u
exe="$1"; mode="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
case "$mode" in
  frames)
    "$exe" simulate --scene fountain --seconds 0.3 --fps 20 --set rate=2000 --out "$work/out" \
      >"$work/stdout" 2>"$work/stderr" || { cat "$work/stderr"; echo "simulate failed"; exit 1; }
    if [ -s "$work/stderr" ]; then echo "stderr not empty when piped:"; cat "$work/stderr"; exit 1; fi
    n=$(ls "$work/out"/frame_*.xyz | wc -l)
    [ "$n" -eq 7 ] || { echo "expected 7 frames, got $n"; exit 1; }
    # Every frame: 4 columns, ids strictly ascending. Consecutive frames: a common id moves < 0.5 m
    # (the jet runs at 3.5 m/s, 0.05 s apart).
    awk 'FNR == 1 { f++; last = -1
                    if (NR > 1) { for (k in px) delete px[k]; for (k in nx) { px[k] = nx[k]; py[k] = ny[k]; pz[k] = nz[k] }
                                  for (k in nx) delete nx[k] } }
         NF != 4 { print FILENAME ":" FNR ": " NF " columns, expected x y z id"; bad = 1; exit }
         { if ($4 + 0 <= last) { print FILENAME ":" FNR ": id " $4 " after " last; bad = 1; exit }
           last = $4 + 0
           if ($4 in px) { dx = $1 - px[$4]; dy = $2 - py[$4]; dz = $3 - pz[$4]
             if (dx * dx + dy * dy + dz * dz > 0.25) { print FILENAME ": id " $4 " jumped"; bad = 1; exit }
             common++ }
           nx[$4] = $1; ny[$4] = $2; nz[$4] = $3 }
         END { if (bad) exit 1; if (common < 100) { print "only " common " particles followed"; exit 1 }
               print "frames ok: " f " frames, " common " particle matches" }' $(ls "$work/out"/frame_*.xyz | sort)
    ;;
  progress)
    command -v script >/dev/null || { echo "script(1) not found: skipped"; exit 0; }
    script -qec "'$exe' simulate --scene column --seconds 0.05 --set spacing=0.02" /dev/null >"$work/tty" 2>&1 || {
      cat "$work/tty"; echo "simulate failed"; exit 1; }
    grep -Eq "simulate: 0\.0[5-9][0-9]* of 0\.050 s simulated, [0-9]+ steps" "$work/tty" || {
      cat "$work/tty"; echo "no progress line on a terminal"; exit 1; }
    echo "progress ok"
    ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac
