// Point sprites are axis-aligned; the 2D rotation is applied to the texture coordinates here
// (§3.3.4). The sprite is an elongated soft droplet so the rotation shows.
in vec4 v_colour;
flat in float v_angle;
flat in float v_shape;  // sprite.vert: 0 droplet, 1 flat fleck (foam), 2 round dot (bubble)

layout(location = 0) out vec4 out_colour;

void main() {
  vec2 c = gl_PointCoord * 2.0 - 1.0;
  float cs = cos(v_angle), sn = sin(v_angle);
  vec2 r = vec2(cs * c.x + sn * c.y, -sn * c.x + cs * c.y);
  float d2 = v_shape == 2.0 ? dot(r, r) : r.x * r.x + 4.0 * r.y * r.y;  // round, or a 2:1 ellipse
  if (d2 > 1.0) discard;
  out_colour = v_colour * (1.0 - d2);
}
