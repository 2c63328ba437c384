# The anisotropic kernels' pass against the SPH step (tests/bench/anisotropy_bench.cpp).
add_executable(bench_anisotropy ${CMAKE_CURRENT_LIST_DIR}/anisotropy_bench.cpp)
target_link_libraries(bench_anisotropy PRIVATE fluid benchmark::benchmark fluiddemo_options)
