# Sound synthesised from the simulation (engine/audio/synth.hpp): the mixer and its voices, the
# WAV writer, and the SDL device that pulls the mixer live.
target_sources(engine PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/synth.cpp
  ${CMAKE_CURRENT_LIST_DIR}/wav.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bubbles.cpp
  ${CMAKE_CURRENT_LIST_DIR}/device.cpp
)
