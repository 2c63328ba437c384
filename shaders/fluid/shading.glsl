// Shared lighting for the fluid surface: sky for reflections, Schlick's Fresnel, Blinn-Phong.
uniform vec3 u_eye;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_light;  // unit, towards the light
uniform float u_shininess;
uniform float u_ior;

vec3 sky(vec3 direction) {
  float up = clamp(direction.y, -1.0, 1.0);
  return up >= 0.0 ? mix(u_sky_horizon, u_sky_zenith, sqrt(up)) : u_sky_horizon * (0.6 + 0.4 * (1.0 + up));
}

// Schlick: F = F0 + (1 − F0)(1 − cos θ)^5 with F0 from the index of refraction.
float fresnel(float cos_theta) {
  float f0 = (u_ior - 1.0) / (u_ior + 1.0);
  f0 *= f0;
  return f0 + (1.0 - f0) * pow(1.0 - clamp(cos_theta, 0.0, 1.0), 5.0);
}

float specular(vec3 n, vec3 to_eye) {
  vec3 h = normalize(u_light + to_eye);
  return pow(max(dot(n, h), 0.0), u_shininess) * step(0.0, dot(n, u_light));
}

// Normal facing the viewer: back faces are seen from inside the fluid or through it.
vec3 facingNormal(vec3 n) { return gl_FrontFacing ? normalize(n) : -normalize(n); }
