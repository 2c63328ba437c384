# GPU particle benchmark (owned by the gpu module): particles per ms per pass, 16k…1M.
# A plain executable (GL passes are timed with glFinish, not by Google Benchmark's loop).
find_package(SDL2 REQUIRED)
add_executable(bench_gpu_particles
  gpu_particles_bench.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/cpu_reference.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/gl_test_context.cpp)
target_link_libraries(bench_gpu_particles PRIVATE engine SDL2::SDL2 fluiddemo_options)
target_compile_definitions(bench_gpu_particles PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")

# Screenshots for docs/gpu.md (not a benchmark, not a test): gpu_screenshot docs/images [--force]
find_package(PkgConfig REQUIRED)
pkg_check_modules(GPU_STB REQUIRED IMPORTED_TARGET stb)
add_executable(gpu_screenshot
  gpu_screenshot.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/cpu_reference.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/gl_test_context.cpp)
target_link_libraries(gpu_screenshot PRIVATE engine SDL2::SDL2 PkgConfig::GPU_STB fluiddemo_options)
target_compile_definitions(gpu_screenshot PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")

# Fluid-render screenshots for docs/gpu.md: gpu_fluid_screenshot docs/images [--force]
add_executable(gpu_fluid_screenshot
  gpu_fluid_screenshot.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/fluid_scene.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/gl_test_context.cpp)
target_link_libraries(gpu_fluid_screenshot PRIVATE engine SDL2::SDL2 PkgConfig::GPU_STB fluiddemo_options)
target_compile_definitions(gpu_fluid_screenshot PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
