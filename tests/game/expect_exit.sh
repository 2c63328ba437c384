#!/usr/bin/env bash
# expect_exit.sh CODE REGEX COMMAND [ARGS...]
# Runs COMMAND, and passes only if it exits with CODE and its stdout+stderr matches REGEX (grep -E).
set -u
expected_code="$1"; pattern="$2"; shift 2
output="$("$@" 2>&1)"; code=$?
printf '%s\n' "$output"
if [ "$code" -ne "$expected_code" ]; then
  echo "expect_exit: exit code $code, expected $expected_code" >&2
  exit 1
fi
if ! printf '%s\n' "$output" | grep -Eq -- "$pattern"; then
  echo "expect_exit: output does not match /$pattern/" >&2
  exit 1
fi
echo "expect_exit: ok (exit $code, output matches)"
