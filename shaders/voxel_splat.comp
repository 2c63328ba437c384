// Splat (Zirr & Dachsbacher 2015 §3.1 a, §4.1): every particle sphere marks the voxels its
// pixels' centre rays cross inside it, in the current tile's bit grid, with atomicOr per word. One
// invocation per particle walks the sphere's screen bounds in the tile sequentially (the paper's
// splatting kernel for small particles, §4.1), so llvmpipe needs no geometry shader.
// Anisotropic kernels (Yu & Turk 2013, u_ellipsoids): particle j is the ellipsoid
// { x : |g_j (x − x̄_j)| <= u_radius }; its screen bounds and depth cull are those of its bounding
// sphere (radius u_radius · max axis), and each pixel ray is tested against the ellipsoid as the
// sphere test of the ray and centre mapped by M = R g Rᵀ (fluid/surface/voxel_reference.hpp).
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Particles { vec4 centres[]; };
layout(std430, binding = 2) buffer Bits { uint bits[]; };
layout(std430, binding = 9) readonly buffer Selection { uint selected[]; };  // u_use_selection: indices
// §4.3: full inner cells left out of the particles come back as one sphere each (centre, radius).
layout(std430, binding = 10) readonly buffer InnerCells { vec4 inner_cells[]; };
uniform uint u_inner_count;
uniform mat4 u_world_to_view;
uniform uint u_count;
uniform uint u_row;  // invocations per dispatch row (the grid is 2D past 65535 groups)
uniform bool u_use_selection;
uniform float u_radius;
uniform ivec4 u_tile;  // x, y, width, height
// u_ellipsoids: per particle g's three columns (particle_pass.hpp ShapeBuffer; the first's w is the
// largest semi-axis factor). Inner-cell spheres stay spheres.
layout(std430, binding = 11) readonly buffer Shapes { vec4 shapes[]; };
uniform bool u_ellipsoids;

// voxelKernelMatrix: M = I + R (g − I) Rᵀ, R = the view's rotation, in the reference's order
// (a sphere's g = I gives exactly I).
mat3 kernelMatrix(mat4 v, mat3 g) {
  mat3 t, m;  // t[j][k] = T(k, j), T = (g − I) Rᵀ
  for (int k = 0; k < 3; ++k) {
    precise float d0 = g[0][k] - (k == 0 ? 1.0 : 0.0);
    precise float d1 = g[1][k] - (k == 1 ? 1.0 : 0.0);
    precise float d2 = g[2][k] - (k == 2 ? 1.0 : 0.0);
    for (int j = 0; j < 3; ++j) {
      precise float s = (d0 * v[0][j] + d1 * v[1][j]) + d2 * v[2][j];
      t[j][k] = s;
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      precise float e = (v[0][i] * t[j][0] + v[1][i] * t[j][1]) + v[2][i] * t[j][2];
      precise float s = (i == j ? 1.0 : 0.0) + e;
      m[j][i] = s;
    }
  }
  return m;
}

vec3 mapped(mat3 m, vec3 p) {
  precise float x = (m[0][0] * p.x + m[1][0] * p.y) + m[2][0] * p.z;
  precise float y = (m[0][1] * p.x + m[1][1] * p.y) + m[2][1] * p.z;
  precise float z = (m[0][2] * p.x + m[1][2] * p.y) + m[2][2] * p.z;
  return vec3(x, y, z);
}

int pixelOf(float ndc, int size) { return int(floor(clamp((ndc + 1.0) * 0.5 * float(size) - 0.5, -1e6, 1e6))); }

void main() {
  uint i = gl_GlobalInvocationID.y * u_row + gl_GlobalInvocationID.x;
  if (i >= u_count + u_inner_count) return;
  uint j = i < u_count ? (u_use_selection ? selected[i] : i) : 0u;
  vec4 sphere = i < u_count ? vec4(centres[j].xyz, u_radius) : inner_cells[i - u_count];
  vec3 p = sphere.xyz;
  mat4 v = u_world_to_view;
  precise float cx = ((v[0][0] * p.x + v[1][0] * p.y) + v[2][0] * p.z) + v[3][0];
  precise float cy = ((v[0][1] * p.x + v[1][1] * p.y) + v[2][1] * p.z) + v[3][1];
  precise float cz = ((v[0][2] * p.x + v[1][2] * p.y) + v[2][2] * p.z) + v[3][2];
  vec3 c = vec3(cx, cy, cz);
  float r = sphere.w, d = -c.z;
  bool ellipsoid = u_ellipsoids && i < u_count;
  mat3 m = mat3(1.0);
  vec3 mc = c;  // the centre mapped by m
  if (ellipsoid) {
    vec4 g0 = shapes[3u * j];
    m = kernelMatrix(v, mat3(g0.xyz, shapes[3u * j + 1u].xyz, shapes[3u * j + 2u].xyz));
    mc = mapped(m, c);
    r = sphere.w * g0.w;  // the bounding sphere, for the culls and the screen bounds
  }
  if (d + r < layer_depth[0] || d - r >= layer_depth[u_layer_count]) return;
  ivec2 lo = u_tile.xy, hi = u_tile.xy + u_tile.zw - 1;
  if (d - r > 1e-4) {
    // Screen bounds: x/d over the sphere's view box is extreme at its corners; one pixel of margin,
    // the per-pixel ray test decides.
    float zn = d - r, zf = d + r;
    vec2 a0 = min((c.xy - r) / zn, (c.xy - r) / zf), a1 = max((c.xy + r) / zn, (c.xy + r) / zf);
    vec2 n0 = a0 * u_proj.xy - u_proj.zw, n1 = a1 * u_proj.xy - u_proj.zw;
    lo = max(lo, ivec2(pixelOf(n0.x, u_size.x), pixelOf(n0.y, u_size.y)) - 1);
    hi = min(hi, ivec2(pixelOf(n1.x, u_size.x), pixelOf(n1.y, u_size.y)) + 2);
  }
  for (int y = lo.y; y <= hi.y; ++y) {
    for (int x = lo.x; x <= hi.x; ++x) {
      int first, last;
      vec3 ray = columnRay(ivec2(x, y));
      if (ellipsoid ? !sphereLayers(mapped(m, ray), mc, sphere.w, first, last)
                    : !sphereLayers(ray, c, r, first, last))
        continue;
      int base = ((y - u_tile.y) * u_tile.z + (x - u_tile.x)) * u_words;
      for (int w = first >> 5; w <= (last >> 5); ++w) {
        int b0 = max(first - 32 * w, 0), b1 = min(last - 32 * w, 31);
        uint upper = b1 == 31 ? 0xffffffffu : ((1u << uint(b1 + 1)) - 1u);
        atomicOr(bits[base + w], upper & ~((1u << uint(b0)) - 1u));
      }
    }
  }
}
