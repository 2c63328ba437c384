# Fluid surface rendering (refraction, absorption, Fresnel), owned by the gpu module.
target_sources(engine PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/fluid_render.cpp
)
