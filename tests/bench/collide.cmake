# Benchmarks of fluid/collide (plain executables printing markdown; not registered with ctest).
#   bench_collide_tables: L1 error and accuracy-vs-time tables of docs/collide.md
#   bench_collide_query:  1M batch queries vs exact mesh distance (the issue's performance bar)
foreach(name collide_tables collide_query)
  add_executable(bench_${name} ${CMAKE_CURRENT_LIST_DIR}/${name}.cpp ${PROJECT_SOURCE_DIR}/tests/collide/collide_meshes.cpp)
  target_include_directories(bench_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/collide)
  target_link_libraries(bench_${name} PRIVATE fluid TBB::tbb bench_csv fluiddemo_options)
endforeach()
