// Translucent goo (the blob monster, issue 19): blended over the scene in the order the extractor
// emitted (back-to-front, marching slices paper §5), like the water, but with a subsurface look
// in place of refraction:
//  - d, the thickness through the body along the pixel's ray, from the same extent pass as the
//    water (water_extent.frag); a back face with an entry in front of it adds nothing (the front
//    face already accounts for the whole body), unless the eye is inside the goo;
//  - coverage 1 - exp(-density d) (Beer-Lambert on the goo's extinction): thin tentacle tips and
//    edges let the scene through, the core is nearly opaque; never below u_goo_min_coverage;
//  - wrapped diffuse (light reaches past the terminator, as light scattered inside the body
//    does) plus a glow where the goo is thin, strongest looking toward the light (back-lit tips);
//  - albedo: the goo colour, or the skin texture at the mesh's (u, v) weighted by the vertex's
//    tentacle share (fluid/blob/tentacle_uv.hpp): tentacles textured, the body between plain.
uniform sampler2D u_scene_depth;
uniform sampler2D u_water_extent;
uniform sampler2D u_goo_texture;
uniform bool u_goo_textured;
uniform vec2 u_viewport;
uniform vec3 u_goo_colour;
uniform float u_goo_density;
uniform float u_goo_min_coverage;

in vec3 v_world;
in vec3 v_normal;
in vec4 v_attributes;  // (u, v, skin weight, u shifted by half a turn)
layout(location = 0) out vec4 out_colour;

// u goes once around the tentacle, so 0 and 1 meet: a triangle spanning that seam interpolates
// through the whole texture. Of u and its half-turn-shifted copy (seamed on the opposite side),
// take the one that changes less across the pixel: it is the continuous one here (Tarini 2012,
// "Cylindrical and toroidal parameterizations without vertex seams").
float seamlessU(float u, float u_shifted) { return fwidth(u) <= fwidth(u_shifted) + 1e-6 ? u : u_shifted; }

void main() {
  vec2 uv = gl_FragCoord.xy / u_viewport;
  float surface = linearDepth(gl_FragCoord.z);
  if (linearDepth(texture(u_scene_depth, uv).r) < surface) discard;  // behind an opaque object
  vec2 extent = texture(u_water_extent, uv).rg;                        // (-nearest entry, farthest surface)
  float thickness = gl_FrontFacing ? max(extent.y - surface, 0.0)
                                   : (surface < -extent.x ? surface - u_near_far.x : -1.0);
  if (thickness < 0.0) discard;
  vec3 n = facingNormal(v_normal);
  vec3 to_eye = normalize(u_eye - v_world);
  vec3 albedo = u_goo_colour;
  if (u_goo_textured) {
    vec2 st = vec2(seamlessU(v_attributes.x, v_attributes.w), v_attributes.y);
    // The texture is sRGB (decoded on fetch); the scene target holds display-encoded colour.
    vec3 skin = pow(texture(u_goo_texture, st).rgb, vec3(1.0 / 2.2));
    albedo = mix(albedo, skin, smoothstep(0.15, 0.6, v_attributes.z));
  }
  float thin = exp(-u_goo_density * thickness);  // 1 at edges and tips, toward 0 through the core
  float wrap = 0.5;
  float diffuse = max((dot(n, u_light) + wrap) / (1.0 + wrap), 0.0);
  float glow = thin * (0.3 + 0.7 * pow(max(dot(-to_eye, u_light), 0.0), 4.0));
  vec3 colour = albedo * (0.25 + 0.75 * diffuse + 0.6 * glow);
  float f = fresnel(dot(n, to_eye));
  colour = mix(colour, sky(reflect(-to_eye, n)), 0.5 * f) + vec3(0.6 * specular(n, to_eye)) +
           flashLight(v_world, n, to_eye);
  float coverage = max(1.0 - thin, u_goo_min_coverage);
  out_colour = vec4(colour, mix(coverage, 1.0, f));
}
