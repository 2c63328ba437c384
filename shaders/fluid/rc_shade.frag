// Metaball ray casting, shading (Szécsi & Illés 2012 §5): the hits of rc_cast.comp shaded with
// the mesh's water look (water_shade.glsl), blended over the opaque scene.
uniform sampler2D u_hits;       // outward normal, hit distance along the ray (< 0: none)
uniform sampler2D u_thickness;  // metres
layout(location = 0) out vec4 out_colour;

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  vec4 hit = texelFetch(u_hits, pixel, 0);
  if (hit.w < 0.0) discard;
  vec3 world = u_eye + hit.w * pixelRay(gl_FragCoord.xy);
  float surface = -(u_view * vec4(world, 1.0)).z;
  out_colour = shadeWater(gl_FragCoord.xy / u_viewport, world, hit.xyz, surface, texelFetch(u_thickness, pixel, 0).r);
}
