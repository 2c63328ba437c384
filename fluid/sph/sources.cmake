# Sources of fluid/sph, added to the `fluid` library. The step (sph_step.cpp) runs the units in
# order: emitters_sinks, neighbor_step, boundary, one solver (wcsph / dfsph, with pair_loops and
# time_step), collisions, spray (ballistic drops outside the solve).
target_sources(fluid PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/neighbor_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/analytic_colliders.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_world.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_step.cpp
  ${CMAKE_CURRENT_LIST_DIR}/emitters_sinks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/neighbor_step.cpp
  ${CMAKE_CURRENT_LIST_DIR}/boundary.cpp
  ${CMAKE_CURRENT_LIST_DIR}/time_step.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pair_loops.cpp
  ${CMAKE_CURRENT_LIST_DIR}/wcsph.cpp
  ${CMAKE_CURRENT_LIST_DIR}/dfsph.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collisions.cpp
  ${CMAKE_CURRENT_LIST_DIR}/spray.cpp
  ${CMAKE_CURRENT_LIST_DIR}/blast.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_scenes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/anisotropy.cpp
  ${CMAKE_CURRENT_LIST_DIR}/diffuse.cpp
)
