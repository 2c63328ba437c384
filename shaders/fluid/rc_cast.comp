// Metaball ray casting, the cast (Szécsi & Illés 2012 §4, §6) over the lists of rc_gather.frag.
// The field is the mesh's (Rosenberg & Birdwell 2008 §2, fluid/surface/detail/field.hpp):
// f_j(r) = (u − 1/2)^2 with u = r^2 / (2 Rc^2) inside Rc, and the surface is sum f_j = T. Since
// f_j depends on r^2 and r^2 is quadratic along the ray, each particle adds an exact quartic
// over its effective interval [t0, t1] (the paper's "exact polynomials for appropriately chosen
// density functions", §3), and f_j and its derivative vanish at both ends, so the summed field
// is a C1 piecewise quartic whose separators are the interval ends. Per pixel: keep the
// kMaxRecords nearest records sorted by t0 (a longer list is cut at the first record left
// out), sweep the separators in order keeping the running coefficients, and in each subdomain find the crossings of T (sign test on 4 sub-steps, then
// bisection). The first upward crossing is the surface; the summed inside length up to the
// scene is the water thickness for absorption. Normal = −∇ sum f_j at the hit (paper §5).
// A compute pass, not a full-screen fragment pass: llvmpipe ran this shader wrongly in 4x4 blocks
// that a full-screen polygon's two triangles share (its per-lane arrays lost records: holes along
// the viewport diagonal), and compute invocations have no partial coverage. rc_shade.frag then
// shades the hits.
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32ui) uniform readonly uimage2D u_heads;
layout(binding = 1, rgba32f) uniform writeonly image2D u_hits;       // outward normal, hit distance (< 0: none)
layout(binding = 2, r32f) uniform writeonly image2D u_thickness_out;  // water along the ray, metres
uniform sampler2D u_scene_depth;
uniform vec3 u_eye;
layout(std430, binding = 0) readonly buffer Nodes { uvec4 nodes[]; };
layout(std430, binding = 2) readonly buffer Particles { vec4 centres[]; };
#ifdef ELLIPSOID
// Ellipsoidal metaballs (Yu & Turk 2013's G times h per particle, 3 vec4 columns): r^2 below is
// |g (x - centre)|^2 instead of |x - centre|^2, still quadratic along the ray.
layout(std430, binding = 3) readonly buffer Shapes { vec4 shapes[]; };
mat3 shapeOf(int id) { return mat3(shapes[3 * id].xyz, shapes[3 * id + 1].xyz, shapes[3 * id + 2].xyz); }
#endif
uniform float u_rc;
uniform float u_threshold;

const int kMaxRecords = 32;
const uint kEnd = 0xffffffffu;

float t0s[kMaxRecords];  // records by entry, ascending
float t1s[kMaxRecords];
int ids[kMaxRecords];
float exits[kMaxRecords];  // the same records' exits, ascending
int exit_ids[kMaxRecords];
float coef[5];  // running sum of the live quartics in s = t − reference, coef[j] · s^j

// Shifts the running polynomial's origin by delta (Taylor shift, Horner scheme), so the
// coefficients stay those of a local parameter and float keeps its precision on long rays.
void shiftOrigin(float delta) {
  for (int i = 0; i < 4; ++i)
    for (int j = 3; j >= i; --j) coef[j] += delta * coef[j + 1];
}

// Adds sign × particle `id`'s quartic, in s = t − reference, to the running sum.
void addParticle(int id, vec3 eye, vec3 dir, float reference, float sign) {
#ifdef ELLIPSOID
  // In g space the ray is P + s v (P at the reference), r^2 = |P + s v|^2.
  mat3 g = shapeOf(id);
  vec3 v = g * dir;
  vec3 p = g * (eye + reference * dir - centres[id].xyz);  // the reference point is near the particle
  float k = 1.0 / (2.0 * u_rc * u_rc);
  float a = k * dot(v, v), b = 2.0 * k * dot(p, v), c = k * dot(p, p) - 0.5;
#else
  vec3 oc = centres[id].xyz - eye;
  float m = dot(oc, dir);
  float q2 = max(dot(oc, oc) - m * m, 0.0);
  float k = 1.0 / (2.0 * u_rc * u_rc);
  float g = reference - m;
  // w(s) = k r^2 − 1/2 = A s^2 + B s + C, r^2 = (s + g)^2 + q2; f = w^2.
  float a = k, b = 2.0 * k * g, c = k * (g * g + q2) - 0.5;
#endif
  coef[4] += sign * a * a;
  coef[3] += sign * 2.0 * a * b;
  coef[2] += sign * (b * b + 2.0 * a * c);
  coef[1] += sign * 2.0 * b * c;
  coef[0] += sign * c * c;
}

float fieldMinusT(float s) {
  return (((coef[4] * s + coef[3]) * s + coef[2]) * s + coef[1]) * s + coef[0] - u_threshold;
}

// −∇ sum f_j at x over the records whose interval holds distance t (field.hpp's gradient:
// df/dc = 4 s (u − 1/2) k (c − p)).
vec3 outwardNormal(vec3 x, float t, int count) {
  float k = 1.0 / (2.0 * u_rc * u_rc);
  vec3 gradient = vec3(0.0);
  for (int i = 0; i < count; ++i) {
    if (t0s[i] > t || t1s[i] <= t) continue;
    vec3 d = x - centres[ids[i]].xyz;
#ifdef ELLIPSOID
    mat3 g = shapeOf(ids[i]);
    vec3 y = g * d;  // gradient of |g d|^2 / 2 is g^T g d (g symmetric)
    gradient += 4.0 * (dot(y, y) * k - 0.5) * k * (g * y);
#else
    gradient += 4.0 * (dot(d, d) * k - 0.5) * k * d;
#endif
  }
  return length(gradient) > 0.0 ? -normalize(gradient) : vec3(0.0, 1.0, 0.0);
}

