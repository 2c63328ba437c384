# Sources of fluid/sph, added to the `fluid` library.
target_sources(fluid PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/neighbor_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/analytic_colliders.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_world.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_solver.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_scenes.cpp
)
