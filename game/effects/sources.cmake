# One file per game effect plus the registry (game/effects/effect.hpp), added to fluiddemo_game.
target_sources(fluiddemo_game PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/registry.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rigid_bodies.cpp
  ${CMAKE_CURRENT_LIST_DIR}/explosives.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sph_fluid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sprite_particles.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fluid_surface.cpp
  ${CMAKE_CURRENT_LIST_DIR}/blob.cpp
  ${CMAKE_CURRENT_LIST_DIR}/audio.cpp
)
