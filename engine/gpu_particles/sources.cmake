# GPU state-preserving sprite particles (Kolb et al. 2004 §3). GL and SDL come from engine/CMakeLists.txt.
target_sources(engine PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/allocator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/emitters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gpu_particles.cpp
)
