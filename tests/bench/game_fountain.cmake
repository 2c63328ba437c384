# The game aim of issue 4 on the game's own fountain (game::initSphFluid / stepSphFluid): a plain executable.
add_executable(bench_game_fountain ${CMAKE_CURRENT_LIST_DIR}/game_fountain_bench.cpp)
target_link_libraries(bench_game_fountain PRIVATE fluiddemo_game fluiddemo_options)
target_compile_definitions(bench_game_fountain PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
