// Depth-map colliders in the shader: Kolb et al. 2004 §4.1 (eq. (1), rule (2), invalid votes),
// §4.2 (L1 normal index texture, looked up, never recomputed), §4.3 (formats), and the §3.3.2
// double check + reaction. Texel bytes and their meaning follow fluid/collide/collide.hpp
// (normative encodings) and mirror its CPU query decision for decision, so the GPU and the CPU
// agree on which map wins and on the decoded depth and normal bit for bit.
//
// All maps of all colliders live in one R32UI buffer texture holding the texel bytes as they are
// (little-endian words): float32 = 4 words/texel, fixed8 and cube8 = 1, front_back16 = 2.

// A GPU may fuse a multiply and an add (FMA) where the CPU rounds twice; at a texel boundary or a
// tie of two votes that one rounding flips the texel or the winning map. `precise` (GLSL 4.00,
// ARB_gpu_shader5 under 3.30) keeps the stated operations in the position transforms and votes.
#extension GL_ARB_gpu_shader5 : enable
#ifdef GL_ARB_gpu_shader5
#define PRECISE precise
#else
#define PRECISE
#endif

// MAX_COLLIDERS and MAX_MAPS are #defined by the engine (kMaxGpuColliders, kMaxGpuDepthMaps).

uniform usamplerBuffer u_map_words;
uniform samplerBuffer u_normals;  // RGB float32 normal index tables, 3 floats per texel
uniform int u_collider_count;
uniform int u_collider_first_map[MAX_COLLIDERS + 1];
uniform ivec4 u_map_info[MAX_MAPS];    // format, compare, resolution N, first word
uniform vec4 u_map_params[MAX_MAPS];   // z_scale, cube_scale.xyz
uniform int u_map_encloses[MAX_MAPS];
uniform mat4 u_map_matrix[MAX_MAPS];   // T_OC->DC
uniform int u_normal_res[MAX_COLLIDERS];
uniform int u_normal_offset[MAX_COLLIDERS];  // first float of the collider's table
uniform vec4 u_pose_rotation[MAX_COLLIDERS];  // quaternion (x, y, z, w)
uniform vec3 u_pose_translation[MAX_COLLIDERS];
uniform vec3 u_pose_linear[MAX_COLLIDERS];
uniform vec3 u_pose_angular[MAX_COLLIDERS];
uniform float u_fixed_step;  // kFixedDepthStep, passed as the exact float
uniform float u_cube_step;   // kCubeRadiusStep
uniform float u_friction, u_resilience, u_friction_threshold, u_skin;
uniform int u_push_out_iterations;

const float kFloatMax = 3.402823466e38;
const uint kFixedBackground = 65535u;

struct Winner {
  float f;      // rule (2): starts "far inside"
  int map;      // -1: none (or only far-outside votes)
  int texel;
  int layer;    // front_back16: 0 front, 1 back
  bool any_vote;
};

// Rule (2), order-independent form (as fluid/collide): the smallest vote >= 0 if any, else the
// largest negative vote.
void vote(inout Winner w, float fi, int map, int texel, int layer) {
  w.any_vote = true;
  bool take = fi >= 0.0 ? (w.f < 0.0 || fi < w.f) : (w.f < 0.0 && fi > w.f);
  if (take) {
    w.f = fi;
    w.map = map;
    w.texel = texel;
    w.layer = layer;
  }
}

void invalidVote(inout Winner w, int map) {
  if (u_map_encloses[map] != 0) vote(w, kFloatMax, -1, 0, 0);
}

// IEEE binary16 -> float, exact (no unpackHalf2x16 in GLSL 3.30).
float halfToFloat(uint h) {
  uint sign_bit = (h & 0x8000u) << 16;
  uint e = (h >> 10) & 31u;
  uint m = h & 1023u;
  float v;
  if (e == 0u) {
    v = float(m) * 5.9604644775390625e-8;  // m·2^-24, exact
    return sign_bit != 0u ? -v : v;
  }
  if (e == 31u) return uintBitsToFloat(sign_bit | 0x7f800000u | (m << 13));
  return uintBitsToFloat(sign_bit | ((e + 112u) << 23) | (m << 13));
}

uint mapWord(int map, int word) { return texelFetch(u_map_words, u_map_info[map].w + word).r; }

vec3 transformPoint(mat4 m, vec3 p) { return m[0].xyz * p.x + m[1].xyz * p.y + m[2].xyz * p.z + m[3].xyz; }

