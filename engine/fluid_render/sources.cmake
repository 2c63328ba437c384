# Fluid surface rendering (refraction, absorption, Fresnel), owned by the gpu module: the mesh
# renderer and the two particle-direct ones (screen space, metaball ray casting).
target_sources(engine PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/fluid_render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/particle_pass.cpp
  ${CMAKE_CURRENT_LIST_DIR}/screen_space.cpp
  ${CMAKE_CURRENT_LIST_DIR}/raycast.cpp
  ${CMAKE_CURRENT_LIST_DIR}/water_backends.cpp
  ${CMAKE_CURRENT_LIST_DIR}/backdrop.cpp
  ${CMAKE_CURRENT_LIST_DIR}/voxel.cpp
  ${CMAKE_CURRENT_LIST_DIR}/first_surface.cpp
)
