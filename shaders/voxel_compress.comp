// Compression (Zirr & Dachsbacher 2015 §3.1 b, §3.2, §4.3–4.4): each pixel of the tile scans its
// column word by word (findLSB jumps to the next transition; words without one are skipped) and
// keeps runs of set voxels as spans [entry, exit) of layers. Runs whose empty gap along the ray is
// below u_min_gap are one span (gap bridging). Past u_max_spans the last span is extended and the
// empty depth inside it kept, for absorption (§3.1, Fig. 8). Same steps as
// compressColumnReference (fluid/surface/voxel_reference.cpp).
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 2) readonly buffer Bits { uint bits[]; };
layout(std430, binding = 3) buffer Spans { uvec2 spans[]; };     // per pixel u_max_spans, layers
layout(std430, binding = 4) writeonly buffer Meta { uvec4 meta[]; };  // stored, total, hidden gap bits, 0
uniform ivec4 u_tile;
uniform float u_min_gap;

uint g_base = 0u, g_stored = 0u, g_total = 0u;
float g_hidden = 0.0;
bool g_have = false;
uvec2 g_current = uvec2(0u), g_back = uvec2(0u);

void emitSpan(uvec2 s) {
  if (int(g_stored) < u_max_spans) {
    spans[g_base + g_stored] = s;
    g_back = s;
    ++g_stored;
  } else {
    precise float gap = layer_depth[s.x] - layer_depth[g_back.y];
    precise float hidden = g_hidden + gap;
    g_hidden = hidden;
    g_back.y = s.y;
    spans[g_base + uint(u_max_spans) - 1u] = g_back;
  }
  ++g_total;
}

void run(uint start, uint end, float ray_length) {
  if (g_have) {
    precise float gap = (layer_depth[start] - layer_depth[g_current.y]) * ray_length;
    if (gap < u_min_gap) {
      g_current.y = end;
      return;
    }
    emitSpan(g_current);
  }
  g_current = uvec2(start, end);
  g_have = true;
}

void main() {
  ivec2 local = ivec2(gl_GlobalInvocationID.xy);
  if (local.x >= u_tile.z || local.y >= u_tile.w) return;
  ivec2 pixel = u_tile.xy + local;
  uint pixel_index = uint(pixel.y * u_size.x + pixel.x);
  g_base = pixel_index * uint(u_max_spans);
  g_stored = 0u;
  g_total = 0u;
  g_hidden = 0.0;
  g_have = false;
  float ray_length = rayLength(columnRay(pixel));
  int column = (local.y * u_tile.z + local.x) * u_words;
  bool inside = false;
  uint start = 0u;
  for (int w = 0; w < u_words; ++w) {
    uint word = bits[column + w];
    if (word == (inside ? 0xffffffffu : 0u)) continue;
    int pos = 0;
    while (pos < 32) {
      uint rest = (inside ? ~word : word) & (0xffffffffu << uint(pos));
      if (rest == 0u) break;
      int b = findLSB(rest);
      uint layer = uint(32 * w + b);
      if (inside) run(start, layer, ray_length);
      else start = layer;
      inside = !inside;
      pos = b;
    }
  }
  if (inside) run(start, uint(u_layer_count), ray_length);
  if (g_have) emitSpan(g_current);
  meta[pixel_index] = uvec4(g_stored, g_total, floatBitsToUint(g_hidden), 0u);
}
