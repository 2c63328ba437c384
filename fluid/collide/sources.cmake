# Sources of fluid/collide, added to the `fluid` library.
target_sources(fluid PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/l1_normal.cpp
  ${CMAKE_CURRENT_LIST_DIR}/depth_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bake.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collider_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collider_cache.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mesh_distance.cpp
  ${CMAKE_CURRENT_LIST_DIR}/reach_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/coverage.cpp
)
