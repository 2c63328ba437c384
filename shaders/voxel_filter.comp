// Surface smoothing (Zirr & Dachsbacher 2015 §3.4, §4.6): one iteration of a 3x3 binomial kernel
// on the reciprocal depth of every surface point, its neighbours found through the surface links
// (diagonals by two steps). A point takes part in iterations while u_iteration is below its own
// count, from u_filter_radius over its pixel's width at its depth (Bagar et al. 2010): the
// filter's world-space radius is about constant.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 4) readonly buffer Meta { uvec4 meta[]; };
layout(std430, binding = 6) readonly buffer DepthsIn { vec2 depths_in[]; };
layout(std430, binding = 7) writeonly buffer DepthsOut { vec2 depths_out[]; };
layout(std430, binding = 8) readonly buffer DepthsRaw { vec2 depths_raw[]; };
uniform int u_iteration;
uniform int u_max_iterations;
uniform float u_filter_radius;  // metres

float depthAt(ivec2 pixel, int ref) {
  return depths_in[uint(pixel.y * u_size.x + pixel.x) * uint(u_max_spans) + uint(ref >> 1)][ref & 1];
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (pixel.x >= u_size.x || pixel.y >= u_size.y) return;
  uint index = uint(pixel.y * u_size.x + pixel.x);
  uint count = meta[index].x;
  uint base = index * uint(u_max_spans);
  float pixel_angle = 2.0 / (u_proj.y * float(u_size.y));  // pixel width over depth
  for (uint s = 0u; s < count; ++s) {
    vec2 result = depths_in[base + s];
    for (int side = 0; side < 2; ++side) {
      int ref = int(s) * 2 + side;
      float own = depths_raw[base + s][side];
      // n rounds of the binomial kernel spread about sqrt(n / 2) px: n = 2 (radius / pixel)^2.
      float reach = min(u_filter_radius / (own * pixel_angle), 64.0);
      int iterations = min(int(2.0 * reach * reach), u_max_iterations);
      if (u_iteration >= iterations) continue;
      float sum = 4.0 / depthAt(pixel, ref);
      for (int d = 0; d < 4; ++d) {
        ivec2 p = pixel;
        int r = ref;
        follow(p, r, d);
        sum += 2.0 / depthAt(p, r);
        // diagonals: x steps then y steps
        if (d < 2) {
          for (int e = 2; e < 4; ++e) {
            ivec2 p2 = p;
            int r2 = r;
            follow(p2, r2, e);
            sum += 1.0 / depthAt(p2, r2);
          }
        }
      }
      result[side] = 16.0 / sum;
    }
    depths_out[base + s] = result;
  }
}
