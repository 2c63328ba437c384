#version 330 core
// One colour over the whole frame, blended by its alpha (FrameBatches::screen_tint).
uniform vec4 u_tint;
out vec4 frag_colour;

void main() { frag_colour = u_tint; }
