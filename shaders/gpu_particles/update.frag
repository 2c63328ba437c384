// One simulation step per particle texel (Kolb et al. 2004 §3.3.2): forces, integration,
// the depth-map collision double check (collide.glsl), and the GPU side of death (§3.3.1).
// Euler:  state0 = position, state1 = velocity.
// Verlet: state0 = P_{i-1}, state1 = P_{i-2}; P_i = 2P_{i-1} − P_{i-2} + a·dt² (no velocity
//         texture). A collision reaction is written back as a new P_{i-1} = P_i − v'·dt, the
//         "position manipulation" the paper asks for.

uniform sampler2D u_state0;
uniform sampler2D u_state1;
uniform sampler2D u_attributes;  // birth time, death time, type, spin
uniform float u_time;            // time at the end of this step, s
uniform float u_dt;
uniform int u_verlet;
uniform vec3 u_gravity;
uniform vec3 u_wind;
uniform float u_type_gravity[16];  // per particle type: gravity scale (ParticleTypeDesc)
uniform float u_type_damping[16];  // per particle type: velocity damping, 1/s
uniform int u_attractor_count;
uniform vec4 u_attractors[4];    // xyz position, w strength
uniform float u_softening[4];
uniform float u_drag;            // 6πηr/m, 1/s
uniform sampler3D u_flow;
uniform vec3 u_flow_origin;
uniform vec3 u_flow_extent;

#ifdef BLASTS
uniform int u_blast_count;
uniform vec4 u_blasts[4];        // xyz centre, w specific impulse 1 m away (Pa s)
uniform vec2 u_blast_radii[4];   // core radius, reach (m)
uniform float u_blast_area_over_mass;  // pi r^2 / m, m^2/kg
uniform float u_blast_max_dv;          // m/s

// The blast law of fluid/core/blast.hpp (I = I1 / max(r, core)^2, smoothstep taper over the outer
// fifth of the reach, straight up at the centre), so sprites fly with the water and the crates.
vec3 blastVelocityChange(vec3 p) {
  vec3 dv = vec3(0.0);
  for (int k = 0; k < u_blast_count; ++k) {
    vec3 d = p - u_blasts[k].xyz;
    float distance = length(d);
    float reach = u_blast_radii[k].y;
    if (!(distance < reach)) continue;
    float r = max(distance, u_blast_radii[k].x);
    float taper_start = 0.8 * reach;
    float t = clamp((reach - distance) / (reach - taper_start), 0.0, 1.0);
    float taper = distance > taper_start ? t * t * (3.0 - 2.0 * t) : 1.0;
    float speed = min(u_blasts[k].w / (r * r) * taper * u_blast_area_over_mass, u_blast_max_dv);
    vec3 direction = distance > 1e-6 ? d / distance : vec3(0.0, 1.0, 0.0);
    dv += speed * direction;
  }
  return dv;
}
#endif

#ifdef DIFFUSE
// Diffuse sprites (Ihmsen et al. 2012 §4.2): the fluid grid holds per cell the sum of the fluid
// velocities (xyz) and the particle count (w); see engine::FluidGridDesc.
uniform sampler3D u_fluid;
uniform int u_fluid_on;
uniform vec3 u_fluid_origin;
uniform float u_fluid_cell;
uniform float u_neighbour_scale;  // (4/3 pi h^3) / cell^3: count per cell -> neighbours within h
uniform vec2 u_class_counts;      // spray below x, bubble above y
uniform float u_buoyancy;         // k_b
uniform float u_bubble_drag;      // k_d
uniform int u_type_diffuse[16];

