# Benchmarks of fluid/surface: bench_surface reproduces the paper's Figure 7 and writes
# docs/surface.md (see the header of surface_bench.cpp). Built, not run by ctest.
add_executable(bench_surface ${CMAKE_CURRENT_LIST_DIR}/surface_bench.cpp)
target_link_libraries(bench_surface PRIVATE fluid bench_csv fluiddemo_options)
target_include_directories(bench_surface PRIVATE ${PROJECT_SOURCE_DIR}/tests/surface)
target_compile_definitions(bench_surface PRIVATE FLUIDDEMO_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")

# Single-set, single-thread driver for callgrind instruction counts (header of surface_count.cpp).
add_executable(bench_surface_count ${CMAKE_CURRENT_LIST_DIR}/surface_count.cpp)
target_link_libraries(bench_surface_count PRIVATE fluid fluiddemo_options)

# The mesher's randomised property sweep (header of surface_seeds.cpp; ctest runs a slice).
add_executable(bench_surface_seeds ${CMAKE_CURRENT_LIST_DIR}/surface_seeds.cpp)
target_link_libraries(bench_surface_seeds PRIVATE fluid fluiddemo_options)
target_include_directories(bench_surface_seeds PRIVATE ${PROJECT_SOURCE_DIR}/tests/surface)
target_compile_definitions(bench_surface_seeds PRIVATE FLUIDDEMO_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
