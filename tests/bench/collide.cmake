# Benchmarks of fluid/collide (plain executables printing markdown; not registered with ctest).
#   bench_collide_tables: L1 error and accuracy-vs-time tables of docs/collide.md
#   bench_collide_query:  1M batch queries vs exact mesh distance (the issue's performance bar)
foreach(name collide_tables collide_query)
  add_executable(bench_${name} ${CMAKE_CURRENT_LIST_DIR}/${name}.cpp ${PROJECT_SOURCE_DIR}/tests/collide/collide_meshes.cpp)
  target_include_directories(bench_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/collide)
  target_link_libraries(bench_${name} PRIVATE fluid TBB::tbb bench_csv fluiddemo_options)
endforeach()

# bench_collide_fountain: the fountain's baked colliders (content/colliders) against the exact
# meshes and the analytic FountainShape, and the SPH step cost of switching (needs the game).
if(TARGET fluiddemo_game)
  add_executable(bench_collide_fountain ${CMAKE_CURRENT_LIST_DIR}/collide_fountain.cpp)
  target_link_libraries(bench_collide_fountain PRIVATE fluiddemo_game fountain_reference bench_csv TBB::tbb fluiddemo_options)
  target_compile_definitions(bench_collide_fountain PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endif()