// Trilinear between cell centres, zero outside the grid (no water there).
vec4 fluidSample(vec3 p) {
  ivec3 size = textureSize(u_fluid, 0);
  vec3 g = (p - u_fluid_origin) / u_fluid_cell - 0.5;
  if (any(lessThan(g, vec3(-0.5))) || any(greaterThan(g, vec3(size) - 0.5))) return vec4(0.0);
  g = clamp(g, vec3(0.0), vec3(size - 1));
  ivec3 i0 = ivec3(floor(g));
  vec3 f = g - vec3(i0);
  ivec3 i1 = min(i0 + 1, size - 1);
  vec4 c000 = texelFetch(u_fluid, ivec3(i0.x, i0.y, i0.z), 0);
  vec4 c100 = texelFetch(u_fluid, ivec3(i1.x, i0.y, i0.z), 0);
  vec4 c010 = texelFetch(u_fluid, ivec3(i0.x, i1.y, i0.z), 0);
  vec4 c110 = texelFetch(u_fluid, ivec3(i1.x, i1.y, i0.z), 0);
  vec4 c001 = texelFetch(u_fluid, ivec3(i0.x, i0.y, i1.z), 0);
  vec4 c101 = texelFetch(u_fluid, ivec3(i1.x, i0.y, i1.z), 0);
  vec4 c011 = texelFetch(u_fluid, ivec3(i0.x, i1.y, i1.z), 0);
  vec4 c111 = texelFetch(u_fluid, ivec3(i1.x, i1.y, i1.z), 0);
  vec4 x00 = mix(c000, c100, f.x), x10 = mix(c010, c110, f.x);
  vec4 x01 = mix(c001, c101, f.x), x11 = mix(c011, c111, f.x);
  return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}
#endif

layout(location = 0) out vec4 out_state0;
layout(location = 1) out vec4 out_state1;

