// Pass before the blended water: per pixel, the nearest front-facing and the farthest water
// surface in front of the opaque scene, as view distances in metres (RG32F target cleared to
// (-1e30, 0), blend equation MAX: r = max(-distance of front faces), g = max(distance)).
// The water shader takes each fragment's thickness from them, so water seen against the sky or
// a distant wall absorbs through itself only, and a camera inside the water sees it tinted.
uniform sampler2D u_scene_depth;
uniform vec2 u_viewport;
layout(location = 0) out vec4 out_extent;

void main() {
  // Same projection and resolution as the opaque pass: raw window depths compare directly.
  if (gl_FragCoord.z >= texture(u_scene_depth, gl_FragCoord.xy / u_viewport).r) discard;
  float distance = linearDepth(gl_FragCoord.z);
  // Outward winding (fluid/surface's tables): front faces are where a ray enters the water.
  out_extent = vec4(gl_FrontFacing ? -distance : -1e30, distance, 0.0, 0.0);
}
