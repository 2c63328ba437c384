// Metaball ray casting, gathering (Szécsi & Illés 2012 §5): every particle's effective sphere
// (radius Rc, the support of the field) prepends a record to its pixel's linked list: the
// particle index, the next record, and the effective interval [t0, t1] clipped against the
// opaque scene. Records come from one bounded pool; a full pool drops the record and counts it
// (the paper's fixed-size storage trade-off, §6), so a caller can see and size the overflow.
layout(binding = 0, r32ui) uniform coherent uimage2D u_heads;  // 0xffffffff = empty list
layout(std430, binding = 0) buffer Nodes { uvec4 nodes[]; };   // (particle, next, t0 bits, t1 bits)
layout(std430, binding = 1) buffer Counters {
  uint used;     // records asked for (may exceed the pool)
  uint dropped;  // records refused because the pool was full
};
uniform sampler2D u_scene_depth;
uniform vec3 u_eye;
uniform float u_radius;  // Rc
uniform uint u_pool;     // records in `nodes`
flat in vec3 v_centre;
flat in int v_index;
#ifdef ELLIPSOID
flat in vec3 v_g0, v_g1, v_g2;  // ellipsoidal metaballs: the support is |g (x - centre)| < Rc
#endif

void main() {
  vec3 dir = pixelRay(gl_FragCoord.xy);
  float t0, t1;
#ifdef ELLIPSOID
  if (!rayEllipsoid(u_eye, dir, v_centre, mat3(v_g0, v_g1, v_g2), u_radius, t0, t1)) discard;
#else
  if (!raySphere(u_eye, dir, v_centre, u_radius, t0, t1)) discard;
#endif
  float scene = rayDistance(gl_FragCoord.xy, texelFetch(u_scene_depth, ivec2(gl_FragCoord.xy), 0).r, u_eye);
  if (t1 <= 0.0 || t0 >= scene) discard;
  uint slot = atomicAdd(used, 1u);
  if (slot >= u_pool) {
    atomicAdd(dropped, 1u);
    discard;
  }
  uint next = imageAtomicExchange(u_heads, ivec2(gl_FragCoord.xy), slot);
  nodes[slot] = uvec4(uint(v_index), next, floatBitsToUint(t0), floatBitsToUint(t1));
}
