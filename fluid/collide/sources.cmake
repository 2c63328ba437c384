# Sources of fluid/collide, added to the `fluid` library.
# target_sources(fluid PRIVATE ${CMAKE_CURRENT_LIST_DIR}/file.cpp)
