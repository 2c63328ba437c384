# Sources of the game world, added to fluiddemo_game.
target_sources(fluiddemo_game PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/fountain.cpp
  ${CMAKE_CURRENT_LIST_DIR}/collider_model.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sprite_particles.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rigid_bodies.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_fluid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fluid_surface.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_job.cpp
  ${CMAKE_CURRENT_LIST_DIR}/blob_program.cpp
  ${CMAKE_CURRENT_LIST_DIR}/blob_crates.cpp
  ${CMAKE_CURRENT_LIST_DIR}/body_fluid_coupling.cpp
  ${CMAKE_CURRENT_LIST_DIR}/world.cpp
  ${CMAKE_CURRENT_LIST_DIR}/level.cpp
  ${CMAKE_CURRENT_LIST_DIR}/level_assets.cpp
  ${CMAKE_CURRENT_LIST_DIR}/../run_scene.cpp
)