// Trilinear flow velocity between cell centres, clamped at the border (texelFetch keeps the
// weights in full float precision, so the CPU reference can match).
vec3 flowVelocity(vec3 p) {
  ivec3 size = textureSize(u_flow, 0);
  vec3 g = (p - u_flow_origin) / u_flow_extent * vec3(size) - 0.5;
  g = clamp(g, vec3(0.0), vec3(size - 1));
  ivec3 i0 = ivec3(floor(g));
  vec3 f = g - vec3(i0);
  ivec3 i1 = min(i0 + 1, size - 1);
  vec3 c000 = texelFetch(u_flow, ivec3(i0.x, i0.y, i0.z), 0).xyz;
  vec3 c100 = texelFetch(u_flow, ivec3(i1.x, i0.y, i0.z), 0).xyz;
  vec3 c010 = texelFetch(u_flow, ivec3(i0.x, i1.y, i0.z), 0).xyz;
  vec3 c110 = texelFetch(u_flow, ivec3(i1.x, i1.y, i0.z), 0).xyz;
  vec3 c001 = texelFetch(u_flow, ivec3(i0.x, i0.y, i1.z), 0).xyz;
  vec3 c101 = texelFetch(u_flow, ivec3(i1.x, i0.y, i1.z), 0).xyz;
  vec3 c011 = texelFetch(u_flow, ivec3(i0.x, i1.y, i1.z), 0).xyz;
  vec3 c111 = texelFetch(u_flow, ivec3(i1.x, i1.y, i1.z), 0).xyz;
  vec3 x00 = mix(c000, c100, f.x), x10 = mix(c010, c110, f.x);
  vec3 x01 = mix(c001, c101, f.x), x11 = mix(c011, c111, f.x);
  return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

// Optional terms are compiled in only when used (ATTRACTORS, DRAG, FLOW, COLLIDERS are
// #defined per program variant): on llvmpipe an untaken "if (count > 0)" on a uniform still
// cost most of its body's price (measured, docs/gpu.md).
vec3 acceleration(vec3 p, vec3 v, int type) {
  vec3 a = u_gravity * u_type_gravity[type] + u_wind - u_type_damping[type] * v;
#ifdef ATTRACTORS
  for (int k = 0; k < u_attractor_count; ++k) {
    vec3 d = u_attractors[k].xyz - p;
    float r2 = dot(d, d) + u_softening[k] * u_softening[k];
    a += u_attractors[k].w * d / (r2 * sqrt(r2));
  }
#endif
#ifdef DRAG
  // Stokes' law, §3.3.2: F = 6πηr(v_{i−1} − v_flow).
#ifdef FLOW
  vec3 flow = flowVelocity(p);
#else
  vec3 flow = vec3(0.0);
#endif
  a -= u_drag * (v - flow);
#endif
  return a;
}

bool collide(vec3 previous, inout vec3 predicted, inout vec3 velocity) {
#ifdef COLLIDERS
  return collideAll(previous, predicted, velocity);
#else
  return false;
#endif
}

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec4 s0 = texelFetch(u_state0, texel, 0);
  vec4 s1 = texelFetch(u_state1, texel, 0);
  vec4 attributes = texelFetch(u_attributes, texel, 0);
  int type = clamp(int(attributes.z + 0.5), 0, 15);
  // §3.3.1: the GPU finds dead particles by their age; they are flagged (w = 0) and no longer
  // move, drawn or sorted in front.
  if (s0.w == 0.0 || u_time >= attributes.y) {
    out_state0 = vec4(s0.xyz, 0.0);
    out_state1 = s1;
    return;
  }
  vec3 p = s0.xyz;
  vec3 next_p, next_v, next_s1;
  // A sprite born in this step (a blast's own debris, fire and smoke) does not take the push of
  // this step's blasts: it starts with its own velocity at the centre instead of flying out as a ring.
  bool pushable = attributes.x < u_time - 1.5 * u_dt;  // born at this step's start: u_time - dt
  float diffuse_class = 0.0;  // 0 spray (or not diffuse), 1 foam, 2 bubble: kept in state1.w
  if (u_verlet == 0) {
    vec3 v = s1.xyz;
#ifdef BLASTS
    if (pushable) v += blastVelocityChange(p);
#endif
    vec3 fluid_velocity = vec3(0.0);
#ifdef DIFFUSE
    if (u_type_diffuse[type] != 0 && u_fluid_on != 0) {
      // §4.2: the class follows the fluid-neighbour count at the sprite, estimated from the grid's
      // interpolated count; v_f is the count-weighted mean velocity around it.
      vec4 fluid = fluidSample(p);
      float neighbours = fluid.w * u_neighbour_scale;
      diffuse_class = neighbours < u_class_counts.x ? 0.0 : (neighbours > u_class_counts.y ? 2.0 : 1.0);
      fluid_velocity = fluid.w > 1e-6 ? fluid.xyz / fluid.w : vec3(0.0);
    }
#endif
#ifdef DIFFUSE
    if (diffuse_class == 1.0) {
      // Foam: carried by the surface (eq. 7), x += dt v_f.
      next_v = fluid_velocity;
    } else if (diffuse_class == 2.0) {
      // Bubble (eq. 8): v += dt (-k_b g + k_d (v_f - v) / dt); it rises against gravity and the
      // drag pulls it along with the water.
      next_v = v - u_buoyancy * u_gravity * u_dt + u_bubble_drag * (fluid_velocity - v);
    } else
#endif
    {
      next_v = v + acceleration(p, v, type) * u_dt;
    }
    next_p = p + next_v * u_dt;
    collide(p, next_p, next_v);
    next_s1 = next_v;
  } else {
    vec3 p2 = s1.xyz;
#ifdef BLASTS
    if (pushable) p2 -= blastVelocityChange(p) * u_dt;  // Verlet keeps no velocity: dv moves P_{i-2} back
#endif
    vec3 v = (p - p2) / u_dt;
    next_p = 2.0 * p - p2 + acceleration(p, v, type) * (u_dt * u_dt);
    next_v = (next_p - p) / u_dt;
    next_s1 = p;
    if (collide(p, next_p, next_v)) next_s1 = next_p - next_v * u_dt;
  }
  // NaN/inf never spread: a particle that became non-finite dies here (w = 0).
  bool finite = !(any(isnan(next_p)) || any(isinf(next_p)) || any(isnan(next_s1)) || any(isinf(next_s1)));
  if (!finite) {
    out_state0 = vec4(0.0);
    out_state1 = vec4(0.0);
    return;
  }
  out_state0 = vec4(next_p, 1.0);
  out_state1 = vec4(next_s1, u_verlet == 0 ? diffuse_class : 1.0);
}
