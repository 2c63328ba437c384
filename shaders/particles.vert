#version 330 core
// Camera-facing sprite per particle: an instanced quad (two triangles, corners from
// gl_VertexID) in view space. Quads rather than GL_POINTS: llvmpipe's overlapping points gave
// run-to-run different results, and many drivers cap gl_PointSize at 64 px.
layout(location = 0) in vec4 in_particle;  // per instance: xyz position, w shade 0..1
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_projection_scale;  // projection[1][1] * viewport height / 2 (pixels per unit at depth 1)
uniform float u_radius;
out float v_shade;
out vec3 v_world;
out vec2 v_corner;

const vec2 kCorners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));

void main() {
  vec2 corner = kCorners[gl_VertexID];
  vec4 centre = u_view * vec4(in_particle.xyz, 1.0);
  // Never smaller than about one pixel, so distant spray stays visible instead of aliasing away.
  float depth = max(-centre.z, 1e-3);
  float radius = max(u_radius, 0.7 * depth / u_projection_scale);
  gl_Position = u_projection * vec4(centre.xy + corner * radius, centre.z, 1.0);
  v_shade = in_particle.w;
  v_world = in_particle.xyz;
  v_corner = corner;
}