// Gathers the pixel's list: the kMaxRecords records with the smallest t0, sorted by t0, and
// their exits sorted. Returns the count; `horizon` is the nearest t0 left out (1e30 if none):
// past it the field lacks terms, so the sweep stops there (the paper's "safe zone", §6).
int gatherRecords(uint node, out float horizon) {
  int count = 0;
  horizon = 1e30;
  for (int guard = 0; node != kEnd && guard < 65536; ++guard) {
    uvec4 r = nodes[node];
    node = r.y;
    float t0 = uintBitsToFloat(r.z);
    if (count == kMaxRecords) {
      horizon = min(horizon, max(t0, t0s[kMaxRecords - 1]));
      if (t0 >= t0s[kMaxRecords - 1]) continue;
    }
    int j = min(count, kMaxRecords - 1);
    for (; j > 0 && t0s[j - 1] > t0; --j) {
      t0s[j] = t0s[j - 1];
      t1s[j] = t1s[j - 1];
      ids[j] = ids[j - 1];
    }
    t0s[j] = t0;
    t1s[j] = uintBitsToFloat(r.w);
    ids[j] = int(r.x);
    count = min(count + 1, kMaxRecords);
  }
  for (int i = 0; i < count; ++i) {
    int j = i;
    for (; j > 0 && exits[j - 1] > t1s[i]; --j) {
      exits[j] = exits[j - 1];
      exit_ids[j] = exit_ids[j - 1];
    }
    exits[j] = t1s[i];
    exit_ids[j] = ids[i];
  }
  return count;
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(vec2(pixel), u_viewport))) return;
  vec2 frag = vec2(pixel) + 0.5;
  float horizon;
  int count = gatherRecords(imageLoad(u_heads, pixel).r, horizon);
  vec3 dir = pixelRay(frag);
  float scene = min(rayDistance(frag, texelFetch(u_scene_depth, pixel, 0).r, u_eye), horizon);
  for (int i = 0; i < 5; ++i) coef[i] = 0.0;
  float reference = count > 0 ? max(t0s[0], 0.0) : 0.0;  // the running polynomial's origin
  float current = reference;                              // start of the next subdomain
  int next_entry = 0, next_exit = 0, live = 0;
  bool inside = false;
  float hit = -1.0, entered = 0.0, thickness = 0.0, swept = 0.0;
  for (int event = 0; event < 2 * count; ++event) {
    // Next separator: the nearer of the next entry and the next exit (merge of two sorted lists).
    bool entry = next_entry < count && t0s[next_entry] <= exits[next_exit];
    float next = entry ? t0s[next_entry] : exits[next_exit];
    // Subdomain [current, min(next, scene)]: crossings of T.
    float end = min(next, scene);
    swept = max(swept, end);
    if (end > current && live > 0) {
      float a = current, fa = fieldMinusT(a - reference);
      if ((fa >= 0.0) != inside) {  // only at the very start: the eye is inside the water
        inside = fa >= 0.0;
        entered = a;
        if (inside && hit < 0.0) hit = a;
      }
      for (int step = 1; step <= 4; ++step) {
        float b = mix(current, end, float(step) * 0.25), fb = fieldMinusT(b - reference);
        if ((fb >= 0.0) != (fa >= 0.0)) {
          float lo = a, hi = b;
          for (int it = 0; it < 12; ++it) {
            float mid = 0.5 * (lo + hi);
            if ((fieldMinusT(mid - reference) >= 0.0) == (fa >= 0.0)) {
              lo = mid;
            } else {
              hi = mid;
            }
          }
          float root = 0.5 * (lo + hi);
          if (fb >= 0.0) {
            inside = true;
            entered = root;
            if (hit < 0.0) hit = root;
          } else {
            inside = false;
            thickness += root - entered;
          }
        }
        a = b;
        fa = fb;
      }
    }
    if (next >= scene) break;
    // Apply the separator: move the origin there, then add or remove the particle's quartic.
    shiftOrigin(next - reference);
    reference = next;
    current = max(current, next);
    if (entry) {
      addParticle(ids[next_entry], u_eye, dir, reference, 1.0);
      ++next_entry;
      ++live;
    } else {
      --live;
      if (live == 0) {
        for (int i = 0; i < 5; ++i) coef[i] = 0.0;  // exactly empty again, no rounding residue
      } else {
        addParticle(exit_ids[next_exit], u_eye, dir, reference, -1.0);
      }
      ++next_exit;
    }
  }
  if (inside) thickness += swept - entered;  // the scene (or the record cap) cuts the water
  if (hit < 0.0) {
    imageStore(u_hits, pixel, vec4(0.0, 0.0, 0.0, -1.0));
    return;
  }
  vec3 normal = outwardNormal(u_eye + hit * dir, hit, count);
  if (dot(normal, -dir) < 0.0) normal = -normal;
  imageStore(u_hits, pixel, vec4(normal, hit));
  imageStore(u_thickness_out, pixel, vec4(thickness));
}
