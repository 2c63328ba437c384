#!/usr/bin/env bash
# Runs libFuzzer targets built with -DFLUIDDEMO_FUZZ=ON (docs/fuzz.md), in parallel:
#   tests/fuzz/run_libfuzzer.sh BUILD_DIR SECONDS [TARGET...]     (default: every target)
# Each target starts from a copy of its committed seed corpus (BUILD_DIR/fuzz_corpus/<target>,
# kept between runs), with a 5 s per-input timeout and a 512 MB malloc / 2 GB RSS limit, so hangs
# and unbounded allocations are reported as failures. Logs: BUILD_DIR/fuzz_logs/<target>.log;
# crashes: BUILD_DIR/fuzz_artifacts/. Prints the CPU seconds each target used (user + sys).
set -u
build="$1"; seconds="$2"; shift 2
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(particles_xyz particles_csv particles_ply scene_json scene_set collider_file model_obj)
mkdir -p "$build/fuzz_logs" "$build/fuzz_artifacts"
for t in "${targets[@]}"; do
  mkdir -p "$build/fuzz_corpus/$t"
  cp -n "$root/tests/fuzz/corpus/$t/"* "$build/fuzz_corpus/$t/" 2>/dev/null
  /usr/bin/time -f "%U %S" -o "$build/fuzz_logs/$t.time" \
    "$build/tests/fuzz/fuzz_$t" "$build/fuzz_corpus/$t" -max_total_time="$seconds" -timeout=5 \
    -malloc_limit_mb=512 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$build/fuzz_artifacts/$t-" > "$build/fuzz_logs/$t.log" 2>&1 &
done
wait
status=0
for t in "${targets[@]}"; do
  read -r user sys < <(tail -1 "$build/fuzz_logs/$t.time")
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz_logs/$t.log" | grep -o '[0-9]*$')
  if grep -q "ERROR: libFuzzer\|SUMMARY: \(Address\|Undefined\)\|fuzz $t:" "$build/fuzz_logs/$t.log"; then
    echo "$t: FAILED (see $build/fuzz_logs/$t.log)"; status=1
  else
    printf '%s: ok, %s inputs, %.0f CPU seconds\n' "$t" "${runs:-?}" "$(echo "$user + $sys" | bc)"
  fi
done
exit $status
