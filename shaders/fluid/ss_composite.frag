// Screen-space fluid, pass 4 (Janisz §3.1.4): surface position from the smoothed linear depth,
// normal from depth differences (the smaller one-sided difference per axis, so silhouettes do
// not bend normals, van der Laan et al. 2009 §4), then the mesh's water shading with the
// thickness pass's absorption. Blended "over" the opaque scene already in the target.
uniform sampler2D u_fluid_depth;
uniform sampler2D u_thickness;
uniform mat4 u_projection;
layout(location = 0) out vec4 out_colour;

vec3 viewPosition(ivec2 c, float z) {
  vec2 ndc = (vec2(c) + 0.5) / u_viewport * 2.0 - 1.0;
  return vec3(ndc.x * z / u_projection[0][0], ndc.y * z / u_projection[1][1], -z);
}

// One-sided differences along `step`; the side with the smaller depth jump (an empty
// neighbour counts as infinitely far).
vec3 tangent(ivec2 c, vec3 p, ivec2 step) {
  float zf = texelFetch(u_fluid_depth, c + step, 0).r, zb = texelFetch(u_fluid_depth, c - step, 0).r;
  vec3 forward = viewPosition(c + step, zf) - p, backward = p - viewPosition(c - step, zb);
  bool use_forward = zf < 1e20 && (zb >= 1e20 || abs(forward.z) <= abs(backward.z));
  if (zf >= 1e20 && zb >= 1e20) return vec3(vec2(step), 0.0);
  return use_forward ? forward : backward;
}

void main() {
  ivec2 c = ivec2(gl_FragCoord.xy);
  float z = texelFetch(u_fluid_depth, c, 0).r;
  if (z >= 1e20) discard;
  vec3 p = viewPosition(c, z);
  vec3 n_view = normalize(cross(tangent(c, p, ivec2(1, 0)), tangent(c, p, ivec2(0, 1))));
  if (dot(n_view, -p) < 0.0) n_view = -n_view;
  mat3 view_to_world = transpose(mat3(u_view));
  vec3 world = u_eye + view_to_world * p;
  vec3 n = normalize(view_to_world * n_view);
  float thickness = texelFetch(u_thickness, c, 0).r;
  out_colour = shadeWater(gl_FragCoord.xy / u_viewport, world, n, z, thickness);
}
