// Surface connection (Zirr & Dachsbacher 2015 §3.3, Listing 1): for each stored span and each of
// the four direct neighbours, the entry links to the frontmost overlapping neighbour span's entry
// and the exit to the backmost one's exit; where the neighbour span also overlaps this column's
// previous (next) span the entry (exit) links to that own exit (entry) instead, a bubble wall
// (Fig. 3b); without an overlapping neighbour entry and exit link to each other (Fig. 3c). One
// byte per direction (§4.5): +x, −x, +y, −y. Also writes the spans' view depths for the filter.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 3) readonly buffer Spans { uvec2 spans[]; };
layout(std430, binding = 4) readonly buffer Meta { uvec4 meta[]; };
layout(std430, binding = 5) writeonly buffer Links { uvec2 links[]; };  // entry links, exit links
layout(std430, binding = 6) writeonly buffer Depths { vec2 depths[]; };  // view depth of entry, exit

const ivec2 kDirection[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (pixel.x >= u_size.x || pixel.y >= u_size.y) return;
  uint index = uint(pixel.y * u_size.x + pixel.x);
  uint count = meta[index].x;
  uint base = index * uint(u_max_spans);
  for (uint s = 0u; s < count; ++s) {
    uvec2 cur = spans[base + s];
    depths[base + s] = vec2(layer_depth[cur.x], layer_depth[cur.y]);
    // Layer indices compare like the depths (exits exclusive): touching counts as overlapping.
    uint prev_exit = s > 0u ? spans[base + s - 1u].y : 0u;
    bool has_prev = s > 0u;
    uint next_entry = s + 1u < count ? spans[base + s + 1u].x : 0xffffffffu;
    uint entry_links = 0u, exit_links = 0u;
    for (int d = 0; d < 4; ++d) {
      uint entry_link = kOwnOther, exit_link = kOwnOther;
      ivec2 q = pixel + kDirection[d];
      if (q.x >= 0 && q.y >= 0 && q.x < u_size.x && q.y < u_size.y) {
        uint q_index = uint(q.y * u_size.x + q.x);
        uint q_count = meta[q_index].x, q_base = q_index * uint(u_max_spans);
        uint front = q_count;
        for (uint k = 0u; k < q_count; ++k) {
          if (spans[q_base + k].y >= cur.x) {
            front = k;
            break;
          }
        }
        if (front < q_count && spans[q_base + front].x <= cur.y) {
          entry_link = (!has_prev || spans[q_base + front].x > prev_exit) ? front : kOwnAdjacent;
          uint back = front;
          for (uint k = front + 1u; k < q_count; ++k) {
            if (spans[q_base + k].x <= cur.y) back = k;
          }
          exit_link = next_entry > spans[q_base + back].y ? back : kOwnAdjacent;
        }
      }
      entry_links |= entry_link << uint(8 * d);
      exit_links |= exit_link << uint(8 * d);
    }
    links[base + s] = uvec2(entry_links, exit_links);
  }
}
