// Copies the opaque scene colour into the target before the water is blended over it.
uniform sampler2D u_colour;
in vec2 v_uv;
layout(location = 0) out vec4 out_colour;
void main() { out_colour = vec4(texture(u_colour, v_uv).rgb, 1.0); }