void orthoVotes(inout Winner w, int map, vec3 p) {
  PRECISE vec3 q = transformPoint(u_map_matrix[map], p);
  int format = u_map_info[map].x;
  // Outside the map's footprint: invalid vote (§4.1).
  if (!(q.x >= 0.0 && q.x < 1.0 && q.y >= 0.0 && q.y < 1.0)) {
    if (format == 3) invalidVote(w, map);
    invalidVote(w, map);
    return;
  }
  // Along the view direction a LESS map holds up to its far plane, a GREATER map from its near
  // plane on (fluid/collide: in front of the near plane eq. (1) still holds).
  bool less_ok = q.z <= 1.0, greater_ok = q.z >= 0.0;
  int n = u_map_info[map].z;
  float nf = float(n);
  int i = min(int(q.x * nf), n - 1);
  int j = min(int(q.y * nf), n - 1);
  int texel = j * n + i;
  bool less = u_map_info[map].y == 0;
  float sign_less = less ? 1.0 : -1.0;
  float z_scale = u_map_params[map].x;
#ifdef FORMAT_FLOAT32
  if (format == 1) {
    float depth = uintBitsToFloat(mapWord(map, 4 * texel + 3));
    if (depth < 0.0 || !(less ? less_ok : greater_ok)) {
      invalidVote(w, map);
      return;
    }
    PRECISE float f = sign_less * z_scale * (depth - q.z);
    vote(w, f, map, texel, 0);
  }
#endif
#ifdef FORMAT_FIXED8
  if (format == 2) {
    uint word = mapWord(map, texel);
    uint code = (((word >> 16) & 255u) << 8) | (word >> 24);
    if (code == kFixedBackground || !(less ? less_ok : greater_ok)) {
      invalidVote(w, map);
      return;
    }
    PRECISE float f = sign_less * z_scale * (float(code) * u_fixed_step - q.z);
    vote(w, f, map, texel, 0);
  }
#endif
#ifdef FORMAT_FRONT_BACK16
  if (format == 3) {
    uint word = mapWord(map, 2 * texel + 1);
    float front = halfToFloat(word & 0xffffu);
    float back = halfToFloat(word >> 16);
    if (front < 0.0 || !less_ok) {
      invalidVote(w, map);
    } else {
      PRECISE float f = z_scale * (front - q.z);  // eq. (1), LESS
      vote(w, f, map, texel, 0);
    }
    if (back < 0.0 || !greater_ok) {
      invalidVote(w, map);
    } else {
      PRECISE float f = z_scale * (q.z - back);  // GREATER: eq. (1) negated
      vote(w, f, map, texel, 1);
    }
  }
#endif
}

// Cube face and face-local (sc, tc) by the OpenGL cube-map table, ties x before y before z.
int cubeFace(vec3 d, out float sc, out float tc, out float ma) {
  float ax = abs(d.x), ay = abs(d.y), az = abs(d.z);
  if (ax >= ay && ax >= az) {
    ma = ax;
    tc = -d.y;
    if (d.x >= 0.0) {
      sc = -d.z;
      return 0;
    }
    sc = d.z;
    return 1;
  }
  if (ay >= az) {
    ma = ay;
    sc = d.x;
    if (d.y >= 0.0) {
      tc = d.z;
      return 2;
    }
    tc = -d.z;
    return 3;
  }
  ma = az;
  tc = -d.y;
  if (d.z >= 0.0) {
    sc = d.x;
    return 4;
  }
  sc = -d.x;
  return 5;
}

// §4.3 depth cube: f = (1 − r/L)|S·P'| signed by the compare function.
void cubeVote(inout Winner w, int map, vec3 p) {
  PRECISE vec3 q = transformPoint(u_map_matrix[map], p);
  if (!(abs(q.x) <= 1.0 && abs(q.y) <= 1.0 && abs(q.z) <= 1.0)) {
    invalidVote(w, map);
    return;
  }
  PRECISE float len = sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  PRECISE vec3 dir = len > 0.0 ? q / len : vec3(0.0, 0.0, 1.0);
  float sc, tc, ma;
  int face = cubeFace(len > 0.0 ? q : dir, sc, tc, ma);
  int n = u_map_info[map].z;
  float nf = float(n);
  PRECISE float s = (sc / ma + 1.0) * 0.5;
  PRECISE float t = (tc / ma + 1.0) * 0.5;
  int i = clamp(int(s * nf), 0, n - 1);
  int j = clamp(int(t * nf), 0, n - 1);
  int texel = face * n * n + j * n + i;
  uint word = mapWord(map, texel);
  uint code = (((word >> 16) & 255u) << 8) | (word >> 24);
  if (code == kFixedBackground) {
    invalidVote(w, map);
    return;
  }
  float r = float(code) * u_cube_step;
  PRECISE float along = length(u_map_params[map].yzw * dir);
  PRECISE float f = (u_map_info[map].y == 0 ? (r - len) : (len - r)) * along;
  vote(w, f, map, texel, 0);
}

vec3 indexedNormal(int collider, uint ni, uint nj) {
  int base = u_normal_offset[collider] + 3 * (int(nj) * u_normal_res[collider] + int(ni));
  return vec3(texelFetch(u_normals, base).r, texelFetch(u_normals, base + 1).r, texelFetch(u_normals, base + 2).r);
}

