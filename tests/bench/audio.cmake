# Benchmark of the sound (issue 39; Google Benchmark, not registered with ctest):
#   bench_audio: the audio effect's main-thread step on the shipped fountain (13,000 particles) and
#   the mixer's cost per 512-frame device buffer at 64 and 256 voices.
add_executable(bench_audio ${CMAKE_CURRENT_LIST_DIR}/audio_bench.cpp)
target_link_libraries(bench_audio PRIVATE fluiddemo_game benchmark::benchmark fluiddemo_options)
target_compile_definitions(bench_audio PRIVATE FLUIDDEMO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
