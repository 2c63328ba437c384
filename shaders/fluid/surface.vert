// Fluid mesh from marching slices: world positions, outward unit normals and, for the goo, the
// per-vertex (u, v, skin weight, -) of fluid/blob/tentacle_uv.hpp (constant zero when absent).
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_attributes;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_world;
out vec3 v_normal;
out vec4 v_attributes;  // (u, v, skin weight, u shifted by half a turn: see goo.frag)
void main() {
  v_world = a_position;
  v_normal = a_normal;
  v_attributes = vec4(a_attributes.xyz, fract(a_attributes.x + 0.5) - 0.5);
  gl_Position = u_projection * u_view * vec4(a_position, 1.0);
}
