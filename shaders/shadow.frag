#version 330 core
// Depth only; the colour output is unused.
out vec4 out_colour;

void main() { out_colour = vec4(1.0); }
