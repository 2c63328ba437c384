// Screen-space fluid, pass 3 (Janisz §3.1.2.1): one direction of the separable approximation of
// the bilateral filter over linear depth (Pham & van Vliet 2005). Spatial Gaussian whose width
// is a fixed world-space size projected at the pixel's depth; range Gaussian on depth
// differences keeps silhouettes against farther water. Empty pixels (>= 1e20) stay empty and
// do not contribute.
uniform sampler2D u_depth;
uniform vec2 u_direction;       // (1, 0) or (0, 1)
uniform float u_world_radius;   // filter half-width in metres
uniform float u_focal_px;       // projection[1][1] * height / 2: pixels per metre at depth 1
uniform float u_depth_falloff;  // range sigma, metres
layout(location = 0) out float out_depth;

void main() {
  ivec2 c = ivec2(gl_FragCoord.xy);
  float z0 = texelFetch(u_depth, c, 0).r;
  if (z0 >= 1e20) {
    out_depth = z0;
    return;
  }
  int radius = int(clamp(u_world_radius * u_focal_px / z0, 1.0, 24.0));
  float sigma = max(float(radius) * 0.5, 0.5);
  ivec2 size = textureSize(u_depth, 0);
  float sum = 0.0, weights = 0.0;
  for (int i = -radius; i <= radius; ++i) {
    ivec2 q = clamp(c + ivec2(u_direction) * i, ivec2(0), size - 1);
    float z = texelFetch(u_depth, q, 0).r;
    if (z >= 1e20) continue;
    float dz = (z - z0) / u_depth_falloff;
    float w = exp(-0.5 * float(i * i) / (sigma * sigma) - 0.5 * dz * dz);
    sum += w * z;
    weights += w;
  }
  out_depth = sum / weights;
}
