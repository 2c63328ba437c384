# Benchmarks of fluid/sph: a plain executable (see tests/bench/sph_bench.cpp for the subcommands).
add_executable(bench_sph ${CMAKE_CURRENT_LIST_DIR}/sph_bench.cpp)
target_link_libraries(bench_sph PRIVATE fluid bench_csv fluiddemo_options)
