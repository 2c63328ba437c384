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

# Ours against the dense-lattice peer (dense splat + VTK vtkFlyingEdges3D), interleaved in one run
# (header of surface_peers.cpp). Optional: only when VTK 9 is installed (Debian libvtk9-dev); nothing
# else depends on it.
find_package(VTK 9 QUIET COMPONENTS CommonCore CommonDataModel CommonExecutionModel FiltersCore)
if(VTK_FOUND)
  # VTK 9.1's headers do not parse as C++20: the VTK calls sit in their own C++17 library.
  add_library(bench_surface_peers_vtk STATIC ${CMAKE_CURRENT_LIST_DIR}/surface_peers_vtk.cpp)
  set_target_properties(bench_surface_peers_vtk PROPERTIES CXX_STANDARD 17)
  target_link_libraries(bench_surface_peers_vtk PRIVATE ${VTK_LIBRARIES})
  add_executable(bench_surface_peers ${CMAKE_CURRENT_LIST_DIR}/surface_peers.cpp)
  target_link_libraries(bench_surface_peers PRIVATE fluid bench_surface_peers_vtk fluiddemo_options TBB::tbb)
  target_compile_definitions(bench_surface_peers PRIVATE FLUIDDEMO_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
  message(STATUS "bench_surface_peers: VTK ${VTK_VERSION} found")
else()
  message(STATUS "bench_surface_peers: VTK 9 not found (optional; apt-get install libvtk9-dev)")
endif()
