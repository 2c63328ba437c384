// Window depth (perspective, [0, 1]) back to view distance in metres, for the water passes.
uniform vec2 u_near_far;

float linearDepth(float d) {
  float n = u_near_far.x, f = u_near_far.y;
  return 2.0 * n * f / (f + n - (2.0 * d - 1.0) * (f - n));
}
