# Explosives: fused Bullet charges whose detonations are fluid::Blast values for the other effects.
target_sources(fluiddemo_game PRIVATE ${CMAKE_CURRENT_LIST_DIR}/explosives.cpp)
