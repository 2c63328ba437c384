# Project-wide compile settings, applied through an interface target so every
# fluiddemo target opts in explicitly with target_link_libraries(... fluiddemo_options).
add_library(fluiddemo_options INTERFACE)
target_compile_options(fluiddemo_options INTERFACE -Wall -Wextra -Wshadow)

if(FLUIDDEMO_KEEP_ASSERTS)
  # CMake's Release/RelWithDebInfo flags add -DNDEBUG; undo it for our own targets.
  target_compile_options(fluiddemo_options INTERFACE -UNDEBUG)
endif()

if(FLUIDDEMO_SANITIZE STREQUAL "address")
  target_compile_options(fluiddemo_options INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(fluiddemo_options INTERFACE -fsanitize=address,undefined)
elseif(FLUIDDEMO_SANITIZE STREQUAL "thread")
  target_compile_options(fluiddemo_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_link_options(fluiddemo_options INTERFACE -fsanitize=thread)
elseif(NOT FLUIDDEMO_SANITIZE STREQUAL "")
  message(FATAL_ERROR "FLUIDDEMO_SANITIZE must be empty, 'address' or 'thread', not '${FLUIDDEMO_SANITIZE}'")
endif()
