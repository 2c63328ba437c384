# Sources of the game world, added to fluiddemo_game.
target_sources(fluiddemo_game PRIVATE ${CMAKE_CURRENT_LIST_DIR}/run_scene_pending.cpp)
