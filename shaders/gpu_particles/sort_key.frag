// §3.3.3: "the distance in this texture is updated after the position simulation". The
// permutation is kept (frame-to-frame coherence); only the keys are refreshed. Keys sort
// ascending: −distance puts the farthest first (back-to-front); dead particles go last.
uniform sampler2D u_pairs;  // (key, particle index)
uniform sampler2D u_state0;
uniform sampler2D u_attributes;
uniform vec3 u_eye;
uniform float u_time;
uniform int u_width;

layout(location = 0) out vec4 out_pair;

void main() {
  vec2 pair = texelFetch(u_pairs, ivec2(gl_FragCoord.xy), 0).xy;
  int index = int(pair.y);
  ivec2 texel = ivec2(index % u_width, index / u_width);
  vec4 p = texelFetch(u_state0, texel, 0);
  bool alive = p.w != 0.0 && u_time < texelFetch(u_attributes, texel, 0).y;
  out_pair = vec4(alive ? -distance(p.xyz, u_eye) : 3.0e38, pair.y, 0.0, 0.0);
}
