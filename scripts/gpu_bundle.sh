#!/bin/bash
# Packs what scripts/gpu_check.sh needs to run fluiddemo's GL paths on a machine with a GPU driver
# but none of our packages: the game, the GL tests and the GPU benchmarks from BUILD (stripped), the
# shared libraries they load that are not the C library or GL itself, and the glvnd loaders as
# Debian packages (unpacked there; the machine's driver supplies the vendor library).
#   usage: scripts/gpu_bundle.sh [BUILD=build/dev]   -> .gpurun/ and .gl/ in the repository root
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/dev}
# Every GL test binary the build made (tests/*/gl_*): a test left out is a GL path never run on a GPU.
mapfile -t gl_tests < <(cd "$build" && find tests -name 'gl_*' -type f -executable | sort)
bins=(game/fluiddemo "${gl_tests[@]}"
      tests/bench/bench_gpu_particles tests/bench/bench_fluid_render tests/bench/bench_game_fountain)
rm -rf .gpurun
mkdir -p .gpurun/bin .gpurun/lib .gpurun/data .gl
# The mesher's two-thread sets (../shared does not travel with the repository).
cp ../shared/bench-data/explosion.xyz ../shared/bench-data/spray.xyz .gpurun/data/
for b in "${bins[@]}"; do
  strip --strip-unneeded -o ".gpurun/bin/$(basename "$b")" "$build/$b"
done
# Every library the binaries load, minus glibc's own and the GL dispatch libraries (glvnd, below).
skip='^(linux-vdso|ld-linux|libc\.so|libm\.so|libpthread|libdl\.so|librt\.so|libGL|libEGL|libOpenGL|libGLX|libGLdispatch)'
for b in .gpurun/bin/*; do ldd "$b"; done | awk '$3 ~ /^\// {print $1, $3}' | sort -u |
  while read -r name path; do
    [[ $name =~ $skip ]] && continue
    strip --strip-unneeded -o ".gpurun/lib/$name" "$path"
  done
# One compressed payload: the working tree that travels to the device machine is capped at 64 MiB.
tar -C .gpurun -cJf .gpurun/payload.tar.xz bin lib && rm -rf .gpurun/bin .gpurun/lib
cp scripts/gpu_check.sh .gpurun/run.sh
# The source path compiled into the test binaries (FLUIDDEMO_SOURCE_DIR): gpu_check.sh links it.
sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$build/CMakeCache.txt" > .gpurun/source_dir
if ! ls .gl/libegl1_*.deb >/dev/null 2>&1; then
  o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
  mkdir -p /tmp/amd64/partial
  apt-get $o update >/dev/null
  (cd .gl && apt-get $o download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
du -sh .gpurun .gl
