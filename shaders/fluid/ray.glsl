// The pixel's view ray in world space and distances along it, for the particle renderers.
uniform mat4 u_inv_view_projection;
uniform vec2 u_viewport;

vec3 unprojectPixel(vec2 frag, float window_depth) {
  vec4 p = u_inv_view_projection * vec4(frag / u_viewport * 2.0 - 1.0, window_depth * 2.0 - 1.0, 1.0);
  return p.xyz / p.w;
}

// Unit direction from the eye through the pixel centre `frag` (gl_FragCoord.xy).
vec3 pixelRay(vec2 frag) { return normalize(unprojectPixel(frag, 1.0) - unprojectPixel(frag, 0.0)); }

// Distance from `eye` along the pixel's ray to the point at window depth `window_depth`.
float rayDistance(vec2 frag, float window_depth, vec3 eye) {
  return length(unprojectPixel(frag, window_depth) - eye);
}

// Ray (eye, dir) against the sphere (centre, radius): false if missed, else entry/exit distances.
bool raySphere(vec3 eye, vec3 dir, vec3 centre, float radius, out float t0, out float t1) {
  vec3 oc = centre - eye;
  float m = dot(oc, dir);                      // midpoint m_j (Szécsi & Illés §3)
  float q2 = dot(oc, oc) - m * m;              // squared distance of the centre from the ray
  float h2 = radius * radius - q2;             // Q_j^2
  if (h2 <= 0.0) return false;
  float h = sqrt(h2);
  t0 = m - h;
  t1 = m + h;
  return true;
}

// Ray (eye, dir) against the ellipsoid { x : |g (x - centre)| <= radius }, g symmetric positive
// definite (Yu & Turk 2013's G times h, fluid/sph/anisotropy.hpp): mapped by g / radius the
// ellipsoid is the unit sphere and the ray o + t d keeps its parameter t, so t0, t1 are distances
// along `dir` as raySphere's. The closest approach q is formed directly (no b^2 - ac cancellation).
bool rayEllipsoid(vec3 eye, vec3 dir, vec3 centre, mat3 g, float radius, out float t0, out float t1) {
  vec3 o = g * (eye - centre) / radius;
  vec3 d = g * dir / radius;
  float a = dot(d, d);
  if (!(a > 0.0)) return false;
  float m = -dot(o, d) / a;  // parameter of the closest approach to the centre
  vec3 q = o + m * d;
  float h2 = (1.0 - dot(q, q)) / a;
  if (h2 <= 0.0) return false;
  float h = sqrt(h2);
  t0 = m - h;
  t1 = m + h;
  return true;
}

// Outward normal of that ellipsoid at p (the gradient of |g (p - centre)|^2).
vec3 ellipsoidNormal(vec3 p, vec3 centre, mat3 g) { return normalize(g * (g * (p - centre))); }
