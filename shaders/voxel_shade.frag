// Rendering (Zirr & Dachsbacher 2015 §3.5): the first stored span in front of the scene gives the
// surface (its filtered entry depth and normal); the water along the way is either the sum of the
// pixel's span lengths clipped to the scene (translucency, §3.5 first paragraph, with the hidden
// empty depth of an overflowing last span taken out) or, with u_refraction_rays, the length a
// refracted ray spends inside spans while it marches across the columns in screen space
// (Listing 2; each column's spans are intersected with the depth interval the ray crosses in it).
// Shaded with the other methods' water look (shaders/fluid/water_shade.glsl) and blended over
// the scene. Needs shading.glsl, depth.glsl, ray.glsl, water_shade.glsl, voxel_common.glsl.
layout(std430, binding = 4) readonly buffer Meta { uvec4 meta[]; };
layout(std430, binding = 6) readonly buffer Depths { vec2 depths[]; };
layout(std430, binding = 7) readonly buffer Normals { uvec2 normals[]; };
uniform bool u_refraction_rays;
uniform int u_max_ray_steps;
uniform float u_max_ray_length;  // metres
layout(location = 0) out vec4 out_colour;

float sceneDepthAt(ivec2 p) { return linearDepth(texelFetch(u_scene_depth, p, 0).r); }

// Water length along the view-space ray origin + t · dir, t in [0, length]: marched column by
// column (one step per pixel the ray's projection crosses), each step's depth interval
// intersected with that column's spans; stops at the scene and at the screen's edge.
float refractedThickness(vec3 origin, vec3 dir, float len) {
  vec3 far_point = origin + dir * len;
  vec2 a = (origin.xy / -origin.z * u_proj.xy - u_proj.zw + 1.0) * 0.5 * vec2(u_size);
  vec2 b = (far_point.xy / max(-far_point.z, 1e-4) * u_proj.xy - u_proj.zw + 1.0) * 0.5 * vec2(u_size);
  int steps = clamp(int(ceil(length(b - a))), 1, u_max_ray_steps);
  float dt = len / float(steps), inside = 0.0;
  for (int k = 0; k < steps; ++k) {
    vec3 p0 = origin + dir * (dt * float(k)), p1 = p0 + dir * dt;
    vec3 mid = 0.5 * (p0 + p1);
    if (-mid.z <= 1e-4) break;
    ivec2 pixel = ivec2(floor((mid.xy / -mid.z * u_proj.xy - u_proj.zw + 1.0) * 0.5 * vec2(u_size)));
    if (pixel.x < 0 || pixel.y < 0 || pixel.x >= u_size.x || pixel.y >= u_size.y) break;
    float z0 = min(-p0.z, -p1.z), z1 = max(-p0.z, -p1.z);
    float scene = sceneDepthAt(pixel);
    if (z0 >= scene) break;
    z1 = min(z1, scene);
    uint index = uint(pixel.y * u_size.x + pixel.x);
    uint count = meta[index].x;
    float covered = 0.0;
    for (uint s = 0u; s < count; ++s) {
      vec2 d = depths[index * uint(u_max_spans) + s];
      covered += max(0.0, min(d.y, z1) - max(d.x, z0));
    }
    float span = max(-p1.z + p0.z, 0.0) + max(-p0.z + p1.z, 0.0);
    // A step nearly parallel to the image plane: inside if its middle is in a span.
    inside += span > 1e-6 ? dt * min(covered / span, 1.0) : (covered > 0.0 ? dt : 0.0);
  }
  return inside;
}

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  uint index = uint(pixel.y * u_size.x + pixel.x);
  uvec4 m = meta[index];
  if (m.x == 0u) discard;
  float scene = sceneDepthAt(pixel);
  uint base = index * uint(u_max_spans);
  vec2 first = depths[base];
  if (first.x >= scene) discard;
  vec3 ray = columnRay(pixel);
  float ray_length = length(ray);
  float along = 0.0;
  for (uint s = 0u; s < m.x; ++s) {
    vec2 d = depths[base + s];
    along += max(0.0, min(d.y, scene) - d.x);
  }
  if (m.y > m.x && depths[base + m.x - 1u].y <= scene) along -= uintBitsToFloat(m.z);
  float thickness = max(along, 0.0) * ray_length;
  vec3 n = decodeNormal(normals[base].x);
  if (u_refraction_rays) {
    vec3 origin = first.x * ray;
    vec3 n_view = mat3(u_view) * n;
    vec3 dir = refract(normalize(ray), n_view, 1.0 / u_ior);
    if (dot(dir, dir) > 0.0) thickness = refractedThickness(origin, dir, min(u_max_ray_length, 1.5 * thickness + 0.05));
  }
  vec3 world = u_eye + first.x * ray_length * pixelRay(gl_FragCoord.xy);
  out_colour = shadeWater(gl_FragCoord.xy / u_viewport, world, n, first.x, thickness);
}
