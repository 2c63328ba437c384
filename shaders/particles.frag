#version 330 core
// Each sprite quad is shaded as a small water droplet: sphere normal from the point coordinate,
// see the lighting terms below.
in float v_shade;
in vec3 v_world;
in vec2 v_corner;
uniform mat4 u_view;
uniform vec3 u_colour;
uniform vec3 u_sun_direction;
uniform vec3 u_sun_colour;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_eye;
uniform float u_fog_density;
out vec4 out_colour;

vec3 toneMap(vec3 c) { return pow(c / (1.0 + c), vec3(1.0 / 2.2)); }

void main() {
  vec2 p = v_corner;
  float r2 = dot(p, p);
  if (r2 > 1.0) discard;
  vec3 n_view = vec3(p, sqrt(1.0 - r2));
  // View-space normal back to world space (u_view is a rigid transform).
  vec3 n = transpose(mat3(u_view)) * n_view;
  vec3 base = mix(u_colour * 1.35, u_colour * 0.7, v_shade);
  float n_dot_l = max(dot(n, u_sun_direction), 0.0);
  vec3 v = normalize(u_eye - v_world);
  vec3 h = normalize(v + u_sun_direction);
  float highlight = pow(max(dot(n, h), 0.0), 60.0);
  float rim = pow(1.0 - n_view.z, 3.0);
  // Water lets light through: a sky-lit base, the sun's diffuse, forward scattering when the
  // droplet is between the eye and the sun, a sharp highlight and a sky-coloured rim.
  float scatter = pow(max(dot(-v, u_sun_direction), 0.0), 4.0);
  vec3 colour = base * (0.5 * u_sky_horizon + 0.3 * u_sky_zenith + 0.5 * u_sun_colour * n_dot_l +
                        0.35 * u_sun_colour * scatter) +
                u_sun_colour * highlight * 0.8 + u_sky_horizon * rim * 0.6;
  float fog = 1.0 - exp(-length(u_eye - v_world) * u_fog_density);
  colour = mix(colour, u_sky_horizon, fog);
  out_colour = vec4(toneMap(colour), 1.0);
}
