// One camera-facing triangle per particle (instanced, 3 vertices) holding the square that covers
// the projection of the sphere of radius u_radius around it: placed at the sphere's nearest
// point, sized by the tangent cone from the eye. One triangle, not a quad of two: a pixel on a
// quad's diagonal lies inside the sphere, and llvmpipe ran the gather shader's atomics for the
// lanes of the other triangle's pixels in a shared 4x4 block, corrupting those pixels' lists
// (seen as holes along the diagonal); with one triangle every uncovered lane is outside the
// sphere and discards before any side effect. Billboards rather than point sprites because GL caps
// the point size (llvmpipe at 255 px) and a support sphere near the camera is larger. When the
// eye is inside the sphere or it nears the near plane, the square covers the whole viewport.
// The fragment shaders intersect the pixel's ray with the sphere exactly (ray.glsl).
// With ELLIPSOID defined (anisotropic kernels, Yu & Turk 2013; fluid/sph/anisotropy.hpp) each
// particle also carries g = h G (attributes 1-3: its columns, the first's w the largest semi-axis
// over u_radius): the square covers the ellipsoid's bounding sphere, radius u_radius * max axis,
// and the fragment shaders intersect the ellipsoid (rayEllipsoid).
layout(location = 0) in vec4 a_centre;
#ifdef ELLIPSOID
layout(location = 1) in vec4 a_g0;
layout(location = 2) in vec4 a_g1;
layout(location = 3) in vec4 a_g2;
flat out vec3 v_g0, v_g1, v_g2;
#endif
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_eye;
uniform vec2 u_near_far;
uniform float u_radius;
flat out vec3 v_centre;
flat out int v_index;

void main() {
  v_centre = a_centre.xyz;
  float radius = u_radius;
  v_index = gl_InstanceID;
#ifdef ELLIPSOID
  v_g0 = a_g0.xyz;
  v_g1 = a_g1.xyz;
  v_g2 = a_g2.xyz;
  radius *= max(a_g0.w, 1e-3);  // the ellipsoid's bounding sphere
#endif
  vec2 corner = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);  // covers [-1, 1]^2
  vec3 to_centre = a_centre.xyz - u_eye;
  float d = length(to_centre);
  if (d - radius < 2.0 * u_near_far.x) {
    gl_Position = vec4(corner, 0.0, 1.0);
    return;
  }
  vec3 axis = to_centre / d;
  vec3 up = abs(axis.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 right = normalize(cross(axis, up));
  up = cross(right, axis);
  // Tangent cone half-angle: tan = R / sqrt(d^2 - R^2); at distance d - R along the axis.
  float near_distance = d - radius;
  float half_size = near_distance * radius / sqrt(d * d - radius * radius);
  vec3 p = u_eye + axis * near_distance + (right * corner.x + up * corner.y) * half_size;
  gl_Position = u_projection * u_view * vec4(p, 1.0);
}
