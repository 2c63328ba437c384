#!/usr/bin/env bash
# Set-up + build + all tests:  scripts/test.sh
# Env: BUILD_DIR (default build/test), FLUIDDEMO_SANITIZE (address|thread), JOBS.
# After ctest (plain builds): installs to a temporary prefix, builds examples/ as an outside project
# with find_package(fluiddemo) and runs it, configures a project that takes fluid/ with
# add_subdirectory, and runs the pytest suite against the installed Python module.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup-deps.sh

build_dir="${BUILD_DIR:-build/test}"
jobs="${JOBS:-$(nproc)}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DFLUIDDEMO_BUILD_TESTS=ON -DFLUIDDEMO_BUILD_BENCHMARKS=ON \
  -DFLUIDDEMO_SANITIZE="${FLUIDDEMO_SANITIZE:-}"
cmake --build "$build_dir" -j "$jobs"
# The smoke and GL tests use Mesa's software rasterizer through SDL's offscreen driver.
export SDL_VIDEODRIVER="${SDL_VIDEODRIVER:-offscreen}"
# The audio effect's live device (rendered runs) uses SDL's dummy driver: no sound card is needed
# and ALSA's "cannot find card" noise stays out of the logs.
export SDL_AUDIODRIVER="${SDL_AUDIODRIVER:-dummy}"
cd "$build_dir"
ctest --output-on-failure -j "$jobs" --timeout 600

if [ -n "${FLUIDDEMO_SANITIZE:-}" ]; then
  exit 0  # the installed library would be an instrumented build: the outside checks need a plain one
fi
build_abs="$PWD"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
echo "test.sh: installing to $scratch/prefix and building examples/ against it"
cmake --install "$build_abs" --prefix "$scratch/prefix" >/dev/null
# Every installed header compiles from the installed tree (nothing missing, nothing outside it).
find "$scratch/prefix/include/fluiddemo/fluid" -name '*.hpp' | sort | sed 's|.*/include/fluiddemo/|#include "|; s|$|"|' \
  >"$scratch/all_headers.cpp"
"${CXX:-c++}" -std=c++20 -fsyntax-only -I"$scratch/prefix/include/fluiddemo" "$scratch/all_headers.cpp"
echo "test.sh: $(grep -c . "$scratch/all_headers.cpp") installed headers compile from the installed tree"
cmake -S "$root/examples" -B "$scratch/examples" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" >/dev/null
cmake --build "$scratch/examples" -j "$jobs"
# The flag fluid's determinism depends on reached the outside project through fluiddemo::fluid.
grep -q -- '-ffp-contract=off' "$scratch/examples/build.ninja"
"$root/examples/run_examples.sh" "$scratch/examples" "$root" "$scratch/examples-run"

# fluid/ taken into another project with add_subdirectory (configure and generate: the step that
# fails when fluid/ needs something only our top level defines).
mkdir -p "$scratch/subdir"
printf '%s\n' 'cmake_minimum_required(VERSION 3.25)' 'project(uses_fluid LANGUAGES CXX)' \
  "add_subdirectory(\"$root/fluid\" fluid)" "add_executable(mesh_particles \"$root/examples/mesh_particles.cpp\")" \
  'target_link_libraries(mesh_particles PRIVATE fluiddemo::fluid)' >"$scratch/subdir/CMakeLists.txt"
cmake -S "$scratch/subdir" -B "$scratch/subdir/build" -G Ninja >/dev/null
echo "test.sh: add_subdirectory(fluid) from an outside project configures"

# The Python module as installed, with the interpreter it was built for (Debian's /usr/bin/python3,
# which has python3-numpy and python3-pytest; README "Use the libraries").
python="$(sed -n 's/^Python_EXECUTABLE:[A-Z]*=//p' "$build_abs/CMakeCache.txt")"
if [ -n "$python" ] && [ -d "$scratch/prefix/lib/python3/dist-packages" ]; then
  exe_env=()  # the CLI comparisons need the executable (not built with FLUIDDEMO_BUILD_ENGINE=OFF)
  if [ -x "$build_abs/game/fluiddemo" ]; then exe_env=(FLUIDDEMO_EXE="$build_abs/game/fluiddemo"); fi
  env PYTHONPATH="$scratch/prefix/lib/python3/dist-packages" FLUIDDEMO_SOURCE_DIR="$root" "${exe_env[@]}" \
    "$python" -m pytest -q -p no:cacheprovider "$root/tests/python"
fi
