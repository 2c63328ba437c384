# Sources of fluid/blob (the blob monster's particle body and behaviours), added to the `fluid` library.
target_sources(fluid PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/body.cpp
  ${CMAKE_CURRENT_LIST_DIR}/behaviour.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tentacle_uv.cpp
)
