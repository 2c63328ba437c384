#version 330 core
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
uniform mat4 u_view_projection;
uniform mat4 u_model;
uniform mat4 u_normal_matrix;
uniform mat4 u_light_view_projection;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_light_clip;

void main() {
  vec4 world = u_model * vec4(in_position, 1.0);
  v_world = world.xyz;
  v_normal = mat3(u_normal_matrix) * in_normal;
  v_uv = in_uv;
  v_light_clip = u_light_view_projection * world;
  gl_Position = u_view_projection * world;
}
