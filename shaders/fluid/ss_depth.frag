// Screen-space fluid, pass 1 (Janisz §3.1.1, van der Laan et al. 2009): the nearest particle
// sphere per pixel. The ray-sphere hit is exact (not the sprite's depth-replacement
// approximation); the output is linear view depth, so the bilateral weights of the smoothing
// pass do not depend on the distance to the camera (the z-buffer issue of Janisz §3.1.2.1).
uniform sampler2D u_scene_depth;
uniform vec3 u_eye;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_radius;
flat in vec3 v_centre;
#ifdef ELLIPSOID
flat in vec3 v_g0, v_g1, v_g2;
#endif

// The pixel's ray against this particle's sphere, or its ellipsoid with ELLIPSOID (ray.glsl).
bool hitParticle(vec3 dir, out float t0, out float t1) {
#ifdef ELLIPSOID
  return rayEllipsoid(u_eye, dir, v_centre, mat3(v_g0, v_g1, v_g2), u_radius, t0, t1);
#else
  return raySphere(u_eye, dir, v_centre, u_radius, t0, t1);
#endif
}
layout(location = 0) out float out_depth;

void main() {
  vec3 dir = pixelRay(gl_FragCoord.xy);
  float t0, t1;
  if (!hitParticle(dir, t0, t1) || t0 <= 0.0) discard;
  vec3 p = u_eye + t0 * dir;
  vec4 clip = u_projection * u_view * vec4(p, 1.0);
  float window_depth = clip.z / clip.w * 0.5 + 0.5;
  if (window_depth >= texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r) discard;  // behind the scene
  gl_FragDepth = window_depth;
  out_depth = -(u_view * vec4(p, 1.0)).z;
}
