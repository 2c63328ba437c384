// One triangle covering the viewport; each fragment is one particle texel (Kolb et al. 2004
// §3.3.2: "the shader is executed for each pixel of the render target by rendering a
// screen-sized quad").
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
