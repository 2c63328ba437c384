#version 330 core
// Sun (Lambert + Blinn-Phong, shadowed by a 5-tap PCF shadow map) plus hemisphere ambient, exponential distance fog towards the
// horizon colour, Reinhard tone map and gamma 2.2. Textures are sRGB, so samples are linear.
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_light_clip;
uniform sampler2D u_albedo;
uniform sampler2DShadow u_shadow_map;
uniform float u_shadow_texel;  // 1 / shadow map size
uniform vec3 u_tint;
uniform float u_uv_scale;
uniform float u_specular;
uniform float u_shininess;
uniform vec3 u_eye;
uniform vec3 u_sun_direction;
uniform vec3 u_sun_colour;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_ground_ambient;
uniform float u_fog_density;
uniform vec3 u_flash_position;  // an explosion's flash (engine::Lighting), a point light
uniform vec3 u_flash_colour;    // zero: no flash
out vec4 out_colour;

vec3 toneMap(vec3 c) { return pow(c / (1.0 + c), vec3(1.0 / 2.2)); }

// Fraction of sunlight reaching this fragment: hardware 2x2 PCF at five offsets.
float sunVisibility(float n_dot_l) {
  vec3 p = v_light_clip.xyz / v_light_clip.w * 0.5 + 0.5;
  if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0 || p.z >= 1.0) return 1.0;
  // Slope-scaled bias against acne on surfaces grazing the light.
  float bias = u_shadow_texel * (1.5 + 3.0 * sqrt(1.0 - n_dot_l * n_dot_l) / max(n_dot_l, 0.2));
  float sum = texture(u_shadow_map, vec3(p.xy, p.z - bias));
  sum += texture(u_shadow_map, vec3(p.xy + vec2(1.5, 0.5) * u_shadow_texel, p.z - bias));
  sum += texture(u_shadow_map, vec3(p.xy + vec2(-1.5, -0.5) * u_shadow_texel, p.z - bias));
  sum += texture(u_shadow_map, vec3(p.xy + vec2(0.5, -1.5) * u_shadow_texel, p.z - bias));
  sum += texture(u_shadow_map, vec3(p.xy + vec2(-0.5, 1.5) * u_shadow_texel, p.z - bias));
  return sum * 0.2;
}

void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 albedo = texture(u_albedo, v_uv * u_uv_scale).rgb * u_tint;
  vec3 to_eye = u_eye - v_world;
  float distance = length(to_eye);
  vec3 v = to_eye / max(distance, 1e-4);
  float n_dot_l = max(dot(n, u_sun_direction), 0.0);
  float sun = n_dot_l > 0.0 ? sunVisibility(n_dot_l) : 0.0;
  vec3 ambient = mix(u_ground_ambient, u_sky_zenith * 0.9 + u_sky_horizon * 0.3, n.y * 0.5 + 0.5);
  vec3 h = normalize(v + u_sun_direction);
  float specular = u_specular * pow(max(dot(n, h), 0.0), u_shininess) * n_dot_l * sun;
  vec3 colour = albedo * (ambient * 0.85 + u_sun_colour * n_dot_l * sun * 0.8) + u_sun_colour * specular;
  vec3 to_flash = u_flash_position - v_world;
  float flash_d2 = max(dot(to_flash, to_flash), 1e-6);
  colour += albedo * u_flash_colour * max(dot(n, to_flash * inversesqrt(flash_d2)), 0.0) / (1.0 + flash_d2);
  float fog = 1.0 - exp(-distance * u_fog_density);
  colour = mix(colour, u_sky_horizon, fog);
  out_colour = vec4(toneMap(colour), 1.0);
}