// Collider-space sample. valid == false: no opinion (or non-finite point).
bool sampleCollider(int collider, vec3 p, out float dist, out vec3 normal) {
  dist = kFloatMax;
  normal = vec3(0.0, 0.0, 1.0);
  if (any(isnan(p)) || any(isinf(p))) return false;
  Winner w = Winner(-kFloatMax, -1, 0, 0, false);
  for (int m = u_collider_first_map[collider]; m < u_collider_first_map[collider + 1]; ++m) {
    // Only the formats present are compiled in (FORMAT_* defines per program variant).
#ifdef FORMAT_CUBE8
    if (u_map_info[m].x == 4) {
      cubeVote(w, m, p);
      continue;
    }
#endif
#if defined(FORMAT_FLOAT32) || defined(FORMAT_FIXED8) || defined(FORMAT_FRONT_BACK16)
    orthoVotes(w, m, p);
#endif
  }
  if (!w.any_vote || w.map < 0) return false;
  dist = w.f;
  int format = u_map_info[w.map].x;
#ifdef FORMAT_FLOAT32
  if (format == 1) {
    int base = 4 * w.texel;
    normal = vec3(uintBitsToFloat(mapWord(w.map, base)), uintBitsToFloat(mapWord(w.map, base + 1)),
                  uintBitsToFloat(mapWord(w.map, base + 2)));
    return true;
  }
#endif
#ifdef FORMAT_FRONT_BACK16
  if (format == 3) {
    uint word = mapWord(w.map, 2 * w.texel);
    uint pk = w.layer == 0 ? (word & 0xffffu) : (word >> 16);
    normal = indexedNormal(collider, pk & 255u, pk >> 8);
    return true;
  }
#endif
#if defined(FORMAT_FIXED8) || defined(FORMAT_CUBE8)
  uint word = mapWord(w.map, w.texel);  // fixed8 and cube8: R = i, G = j
  normal = indexedNormal(collider, word & 255u, (word >> 8) & 255u);
#endif
  return true;
}

// glm's quaternion-vector product, term for term.
vec3 quatRotate(vec4 q, vec3 v) {
  vec3 uv = cross(q.xyz, v);
  vec3 uuv = cross(q.xyz, uv);
  return v + ((uv * q.w) + uuv) * 2.0;
}

// World-space sample of collider c (fluid::queryWorld).
bool sampleWorld(int c, vec3 world, out float dist, out vec3 normal) {
  vec4 inv = vec4(-u_pose_rotation[c].xyz, u_pose_rotation[c].w) / dot(u_pose_rotation[c], u_pose_rotation[c]);
  PRECISE vec3 local = quatRotate(inv, world - u_pose_translation[c]);
  bool valid = sampleCollider(c, local, dist, normal);
  if (valid) normal = quatRotate(u_pose_rotation[c], normal);
  return valid;
}

// fluid::collisionResponse: v' = (1 − ν) v∥ − ε v⊥ (§3.3.2), friction skipped when slow.
vec3 collisionResponse(vec3 v, vec3 n) {
  float normal_speed = dot(v, n);
  if (normal_speed >= 0.0) return v;
  vec3 normal_part = normal_speed * n;
  vec3 tangential_part = v - normal_part;
  float friction = clamp(u_friction, 0.0, 1.0);
  float resilience = clamp(u_resilience, 0.0, 1.0);
  float keep = length(v) >= u_friction_threshold ? 1.0 - friction : 1.0;
  return keep * tangential_part - resilience * normal_part;
}

// fluid::collideParticles for every collider in turn: the double check of §3.3.2 at the
// previous position and the predicted one. Returns true when any collider reacted.
bool collideAll(vec3 previous, inout vec3 predicted, inout vec3 velocity) {
  bool hit = false;
  for (int c = 0; c < u_collider_count; ++c) {
    float d_after;
    vec3 n;
    if (!sampleWorld(c, predicted, d_after, n) || d_after >= 0.0) continue;
    float d_before;
    vec3 n_before;
    bool caught = sampleWorld(c, previous, d_before, n_before) && d_before < 0.0;
    vec3 collider_velocity = u_pose_linear[c] + cross(u_pose_angular[c], predicted - u_pose_translation[c]);
    vec3 relative = velocity - collider_velocity;
    predicted = predicted + n * (u_skin - d_after);
    if (!caught) {
      velocity = collisionResponse(relative, n) + collider_velocity;
    } else {
      float normal_speed = dot(relative, n);
      vec3 pushed = relative;
      if (normal_speed < 0.0) pushed = relative - 2.0 * normal_speed * n;
      velocity = pushed + collider_velocity;
    }
    // Extra projections while the new position is still inside (a neighbouring texel).
    for (int it = 0; it < u_push_out_iterations; ++it) {
      float d_again;
      vec3 n_again;
      if (!sampleWorld(c, predicted, d_again, n_again) || d_again >= 0.0) break;
      predicted = predicted + n_again * (u_skin - d_again);
    }
    hit = true;
  }
  return hit;
}
