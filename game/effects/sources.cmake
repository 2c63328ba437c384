# One file per game effect plus the registry (game/effects/effect.hpp), added to fluiddemo_game.
# Every .cpp here is taken: adding an effect is its file and its line in registry.cpp.
file(GLOB fluiddemo_effect_sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/*.cpp)
target_sources(fluiddemo_game PRIVATE ${fluiddemo_effect_sources})
