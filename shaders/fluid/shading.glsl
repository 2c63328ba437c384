// Shared lighting for the fluid surface: sky for reflections, Schlick's Fresnel, Blinn-Phong.
uniform vec3 u_eye;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_light;  // unit, towards the light
uniform float u_shininess;
uniform float u_ior;
uniform vec3 u_flash_position;  // an explosion's flash (engine::Lighting), a point light
uniform vec3 u_flash_colour;    // zero: no flash

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

// An explosion's flash on the fluid: the point light's highlight on the surface (Blinn-Phong at
// the surface's shininess) and a glow through it, both falling off as 1 / (1 + d^2) like the
// flash on the scene's meshes (mesh.frag), so water near a blast lights up with it.
vec3 flashLight(vec3 world, vec3 n, vec3 to_eye) {
  vec3 to_flash = u_flash_position - world;
  float d2 = max(dot(to_flash, to_flash), 1e-6);
  vec3 l = to_flash * inversesqrt(d2);
  float highlight = pow(max(dot(n, normalize(l + to_eye)), 0.0), u_shininess) * step(0.0, dot(n, l));
  return u_flash_colour * (0.25 * max(dot(n, l), 0.0) + highlight) / (1.0 + d2);
}

// Normal facing the viewer: back faces are seen from inside the fluid or through it.
vec3 facingNormal(vec3 n) { return gl_FrontFacing ? normalize(n) : -normalize(n); }
