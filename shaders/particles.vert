#version 330 core
// Point sprites sized so that the sprite covers a sphere of radius u_radius (perspective).
layout(location = 0) in vec4 in_particle;  // xyz position, w shade 0..1
uniform mat4 u_view_projection;
uniform float u_projection_scale;  // projection[1][1] * viewport height / 2
uniform float u_radius;
out float v_shade;
out vec3 v_world;

void main() {
  vec4 clip = u_view_projection * vec4(in_particle.xyz, 1.0);
  gl_Position = clip;
  gl_PointSize = clamp(2.0 * u_radius * u_projection_scale / max(clip.w, 1e-3), 1.0, 64.0);
  v_shade = in_particle.w;
  v_world = in_particle.xyz;
}
