// Walking the connected surfaces (Zirr & Dachsbacher 2015 §3.4): a surface point is (pixel, ref)
// with ref = 2 · span + side (0 entry, 1 exit); following a link in a direction gives the
// neighbouring point on the same surface. Needs voxel_common.glsl.
layout(std430, binding = 5) readonly buffer Links { uvec2 links[]; };  // entry links, exit links
const ivec2 kStep[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));

void follow(inout ivec2 pixel, inout int ref, int direction) {
  uint index = uint(pixel.y * u_size.x + pixel.x) * uint(u_max_spans) + uint(ref >> 1);
  uint byte = (links[index][ref & 1] >> uint(8 * direction)) & 0xffu;
  if (byte == kOwnOther) {
    ref ^= 1;
  } else if (byte == kOwnAdjacent) {
    ref += (ref & 1) == 0 ? -1 : 1;  // entry → previous exit, exit → next entry
  } else {
    pixel += kStep[direction];
    ref = int(byte) * 2 + (ref & 1);
  }
}
