#version 330 core
// Full-screen triangle at the far plane; the fragment shader recovers the view ray.
uniform mat4 u_inverse_view_projection;
out vec3 v_ray;

void main() {
  vec2 corner = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  vec2 ndc = corner * 2.0 - 1.0;
  vec4 far_point = u_inverse_view_projection * vec4(ndc, 1.0, 1.0);
  vec4 near_point = u_inverse_view_projection * vec4(ndc, -1.0, 1.0);
  v_ray = far_point.xyz / far_point.w - near_point.xyz / near_point.w;
  gl_Position = vec4(ndc, 1.0, 1.0);
}
