#version 330 core
// Gradient sky with a sun disc and glow; below the horizon fades to a hazy ground colour.
in vec3 v_ray;
uniform vec3 u_sun_direction;
uniform vec3 u_sun_colour;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_ground_ambient;
out vec4 out_colour;

vec3 toneMap(vec3 c) { return pow(c / (1.0 + c), vec3(1.0 / 2.2)); }

void main() {
  vec3 dir = normalize(v_ray);
  float up = dir.y;
  vec3 sky = mix(u_sky_horizon, u_sky_zenith, pow(clamp(up, 0.0, 1.0), 0.45));
  vec3 below = mix(u_sky_horizon, u_ground_ambient * 1.5, clamp(-up * 4.0, 0.0, 1.0));
  vec3 colour = up >= 0.0 ? sky : below;
  float sun_cos = max(dot(dir, normalize(u_sun_direction)), 0.0);
  colour += u_sun_colour * (pow(sun_cos, 900.0) * 6.0 + pow(sun_cos, 12.0) * 0.18);
  out_colour = vec4(toneMap(colour), 1.0);
}
