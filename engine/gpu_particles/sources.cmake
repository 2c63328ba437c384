# GPU state-preserving sprite particles (Kolb et al. 2004 §3), owned by the gpu module.
find_package(OpenGL REQUIRED COMPONENTS OpenGL)
target_sources(engine PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/gl_program.cpp
  ${CMAKE_CURRENT_LIST_DIR}/allocator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/emitters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gpu_particles.cpp
)
target_link_libraries(engine PUBLIC OpenGL::OpenGL)
# Core-profile entry points straight from GLVND's libOpenGL (no loader).
target_compile_definitions(engine PUBLIC GL_GLEXT_PROTOTYPES)
