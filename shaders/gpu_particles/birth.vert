// Births (§3.3.1): each new particle is one point drawn onto its texel of the current state,
// velocity/previous-position and attribute textures (multiple render targets).
layout(location = 0) in int a_index;
layout(location = 1) in vec3 a_position;
layout(location = 2) in vec3 a_velocity;
layout(location = 3) in vec4 a_attributes;  // birth time, death time, type, spin

uniform ivec2 u_size;

flat out vec3 v_position;
flat out vec3 v_velocity;
flat out vec4 v_attributes;

void main() {
  ivec2 texel = ivec2(a_index % u_size.x, a_index / u_size.x);
  gl_Position = vec4((vec2(texel) + 0.5) / vec2(u_size) * 2.0 - 1.0, 0.0, 1.0);
  gl_PointSize = 1.0;
  v_position = a_position;
  v_velocity = a_velocity;
  v_attributes = a_attributes;
}
