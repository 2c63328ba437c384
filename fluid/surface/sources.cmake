# Sources of fluid/surface, added to the `fluid` library.
target_sources(fluid PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/mc_tables.cpp
  ${CMAKE_CURRENT_LIST_DIR}/detail/field.cpp
  ${CMAKE_CURRENT_LIST_DIR}/marching_slices.cpp
  ${CMAKE_CURRENT_LIST_DIR}/async_extractor.cpp
  ${CMAKE_CURRENT_LIST_DIR}/baselines.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mesh_io.cpp
  ${CMAKE_CURRENT_LIST_DIR}/voxel_reference.cpp
)
