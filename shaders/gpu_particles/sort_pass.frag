// One pass of Batcher's odd-even merge sort (§3.3.3, [Bat68]): all comparators of stage (p, k)
// run in parallel, each fragment keeping the min (lower element) or max (upper element) of its
// pair. The network for n = 2^m has ½m² + ½m stages; any stage only swaps inverted pairs, so
// the number of inversions never grows.
//   comparators of (p, k): (a, a + k) with (a − k mod p) mod 2k < k, both in one 2p block.
uniform sampler2D u_pairs;
uniform int u_p;
uniform int u_k;
uniform int u_width;
uniform int u_count;

layout(location = 0) out vec4 out_pair;

bool less(vec2 a, vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  int x = texel.y * u_width + texel.x;
  vec2 self = texelFetch(u_pairs, texel, 0).xy;
  int r = x - (u_k % u_p);
  out_pair = vec4(self, 0.0, 0.0);
  if (r < 0) return;
  bool lower = (r % (2 * u_k)) < u_k;
  int partner = lower ? x + u_k : x - u_k;
  if (partner >= u_count || (x / (2 * u_p)) != (partner / (2 * u_p))) return;
  vec2 other = texelFetch(u_pairs, ivec2(partner % u_width, partner / u_width), 0).xy;
  bool other_less = less(other, self);
  if (lower ? other_less : !other_less) out_pair = vec4(other, 0.0, 0.0);
}
