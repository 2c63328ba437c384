// Normals (Zirr & Dachsbacher 2015 §3.4, §4.5): a Sobel operator over the filtered surface, the
// 3x3 neighbours found through the links, on view-space points (depth · pixel ray); the cross of
// the two derivatives, turned towards the eye at entries and away at exits, stored world-space
// and octahedron-encoded in one word (Meyer et al. 2010). At a boundary the links fold onto the
// span's other side, so silhouettes get normals facing sideways.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 4) readonly buffer Meta { uvec4 meta[]; };
layout(std430, binding = 6) readonly buffer Depths { vec2 depths[]; };
layout(std430, binding = 7) writeonly buffer Normals { uvec2 normals[]; };
uniform mat4 u_world_to_view;

vec3 pointAt(ivec2 pixel, int ref) {
  return depths[uint(pixel.y * u_size.x + pixel.x) * uint(u_max_spans) + uint(ref >> 1)][ref & 1] * columnRay(pixel);
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (pixel.x >= u_size.x || pixel.y >= u_size.y) return;
  uint index = uint(pixel.y * u_size.x + pixel.x);
  uint count = meta[index].x;
  uint base = index * uint(u_max_spans);
  mat3 to_world = transpose(mat3(u_world_to_view));
  for (uint s = 0u; s < count; ++s) {
    uvec2 code = uvec2(0u);
    for (int side = 0; side < 2; ++side) {
      int ref = int(s) * 2 + side;
      vec3 centre = pointAt(pixel, ref);
      // Sobel: derivative along x = column +x minus column −x, each [1 2 1] over y; then along y.
      vec3 g[2];
      for (int axis = 0; axis < 2; ++axis) {
        int plus = axis == 0 ? 0 : 2, minus = plus + 1, across = axis == 0 ? 2 : 0;
        vec3 sum = vec3(0.0);
        for (int sgn = 0; sgn < 2; ++sgn) {
          ivec2 p = pixel;
          int r = ref;
          follow(p, r, sgn == 0 ? plus : minus);
          vec3 a = pointAt(p, r) * 2.0;
          ivec2 p2 = p;
          int r2 = r;
          follow(p2, r2, across);
          a += pointAt(p2, r2);
          p2 = p;
          r2 = r;
          follow(p2, r2, across + 1);
          a += pointAt(p2, r2);
          sum += sgn == 0 ? a : -a;
        }
        g[axis] = sum;
      }
      vec3 n = cross(g[0], g[1]);
      float len = length(n);
      vec3 towards_eye = -normalize(centre);
      n = len > 1e-12 ? n / len : towards_eye;
      if ((dot(n, towards_eye) < 0.0) == (side == 0)) n = -n;  // entries face the eye, exits away
      code[side] = encodeNormal(to_world * n);
    }
    normals[base + s] = code;
  }
}
