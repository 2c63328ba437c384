// §3.3.4 point sprites; positions fetched from the state texture in the vertex shader (vertex
// texture fetch), in the order of the sort texture. Size, colour and opacity follow the type's
// key-frames over normalised age (§3.2).
uniform sampler2D u_pairs;
uniform sampler2D u_state0;
uniform sampler2D u_attributes;
uniform sampler2D u_types;  // row 2t: colours, row 2t+1: sizes; one column per key-frame
uniform mat4 u_view_projection;
uniform float u_time;
uniform float u_point_scale;  // projection[1][1] · viewport height / 2
uniform int u_width;
uniform sampler2D u_state1;     // Euler: velocity xyz, diffuse class w (update.frag)
uniform int u_type_diffuse[16];
uniform ivec3 u_class_types;    // key-frame rows of spray, foam, bubble
uniform int u_verlet;

out vec4 v_colour;
flat out float v_angle;
flat out float v_shape;  // 0 droplet (2:1, rotating), 1 flat fleck (2:1, lying), 2 round dot

float hash(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return float(x) / 4294967296.0;
}

void main() {
  ivec2 pair_texel = ivec2(gl_VertexID % textureSize(u_pairs, 0).x, gl_VertexID / textureSize(u_pairs, 0).x);
  int index = int(texelFetch(u_pairs, pair_texel, 0).y);
  ivec2 texel = ivec2(index % u_width, index / u_width);
  vec4 p = texelFetch(u_state0, texel, 0);
  vec4 attributes = texelFetch(u_attributes, texel, 0);
  if (p.w == 0.0 || u_time >= attributes.y) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume
    gl_PointSize = 1.0;
    v_colour = vec4(0.0);
    v_angle = 0.0;
    v_shape = 0.0;
    return;
  }
  int type = int(attributes.z);
  v_shape = 0.0;
  if (u_verlet == 0 && u_type_diffuse[clamp(type, 0, 15)] != 0) {
    // Ihmsen et al. 2012 §4.2: drawn as its class is now: foam a white fleck lying on the water,
    // a bubble a small pale dot.
    int diffuse_class = clamp(int(texelFetch(u_state1, texel, 0).w + 0.5), 0, 2);
    type = u_class_types[diffuse_class];
    v_shape = float(diffuse_class);
  }
  float age = u_time - attributes.x;
  float t = clamp(age / max(attributes.y - attributes.x, 1e-6), 0.0, 1.0) * 3.0;
  int k0 = min(int(t), 2);
  float f = t - float(k0);
  int row = 2 * type;
  vec4 colour = mix(texelFetch(u_types, ivec2(k0, row), 0), texelFetch(u_types, ivec2(k0 + 1, row), 0), f);
  float size = mix(texelFetch(u_types, ivec2(k0, row + 1), 0).x, texelFetch(u_types, ivec2(k0 + 1, row + 1), 0).x, f);
  gl_Position = u_view_projection * vec4(p.xyz, 1.0);
  gl_PointSize = clamp(size * u_point_scale / max(gl_Position.w, 1e-4), 1.0, 255.0);
  v_colour = vec4(colour.rgb * colour.a, colour.a);  // premultiplied
  v_angle = v_shape == 0.0 ? hash(uint(index)) * 6.2831853 + attributes.w * age : 0.0;
}
