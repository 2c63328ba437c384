in vec3 v_world;
layout(location = 0) out vec4 out_colour;
void main() {
  // Vertical stripes (along z on the wall, x + z on the floor) make a sideways shift by
  // refraction visible; checks on the floor.
  float stripe = step(0.5, fract((v_world.z + (v_world.y < 0.001 ? v_world.x : 0.0)) * 2.5));
  float check = step(0.5, fract(v_world.x * 2.5)) * 0.15 * step(v_world.y, 0.001);
  vec3 a = vec3(0.9, 0.85, 0.75), b = vec3(0.2, 0.25, 0.35);
  out_colour = vec4(mix(b, a, stripe) - check, 1.0);
}
