// Screen-space fluid, pass 2 (Janisz §3.1.3): water thickness per pixel as the sum of the
// particle spheres' chords along the ray, clipped at the opaque scene (additive blending, no
// depth test), for the Beer–Lambert absorption of the composite pass.
uniform sampler2D u_scene_depth;
uniform vec3 u_eye;
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
layout(location = 0) out float out_thickness;

void main() {
  vec3 dir = pixelRay(gl_FragCoord.xy);
  float t0, t1;
  if (!hitParticle(dir, t0, t1)) discard;
  float scene = rayDistance(gl_FragCoord.xy, texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r, u_eye);
  float chord = min(t1, scene) - max(t0, 0.0);
  if (chord <= 0.0) discard;
  out_thickness = chord;
}
