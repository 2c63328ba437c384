# Benchmark of fluid/blob (Google Benchmark; not registered with ctest):
#   bench_blob: body step per frame (and step + marching-slices mesh) at 250/1,000/4,000
#   particles on 1 and 2 threads; counters p95_ms per case.
add_executable(bench_blob ${CMAKE_CURRENT_LIST_DIR}/blob_bench.cpp)
target_link_libraries(bench_blob PRIVATE fluid TBB::tbb benchmark::benchmark fluiddemo_options)
