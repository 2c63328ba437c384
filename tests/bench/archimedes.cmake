# Issue 18 item 4: crates of three densities in the SPH tank at several particle radii (a plain
# executable printing a Markdown table; docs/engine.md, buoyancy).
add_executable(bench_archimedes ${CMAKE_CURRENT_LIST_DIR}/archimedes_bench.cpp)
target_include_directories(bench_archimedes PRIVATE ${PROJECT_SOURCE_DIR})
target_link_libraries(bench_archimedes PRIVATE fluiddemo_game fluiddemo_options)
