# The fluid renderers side by side (docs/render.md, tests/bench/render_docs.sh): a plain
# executable over static particle sets, timed with glFinish.
find_package(SDL2 REQUIRED)
add_executable(bench_fluid_render
  render_bench.cpp
  ${PROJECT_SOURCE_DIR}/tests/gpu/gl_test_context.cpp)
target_link_libraries(bench_fluid_render PRIVATE engine SDL2::SDL2 fluiddemo_options)
target_compile_definitions(bench_fluid_render PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
