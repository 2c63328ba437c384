// The mesh's water look (water.frag) for one surface sample of the particle renderers, so the
// three methods' pictures compare: refraction offset scaled by the thickness d, Beer–Lambert
// exp(−σ·d), Schlick-Fresnel sky reflection and the Blinn-Phong highlight of shading.glsl.
// Needs shading.glsl and depth.glsl before it.
uniform sampler2D u_scene_colour;
uniform sampler2D u_scene_depth;
uniform mat4 u_view;
uniform vec3 u_absorption;
uniform float u_refraction;
uniform float u_opacity;

// uv: pixel in [0,1]^2; world: surface point; n: unit normal facing the eye; surface: its view
// depth (metres, as linearDepth); thickness: water along the ray (metres).
vec4 shadeWater(vec2 uv, vec3 world, vec3 n, float surface, float thickness) {
  vec3 to_eye = normalize(u_eye - world);
  vec3 incident = mat3(u_view) * (-to_eye);
  vec3 refracted = refract(incident, mat3(u_view) * n, 1.0 / u_ior);
  vec2 shift = (refracted.xy - incident.xy) * u_refraction * min(thickness, 1.0);
  vec2 uv_refracted = clamp(uv + shift, vec2(0.0), vec2(1.0));
  if (linearDepth(texture(u_scene_depth, uv_refracted).r) < surface) uv_refracted = uv;
  vec3 behind = texture(u_scene_colour, uv_refracted).rgb;
  vec3 transmitted = behind * exp(-u_absorption * thickness);
  float f = fresnel(dot(n, to_eye));
  vec3 colour = mix(transmitted, sky(reflect(-to_eye, n)), f) + vec3(specular(n, to_eye)) +
                flashLight(world, n, to_eye);
  return vec4(colour, mix(u_opacity, 1.0, f));
}
