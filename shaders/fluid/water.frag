// Transparent water over the opaque scene (scene colour + depth from the opaque pass):
//  - thickness d from the water's own extent along the pixel's ray (u_water_extent, written by
//    water_extent.frag: nearest entry and farthest surface in front of the opaque scene): an
//    entering (front) face absorbs over the distance to the farthest surface; an exit (back)
//    face absorbs nothing more, unless no entry lies in front of it (the eye is inside the
//    water), then over the distance from the eye. Water in front of the sky or a distant wall
//    thus absorbs through itself only. Separate bodies of water along one ray also count the air
//    between them (one layer of extent, no depth peeling);
//  - refraction: the scene-colour lookup is offset along the refracted view ray, scaled by d
//    (no shift where the water is thin);
//  - Beer–Lambert absorption exp(−σ·d);
//  - Fresnel-weighted sky reflection and a specular highlight.
uniform sampler2D u_scene_colour;
uniform sampler2D u_scene_depth;
uniform sampler2D u_water_extent;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec2 u_viewport;
uniform vec3 u_absorption;
uniform float u_refraction;
uniform float u_opacity;

in vec3 v_world;
in vec3 v_normal;
layout(location = 0) out vec4 out_colour;

void main() {
  vec2 uv = gl_FragCoord.xy / u_viewport;
  float surface = linearDepth(gl_FragCoord.z);
  float scene = linearDepth(texture(u_scene_depth, uv).r);
  if (scene < surface) discard;  // behind an opaque object
  vec3 n = facingNormal(v_normal);
  vec3 to_eye = normalize(u_eye - v_world);
  vec2 extent = texture(u_water_extent, uv).rg;  // (-nearest entry, farthest surface), metres
  float thickness = gl_FrontFacing ? max(extent.y - surface, 0.0)
                                   : (surface < -extent.x ? surface - u_near_far.x : 0.0);
  // Refracted ray in view space; its screen-space deviation from the straight ray shifts the
  // lookup, more through thick water (clamped at 1 m so the shift stays bounded).
  vec3 incident = mat3(u_view) * (-to_eye);
  vec3 refracted = refract(incident, mat3(u_view) * n, 1.0 / u_ior);
  vec2 shift = (refracted.xy - incident.xy) * u_refraction * min(thickness, 1.0);
  vec2 uv_refracted = clamp(uv + shift, vec2(0.0), vec2(1.0));
  // Do not pull in colour from objects in front of the water.
  if (linearDepth(texture(u_scene_depth, uv_refracted).r) < surface) uv_refracted = uv;
  vec3 behind = texture(u_scene_colour, uv_refracted).rgb;
  vec3 transmitted = behind * exp(-u_absorption * thickness);
  float f = fresnel(dot(n, to_eye));
  vec3 colour = mix(transmitted, sky(reflect(-to_eye, n)), f) + vec3(specular(n, to_eye)) +
                flashLight(v_world, n, to_eye);
  out_colour = vec4(colour, mix(u_opacity, 1.0, f));
}
