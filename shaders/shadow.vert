#version 330 core
// Depth-only pass from the sun for the shadow map.
layout(location = 0) in vec3 in_position;
uniform mat4 u_light_view_projection;
uniform mat4 u_model;

void main() { gl_Position = u_light_view_projection * u_model * vec4(in_position, 1.0); }
