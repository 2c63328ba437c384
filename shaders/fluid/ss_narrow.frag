// Screen-space fluid, pass 3 with fluid_surface.ss_filter = narrow_range: one direction of the
// narrow-range filter (Truong & Yuksel 2018, "A Narrow-Range Filter for Screen-Space Fluid
// Rendering", I3D 2018, §4). A Gaussian over linear depth whose samples are judged against a
// narrow depth range around the pixel instead of weighted by a range Gaussian:
//   - a sample nearer than the range (z < z0 - threshold) is another surface in front: it is left
//     out, and so is its mirror sample on the other side, which keeps the kernel symmetric so a
//     plane stays a plane (a one-sided kernel would tilt it);
//   - a sample farther than the range (z > z0 + threshold: another layer of water behind) is
//     clamped to z0 + clamp, so it bends the surface back by at most the clamp instead of pulling
//     it towards the far layer;
//   - a sample inside the range extends it (range extension), so a sloped surface seen at a
//     grazing angle is followed along its slope instead of being cut off by the range.
// Each side of the pixel keeps its own range. Empty pixels (>= 1e20) stay empty; as samples they
// are left out with their mirror (the authors' code reads the cleared depth as out of range on
// the near side): clamping them would dimple the water around every pinhole between particles.
uniform sampler2D u_depth;
uniform vec2 u_direction;      // (1, 0) or (0, 1)
uniform float u_world_radius;  // filter half-width in metres
uniform float u_focal_px;      // projection[1][1] * height / 2: pixels per metre at depth 1
uniform float u_threshold;     // half-width of the depth range, metres
uniform float u_clamp;         // farther samples count as z0 + u_clamp, metres
layout(location = 0) out float out_depth;

// One sample against its side's range: returns the depth to use; `keep` false leaves it (and its
// mirror) out.
float judge(float z, float z_clamped, inout float near, inout float far, out bool keep) {
  keep = z >= near && z < 1e20;
  if (!keep) return z;
  if (z > far) return z_clamped;
  near = min(near, z - u_threshold);  // range extension
  far = max(far, z + u_threshold);
  return z;
}

void main() {
  ivec2 c = ivec2(gl_FragCoord.xy);
  float z0 = texelFetch(u_depth, c, 0).r;
  if (z0 >= 1e20) {
    out_depth = z0;
    return;
  }
  int radius = int(clamp(u_world_radius * u_focal_px / z0, 1.0, 24.0));
  float sigma = max(float(radius) * 0.5, 0.5);  // the bilateral pass's spatial Gaussian
  ivec2 size = textureSize(u_depth, 0);
  ivec2 step = ivec2(u_direction);
  float z_clamped = z0 + u_clamp;
  float near_a = z0 - u_threshold, far_a = z0 + u_threshold, near_b = near_a, far_b = far_a;
  float sum = z0, weights = 1.0;
  for (int i = 1; i <= radius; ++i) {
    float w = exp(-0.5 * float(i * i) / (sigma * sigma));
    bool keep_a, keep_b;
    float za = judge(texelFetch(u_depth, clamp(c + step * i, ivec2(0), size - 1), 0).r, z_clamped, near_a, far_a, keep_a);
    float zb = judge(texelFetch(u_depth, clamp(c - step * i, ivec2(0), size - 1), 0).r, z_clamped, near_b, far_b, keep_b);
    if (keep_a && keep_b) {
      sum += w * (za + zb);
      weights += 2.0 * w;
    }
  }
  out_depth = sum / weights;
}
