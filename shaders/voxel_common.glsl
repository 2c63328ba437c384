// Shared by the voxel passes (Zirr & Dachsbacher 2015; engine/fluid_render/voxel.hpp). The
// arithmetic that decides bits and spans is written out under `precise`, in the order of
// fluid/surface/voxel_reference.cpp, so the GPU sets the same bits as the CPU reference (no fused
// multiply-add, no reassociation).
uniform ivec2 u_size;      // viewport, px
uniform vec4 u_proj;       // projection P00, P11, P20, P21
uniform int u_layer_count; // layers per column, a multiple of 32
uniform int u_words;       // u_layer_count / 32
uniform int u_max_spans;   // spans stored per pixel (§3.1: up to 7 in the paper)
layout(std430, binding = 1) readonly buffer Layers { float layer_depth[]; };  // u_layer_count + 1 boundaries

// Link bytes (§3.3, §4.5): 0..u_max_spans-1 = that span of the neighbour, same side; kOwnAdjacent
// = this column's previous exit (for an entry) or next entry (for an exit): a bubble wall (Fig. 3b);
// kOwnOther = this span's other side: no overlapping neighbour, a boundary (Fig. 3c).
const uint kOwnAdjacent = 0xfeu;
const uint kOwnOther = 0xffu;

// a / b and sqrt(x) rounded as the CPU reference's IEEE float operations round them. `precise`
// stops fusing and reordering but not a driver's approximate divide and square root (NVIDIA's
// divide through a reciprocal and are off by an ulp or two), which moves a depth across a layer
// boundary now and then; one fma correction step from the exact residual (Markstein 1990) gives
// the correctly rounded result, and leaves an already correctly rounded one as it is.
float quotient(float a, float b) {
  precise float q = a / b;
  precise float residual = fma(-q, b, a);  // a − q b, exact
  precise float corrected = fma(residual, 1.0 / b, q);
  return corrected;
}
float squareRoot(float x) {
  precise float s = sqrt(x);
  if (!(s > 0.0) || isinf(s)) return s;
  precise float residual = fma(-s, s, x);  // x − s², exact
  precise float corrected = fma(residual, quotient(0.5, s), s);
  return corrected;
}

// View-space ray through pixel p's centre, z = −1: the point at view depth d is d * ray.
vec3 columnRay(ivec2 p) {
  precise float ndc_x = quotient(float(p.x) + 0.5, float(u_size.x)) * 2.0 - 1.0;
  precise float ndc_y = quotient(float(p.y) + 0.5, float(u_size.y)) * 2.0 - 1.0;
  precise float rx = quotient(ndc_x + u_proj.z, u_proj.x);
  precise float ry = quotient(ndc_y + u_proj.w, u_proj.y);
  return vec3(rx, ry, -1.0);
}

float rayLength(vec3 r) {
  precise float s = r.x * r.x + r.y * r.y + r.z * r.z;
  return squareRoot(s);
}

// The layer holding view depth d (binary search in the boundary table, as voxelLayerOf).
int layerOf(float d) {
  if (!(d >= layer_depth[0])) return -1;
  if (d >= layer_depth[u_layer_count]) return u_layer_count;
  int lo = 0, hi = u_layer_count;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (layer_depth[mid] <= d) lo = mid;
    else hi = mid;
  }
  return lo;
}

// voxelSphereLayers: layers [first, last] of the ray inside the sphere, clamped to the grid.
bool sphereLayers(vec3 ray, vec3 c, float radius, out int first, out int last) {
  precise float rc = ray.x * c.x + ray.y * c.y + ray.z * c.z;
  precise float rr = ray.x * ray.x + ray.y * ray.y + ray.z * ray.z;
  precise float cc = c.x * c.x + c.y * c.y + c.z * c.z;
  precise float disc = rc * rc - rr * (cc - radius * radius);
  first = 0;
  last = -1;
  if (!(disc > 0.0)) return false;
  precise float s = squareRoot(disc);
  precise float z0 = quotient(rc - s, rr);
  precise float z1 = quotient(rc + s, rr);
  first = layerOf(z0);
  last = layerOf(z1);
  if (last < 0 || first >= u_layer_count) return false;
  first = max(first, 0);
  last = min(last, u_layer_count - 1);
  return true;
}

// Octahedral normal encoding (§4.5, Meyer et al. 2010) into two 16-bit snorms.
uint encodeNormal(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  vec2 e = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return packSnorm2x16(e);
}
vec3 decodeNormal(uint code) {
  vec2 e = unpackSnorm2x16(code);
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return normalize(n);
}
