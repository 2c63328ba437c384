#include "game/world/sprite_particles.hpp"

#include "fluid/core/finite.hpp"
#include "game/world/sph_fluid.hpp"

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace game {
namespace {

// Smallest power-of-two texture (w, h with w = h or w = 2h) holding `capacity` texels.
void textureSize(std::uint32_t capacity, std::uint32_t& w, std::uint32_t& h) {
  w = 1;
  h = 1;
  while (w * h < capacity) (w == h ? w : h) <<= 1;
}

// Ihmsen et al. 2012, eq. 1: Φ(I, τmin, τmax) = (min(I, τmax) − min(I, τmin)) / (τmax − τmin).
float clampPotential(float value, float lo, float hi) {
  if (!(hi > lo)) return value >= hi ? 1.0f : 0.0f;
  return (std::min(value, hi) - std::min(value, lo)) / (hi - lo);
}

std::vector<engine::ParticleTypeDesc> particleTypes(const SpriteParticleParams& p) {
  std::vector<engine::ParticleTypeDesc> types(9);
  const float d = 2.0f * p.size;  // key-frame sizes are diameters
  // Mist: pale, grows a little as it disperses, fades out.
  types[kMistType].keys = {{{glm::vec4(0.86f, 0.91f, 0.96f, 0.55f), d},
                            {glm::vec4(0.88f, 0.92f, 0.97f, 0.45f), 1.3f * d},
                            {glm::vec4(0.90f, 0.94f, 0.98f, 0.25f), 1.6f * d},
                            {glm::vec4(0.92f, 0.95f, 1.00f, 0.0f), 1.8f * d}}};
  // Spray: droplets torn off the SPH water, denser and bluer, smaller.
  types[kSprayType].keys = {{{glm::vec4(0.70f, 0.82f, 0.95f, 0.85f), 0.8f * d},
                             {glm::vec4(0.74f, 0.85f, 0.96f, 0.75f), 0.8f * d},
                             {glm::vec4(0.80f, 0.89f, 0.98f, 0.45f), 0.7f * d},
                             {glm::vec4(0.85f, 0.92f, 1.00f, 0.0f), 0.6f * d}}};
  // Explosion debris: small dark grit, thrown hard, keeps its size.
  types[kDebrisType].keys = {{{glm::vec4(0.22f, 0.19f, 0.16f, 1.0f), 0.7f * d},
                              {glm::vec4(0.25f, 0.22f, 0.18f, 1.0f), 0.7f * d},
                              {glm::vec4(0.28f, 0.25f, 0.21f, 0.8f), 0.6f * d},
                              {glm::vec4(0.30f, 0.27f, 0.23f, 0.0f), 0.5f * d}}};
  // Explosion smoke: dark where it leaves the fire, turns grey, billows out to about 1.4 m (fountain sprites) and
  // fades; it rises like warm air (a fifth of gravity, upward) and the air holds it back, so it
  // drifts up at about 1.3 m/s instead of falling with the debris.
  types[kSmokeType].keys = {{{glm::vec4(0.20f, 0.18f, 0.17f, 0.75f), 6.0f * d},
                             {glm::vec4(0.35f, 0.34f, 0.33f, 0.55f), 16.0f * d},
                             {glm::vec4(0.50f, 0.50f, 0.50f, 0.30f), 30.0f * d},
                             {glm::vec4(0.60f, 0.60f, 0.60f, 0.0f), 40.0f * d}}};
  types[kSmokeType].gravity_scale = -0.2f;
  types[kSmokeType].damping = 1.5f;
  // Explosion fireball: white-yellow at the centre, orange, then dark red as it cools and dies,
  // swelling to about a metre (in the fountain, whose sprites are 0.018 m); hot gas, so it rises and the air stops its
  // outward rush at once.
  types[kFireType].keys = {{{glm::vec4(1.00f, 0.95f, 0.70f, 1.0f), 12.0f * d},
                            {glm::vec4(1.00f, 0.62f, 0.18f, 0.95f), 24.0f * d},
                            {glm::vec4(0.85f, 0.30f, 0.08f, 0.7f), 28.0f * d},
                            {glm::vec4(0.40f, 0.12f, 0.05f, 0.0f), 30.0f * d}}};
  types[kFireType].gravity_scale = -0.3f;
  types[kFireType].damping = 6.0f;
  // Shock ring: white foam torn off the surface, growing as it spreads; the air slows its rush so
  // the ring expands fast and stops within a second, riding just above the water.
  types[kRingType].keys = {{{glm::vec4(0.97f, 0.98f, 1.00f, 0.95f), 4.0f * d},
                            {glm::vec4(0.95f, 0.97f, 1.00f, 0.85f), 7.0f * d},
                            {glm::vec4(0.92f, 0.95f, 0.99f, 0.50f), 10.0f * d},
                            {glm::vec4(0.90f, 0.94f, 0.98f, 0.0f), 12.0f * d}}};
  types[kRingType].gravity_scale = 0.25f;
  types[kRingType].damping = 2.5f;
  // Diffuse sprites (Ihmsen et al. 2012 §4.2), drawn by the class the GPU gives them each step.
  // Spray: like the SPH spray, with air drag (§4.3: ballistic with gravity and drag).
  types[kDiffuseSprayType].keys = types[kSprayType].keys;
  types[kDiffuseSprayType].damping = 0.5f;
  // Foam: white flecks lying on the water, opaque, fading over the lifetime.
  types[kFoamType].keys = {{{glm::vec4(0.97f, 0.98f, 1.00f, 0.95f), 1.6f * d},
                            {glm::vec4(0.96f, 0.97f, 0.99f, 0.90f), 1.8f * d},
                            {glm::vec4(0.94f, 0.96f, 0.99f, 0.60f), 1.8f * d},
                            {glm::vec4(0.92f, 0.95f, 0.98f, 0.0f), 1.6f * d}}};
  // Bubbles: small pale dots.
  types[kBubbleType].keys = {{{glm::vec4(0.85f, 0.93f, 1.00f, 0.70f), 0.6f * d},
                              {glm::vec4(0.85f, 0.93f, 1.00f, 0.70f), 0.6f * d},
                              {glm::vec4(0.88f, 0.95f, 1.00f, 0.60f), 0.6f * d},
                              {glm::vec4(0.90f, 0.96f, 1.00f, 0.0f), 0.5f * d}}};
  for (std::uint32_t t : {kDiffuseSprayType, kFoamType, kBubbleType}) types[t].diffuse = true;
  return types;
}

// One burst of a blast: `count` sprites of `type` from within `radius` of the centre raised by
// `rise`, at `speed`, living `lifetime` seconds (engine emitters).
struct BlastBurst {
  engine::EmitterKind kind;
  float rise, speed, radius;
  std::uint32_t count;
  float lifetime;
  std::uint32_t type;
  std::uint64_t salt;  // decorrelates the bursts' seeds
};
// Debris thrown hard, the fireball, and the smoke that rises after it.
constexpr BlastBurst kBlastBursts[] = {
    {engine::EmitterKind::debris, 0.0f, 9.0f, 0.15f, 160, 1.6f, kDebrisType, 0},
    {engine::EmitterKind::mist, 0.1f, 4.0f, 0.25f, 70, 0.45f, kFireType, 0x27d4eb2full},
    {engine::EmitterKind::mist, 0.2f, 2.5f, 0.4f, 90, 3.5f, kSmokeType, 0x5bd1e995ull},
};

// The water's surface over a blast: the highest SPH particle within `radius` across the blast's
// centre and within `depth` above or below it, when at least `min_particles` are there (a blast in
// or on the water; a blast in the air or on dry stone has none).
bool waterSurfaceAt(const SphFluid& sph, glm::vec3 centre, glm::vec3& surface) {
  constexpr float kRadius = 0.6f, kDepth = 0.8f;
  constexpr int kMinParticles = 12;
  const fluid::ParticleStore& p = sph.world.particles;
  int found = 0;
  float top = -std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < p.sphCount(); ++i) {
    const glm::vec3 d = p.position[i] - centre;
    if (d.x * d.x + d.z * d.z > kRadius * kRadius || std::abs(d.y) > kDepth) continue;
    ++found;
    top = std::max(top, p.position[i].y);
  }
  if (found < kMinParticles) return false;
  surface = glm::vec3(centre.x, top, centre.z);
  return true;
}

// The shock ring where a blast meets the water (issue 35): a crown of foam thrown out nearly flat
// from a ring around the blast on the surface, so the push the water already takes reads as a ring.
void emitShockRing(SpriteParticles& s, const SphFluid& sph, const fluid::Blast& blast, std::uint64_t seed) {
  glm::vec3 surface;
  if (!waterSurfaceAt(sph, blast.centre, surface)) return;
  ++s.shock_rings;
  engine::EmitterDesc ring;
  ring.kind = engine::EmitterKind::splash;
  ring.position = surface + glm::vec3(0.0f, 0.02f, 0.0f);
  ring.direction = glm::vec3(0.0f, 1.0f, 0.0f);
  ring.spread = glm::radians(78.0f);  // mostly outward, a little up
  ring.speed = 6.0f;
  ring.radius = blast.core_radius;
  ring.count = 200;
  ring.lifetime = 0.8f;
  ring.type = kRingType;
  ring.seed = seed ^ 0x165667b19e3779f9ull;
  engine::emit(ring, s.births);
}

// Keeps the births from `first` on whose place every level collider's lookup calls outside
// (distance >= 0, or no opinion), in order; returns how many it removed. The lookup is the
// fluid/collide query the update shader decodes decision for decision (collide.glsl), so a place
// called inside here is one the shader would react to.
//
// Why a blast's sprites are not born inside a solid: §3.3.2's caught-particle rule pushes a
// particle that is already inside "in direction of the shortest way out of the collider", one
// collider at a time. Deep inside a solid that way can lead out through the far side of a wall, or,
// where two solids overlap (a building front sunk into the street slab), into the other one, whose
// own push-out leads back: such a sprite ends every step inside one of them. Smoke and fire born in
// stone are not seen anyway; the part of the burst in the air is born as before.
std::size_t keepBirthsOutside(engine::BirthBatch& b, std::size_t first, const LevelColliders& colliders) {
  std::size_t kept = first;
  for (std::size_t i = first; i < b.positions.size(); ++i) {
    bool inside = false;
    for (const fluid::CachedCollider& part : colliders.parts) {
      const fluid::ColliderSample sample = part.collider.sample(b.positions[i]);  // collider space = world
      if (sample.valid && sample.distance < 0.0f) {
        inside = true;
        break;
      }
    }
    if (inside) continue;
    if (kept != i) {
      b.positions[kept] = b.positions[i];
      b.velocities[kept] = b.velocities[i];
      b.lifetimes[kept] = b.lifetimes[i];
      b.types[kept] = b.types[i];
      b.spins[kept] = b.spins[i];
    }
    ++kept;
  }
  const std::size_t removed = b.positions.size() - kept;
  b.positions.resize(kept);
  b.velocities.resize(kept);
  b.lifetimes.resize(kept);
  b.types.resize(kept);
  b.spins.resize(kept);
  return removed;
}

// Debris, a fireball and smoke at each blast's centre, and a shock ring where it meets the water,
// seeded by the step and the blast; only the ones born outside the level's colliders are kept
// (keepBirthsOutside).
void emitBlastSprites(SpriteParticles& s, const SphFluid* sph, std::span<const fluid::Blast> blasts) {
  const std::size_t first = s.births.size();
  for (std::size_t k = 0; k < blasts.size(); ++k) {
    const std::uint64_t seed = s.seed ^ (0x9e3779b97f4a7c15ull * (s.steps + 1)) ^ (k + 1);
    if (sph != nullptr && sph->error.empty()) emitShockRing(s, *sph, blasts[k], seed);
    for (const BlastBurst& burst : kBlastBursts) {
      if (burst.type == kDebrisType && !s.params.blast_debris) continue;
      engine::EmitterDesc desc;
      desc.kind = burst.kind;
      desc.position = blasts[k].centre + glm::vec3(0.0f, burst.rise, 0.0f);
      desc.speed = burst.speed;
      desc.radius = burst.radius;
      desc.count = burst.count;
      desc.lifetime = burst.lifetime;
      desc.type = burst.type;
      desc.seed = seed ^ burst.salt;
      engine::emit(desc, s.births);
    }
  }
  if (s.level_colliders) s.buried_blast += keepBirthsOutside(s.births, first, *s.level_colliders);
}

engine::GpuStepParams stepParams(const SpriteParticleParams& p) {
  engine::GpuStepParams g;
  g.diffuse.spray_below = static_cast<float>(std::max(p.foam_spray_below, 0));
  g.diffuse.bubble_above = static_cast<float>(std::max(p.foam_bubble_above, p.foam_spray_below));
  g.diffuse.buoyancy = p.bubble_buoyancy;
  g.diffuse.drag = std::clamp(p.bubble_drag, 0.0f, 1.0f);
  g.gravity = p.gravity;
  g.material.resilience = p.restitution;
  g.material.friction = p.friction;
  g.skin = 1e-3f;
  g.push_out_iterations = 4;
  return g;
}

// Mist births of one step: the debt keeps the long-run rate exact for any rate·dt.
void emitMist(SpriteParticles& s, float dt) {
  const SpriteParticleParams& p = s.params;
  s.emit_debt += static_cast<double>(std::max(p.rate, 0.0f)) * dt;
  const auto wanted = static_cast<std::uint32_t>(s.emit_debt);
  s.emit_debt -= wanted;
  if (wanted == 0) return;
  engine::EmitterDesc mist;
  mist.kind = engine::EmitterKind::spray;  // a cone (the emitter's "spray" shape)
  mist.position = p.nozzle;
  mist.direction = {0.0f, 1.0f, 0.0f};
  mist.speed = p.speed;
  mist.spread = glm::radians(std::clamp(p.spread_degrees, 0.0f, 90.0f));
  mist.radius = 0.03f;
  mist.count = wanted;
  mist.lifetime = p.lifetime;
  mist.type = kMistType;
  mist.seed = s.seed ^ (0x9e3779b97f4a7c15ull * (s.steps + 1));
  engine::emit(mist, s.births);
}

}  // namespace

void initSpriteParticles(SpriteParticles& s, const SpriteParticleParams& params, std::uint32_t capacity,
                         std::uint64_t seed) {
  s = SpriteParticles{};
  s.params = params;
  s.capacity = capacity;
  s.seed = seed;
}

bool loadSpriteColliders(SpriteParticles& s, const std::filesystem::path& content_dir, std::string& error) {
  if (!ensureLevelColliders(content_dir, s.level, s.level_colliders, error)) return false;
  s.collider_names.clear();
  for (const fluid::CachedCollider& part : s.level_colliders->parts) s.collider_names.push_back(part.name);
  s.bake_ms = s.level_colliders->load_ms;
  return true;
}

bool attachSpriteGpu(SpriteParticles& s, const std::filesystem::path& shader_dir,
                     const std::filesystem::path& content_dir, float dt) {
  detachSpriteGpu(s);
  s.gpu_error.clear();
  if (s.capacity == 0) return true;  // nothing to simulate: no GL object at all
  std::string error;
  if (!loadSpriteColliders(s, content_dir, error)) {
    s.gpu_error = "sprite colliders: " + error;
    return false;
  }
  engine::GpuParticlesDesc desc;
  textureSize(s.capacity, desc.width, desc.height);
  desc.types = particleTypes(s.params);
  desc.shader_dir = shader_dir;
  desc.dt = dt;
  desc.sort_passes_per_frame = 6;
  desc.budget = s.capacity;  // the texture rounds up to a power of two; the budget stays exact
  desc.class_types = {kDiffuseSprayType, kFoamType, kBubbleType};
  s.attached = true;
  engine::createGpuParticles(desc, s.gpu);
  if (!s.gpu.ready) {
    s.gpu_error = s.gpu.error;
    return false;
  }
  // The maps as baked, margin rings included: the shader does not read the ring flag, so a ring
  // texel's pair of equal depths votes like any other (fluid::DepthMap::margin_ring). Ring texels
  // lie outside the model's conservative cover, so their vote is never "inside": where the CPU
  // lets a ring vote decide (no other map sees the point outside) both say "outside", and where
  // another map says outside the shader may take the ring's shorter distance. The shader reacts
  // only to negative distances (collide.glsl collideAll), so it collides exactly where the CPU
  // lookup says inside.
  const std::vector<fluid::CachedCollider>& parts = s.level_colliders->parts;
  std::vector<std::vector<engine::GpuDepthMapView>> views(parts.size());
  std::vector<std::vector<float>> normals(parts.size());
  std::vector<engine::GpuColliderDesc> descs(parts.size());
  for (std::size_t c = 0; c < parts.size(); ++c)
    engine::describeCollider(parts[c].collider, fluid::ColliderPose{}, views[c], normals[c], descs[c]);
  // The collider variant of the update shader is compiled here, not in the first step's frame.
  if (!engine::setColliders(s.gpu, descs, error) || !engine::prepareStep(s.gpu, stepParams(s.params))) {
    s.gpu_error = error.empty() ? s.gpu.error : error;
    detachSpriteGpu(s);
    s.attached = true;  // attached but off: stepping stays a no-op, the overlay shows why
    return false;
  }
  return true;
}

void detachSpriteGpu(SpriteParticles& s) {
  if (s.attached) engine::destroyGpuParticles(s.gpu);
  s.gpu = engine::GpuParticles{};
  s.attached = false;
}

std::size_t emitSprayFromSph(const SphFluid& sph, const SpriteParticleParams& p, float dt, std::uint64_t seed,
                             double& debt, engine::BirthBatch& batch) {
  // Ihmsen, Akinci, Akinci & Teschner 2012, "Unified spray, foam and air bubbles for
  // particle-based fluids", §4: a fluid particle i generates n_d = I_k (k_ta I_ta + k_wc I_wc) Δt
  // diffuse particles, I_k = Φ(E_k, τ_k,min, τ_k,max) its kinetic-energy potential (eq. 1 clamp).
  // Subset used here: I_k with the specific energy ½|v|² (so the thresholds do not depend on the
  // particle size), and instead of the wave-crest potential I_wc (curvature from colour-field
  // normals, which needs a neighbour pass) a free-surface indicator I_s = 1 when ρ_i/ρ0 ≤
  // spray_surface_density (a particle missing neighbours sits at the surface) or the particle is
  // one of the SPH's ballistic drops, else 0; the
  // trapped-air term is left out. n_d = I_k · k · I_s · Δt, the fractions carried over in `debt`.
  const fluid::SphWorld& w = sph.world;
  const fluid::ParticleStore& store = w.particles;
  const float rest = w.params.rest_density;
  const float radius = w.params.particle_radius;
  const std::size_t n = std::min(store.position.size(), store.velocity.size());
  const auto cap = static_cast<std::size_t>(std::max(p.spray_max_per_step, 0));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float two_pi = glm::two_pi<float>();
  std::size_t added = 0;
  for (std::size_t i = 0; i < n && added < cap; ++i) {
    const glm::vec3 v = store.velocity[i], x = store.position[i];
    if (!fluid::isFinite(v) || !fluid::isFinite(x)) continue;
    // The SPH's ballistic drops (fluid::SphParams::spray_speed: the jet, a blast's spray) have left
    // the water and carry no density: I_s = 1.
    const bool drop = i >= store.sphCount();
    const float density = i < store.density.size() ? store.density[i] : rest;
    if (!drop && (!(density > 0.0f) || density / rest > p.spray_surface_density)) continue;
    const float energy = 0.5f * glm::dot(v, v);
    const float ik = clampPotential(energy, p.spray_energy_min, p.spray_energy_max);
    if (ik <= 0.0f) continue;
    debt += static_cast<double>(ik * std::max(p.spray_rate, 0.0f) * dt);
    if (debt < 1.0) continue;
    debt -= 1.0;
    // §4.1: positions uniform in the cylinder of radius r_i spanned by v_i Δt around x_i; the
    // diffuse particle inherits the fluid velocity (plus the radial offset's direction, scaled
    // small, so a sheet of spray fans out a little).
    const float speed = std::sqrt(2.0f * energy);
    const glm::vec3 axis = v / speed;
    const glm::vec3 helper = std::fabs(axis.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 e1 = glm::normalize(glm::cross(helper, axis)), e2 = glm::cross(axis, e1);
    const float r = radius * std::sqrt(unit(rng)), theta = two_pi * unit(rng), h = unit(rng);
    const glm::vec3 radial = std::cos(theta) * e1 + std::sin(theta) * e2;
    const glm::vec3 position = x + r * radial + h * dt * v;
    const glm::vec3 velocity = v + (0.1f * speed) * (r / std::max(radius, 1e-6f)) * radial;
    const float lifetime = std::max(1e-3f, p.spray_lifetime * (0.75f + 0.5f * unit(rng)));
    batch.push(position, velocity, lifetime, kSprayType, (unit(rng) - 0.5f) * two_pi);
    ++added;
  }
  if (debt > 1.0) debt = 1.0;  // what the cap refused is not owed to later steps
  return added;
}

fluid::DiffuseParams diffuseParams(const SpriteParticleParams& p, float h) {
  fluid::DiffuseParams d;
  d.radius = h;
  d.ta_min = p.foam_ta_min;
  d.ta_max = p.foam_ta_max;
  d.wc_min = p.foam_wc_min;
  d.wc_max = p.foam_wc_max;
  d.k_min = p.foam_energy_min;
  d.k_max = p.foam_energy_max;
  d.k_ta = p.foam_trapped_air_rate;
  d.k_wc = p.foam_wave_crest_rate;
  d.spray_below = p.foam_spray_below;
  d.bubble_above = p.foam_bubble_above;
  return fluid::clampDiffuseParams(d);
}

std::size_t emitDiffuseFromSph(const SphFluid& sph, const SpriteParticleParams& p, float dt, std::uint64_t seed,
                               DiffuseScratchSet scratch, engine::BirthBatch& batch,
                               std::array<std::uint32_t, 3>& per_class) {
  per_class = {};
  const fluid::SphWorld& w = sph.world;
  const fluid::ParticleStore& store = w.particles;
  // The SPH water only (the ballistic drops at the store's end are not part of the fluid).
  const std::size_t n = std::min({store.sphCount(), store.position.size(), store.velocity.size()});
  const std::span<const glm::vec3> x(store.position.data(), n), v(store.velocity.data(), n);
  const fluid::DiffuseParams params = diffuseParams(p, fluid::sphSupport(w.params));
  if (!(params.k_ta > 0.0f || params.k_wc > 0.0f)) return 0;
  if (!fluid::computeDiffusePotentials(x, v, params, scratch.scratch, scratch.potentials)) return 0;
  scratch.births.clear();
  fluid::generateDiffuse(x, v, scratch.potentials, params, dt, seed,
                         static_cast<std::size_t>(std::max(p.foam_max_per_step, 0)), scratch.births);
  std::mt19937_64 rng(seed ^ 0x2545f4914f6cdd1dull);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  constexpr std::uint32_t kTypes[3] = {kDiffuseSprayType, kFoamType, kBubbleType};
  for (const fluid::DiffuseBirth& b : scratch.births) {
    const auto c = static_cast<std::size_t>(b.type);
    const float lifetime = std::max(1e-3f, p.foam_lifetime * (0.75f + 0.5f * unit(rng)));
    batch.push(b.position, b.velocity, lifetime, kTypes[c], 0.0f);
    ++per_class[c];
  }
  return scratch.births.size();
}

std::string stepSpriteParticles(SpriteParticles& s, const SphFluid* sph, float dt,
                                std::span<const fluid::Blast> blasts) {
  if (!s.attached || !s.gpu.ready) return {};
  std::string failure;
  s.births.clear();
  emitMist(s, dt);
  const std::size_t mist = s.births.size();
  s.spray_last_step = 0;
  if (sph != nullptr && sph->error.empty() && s.params.spray_rate > 0.0f) {
    s.spray_last_step = static_cast<std::uint32_t>(
        emitSprayFromSph(*sph, s.params, dt, s.seed ^ (0xc2b2ae3d27d4eb4full * (s.steps + 1)), s.spray_debt, s.births));
  }
  s.diffuse_last_step = {};
  const std::size_t before_diffuse = s.births.size();
  // Foam off (both rates 0): no potentials and no grid; sprites already born keep the last grid.
  const bool foam = s.params.foam_trapped_air_rate > 0.0f || s.params.foam_wave_crest_rate > 0.0f;
  if (sph != nullptr && sph->error.empty() && foam) {
    emitDiffuseFromSph(*sph, s.params, dt, s.seed ^ (0x94d049bb133111ebull * (s.steps + 1)),
                       {s.diffuse_scratch, s.potentials, s.diffuse_births}, s.births, s.diffuse_last_step);
    // The grid the GPU classes and moves the diffuse sprites by (recorded, uploaded by the frame).
    const fluid::ParticleStore& store = sph->world.particles;
    const std::size_t n = std::min({store.sphCount(), store.position.size(), store.velocity.size()});
    const float h = fluid::sphSupport(sph->world.params);
    std::string error;
    engine::FluidGridDesc grid;
    if (fluid::buildFluidCellGrid(std::span(store.position.data(), n), std::span(store.velocity.data(), n), h, h, 64,
                                  s.fluid_grid)) {
      grid.size = s.fluid_grid.size;
      grid.origin = s.fluid_grid.origin;
      grid.cell = s.fluid_grid.cell;
      grid.neighbour_scale = s.fluid_grid.neighbour_scale;
      grid.cells = s.fluid_grid.cells;
    }
    // A refused grid leaves the last one in place; the world counts the refusal.
    if (!engine::setFluidGrid(s.gpu, grid, error)) failure = "sprite_particles: " + error;
  }
  const std::size_t before_blasts = s.births.size();
  emitBlastSprites(s, sph, blasts);
  const std::size_t born = engine::spawn(s.gpu, s.births);
  // spawn takes the batch in order until the budget is full: mist, then spray, then blast sprites.
  // A blast's own sprites, born in its step, do not take its push (update.frag): they start as a
  // ball at the centre, the part of it in the air (emitBlastSprites).
  const std::size_t mist_born = std::min(born, mist);
  const std::size_t spray_born = std::min(born, before_diffuse) - mist_born;
  const std::size_t diffuse_born = std::min(born, before_blasts) - mist_born - spray_born;
  s.born_mist += mist_born;
  s.born_spray += spray_born;
  s.born_diffuse += diffuse_born;
  s.born_blast += born - mist_born - spray_born - diffuse_born;
  s.dropped += s.births.size() - born;
  engine::GpuStepParams params = stepParams(s.params);
  params.blast_count = static_cast<int>(std::min<std::size_t>(blasts.size(), engine::kMaxBlasts));
  for (int k = 0; k < params.blast_count; ++k)
    params.blasts[static_cast<std::size_t>(k)] = blasts[static_cast<std::size_t>(k)];
  engine::step(s.gpu, params);
  ++s.steps;
  if (s.readback_every > 0 && s.steps % static_cast<std::uint64_t>(s.readback_every) == 0)
    engine::requestReadback(s.gpu);
  return failure;
}

std::uint32_t liveSprites(const SpriteParticles& s) {
  return s.attached && s.gpu.ready ? s.gpu.allocator.live_count : 0u;
}

std::string findNonFiniteSprite(const SpriteParticles& s) {
  static constexpr const char* kAxis[] = {"x", "y", "z"};
  auto check = [](const std::vector<glm::vec4>& values, const char* what) -> std::string {
    for (std::size_t i = 0; i < values.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(values[i][a]))
          return "sprite_particles: live sprite " + std::to_string(i) + " " + what + "." + kAxis[a] + " = " +
                 std::to_string(values[i][a]);
      }
    }
    return {};
  };
  std::string bad = check(s.gpu.readback.positions, "position");
  if (bad.empty()) bad = check(s.gpu.readback.velocities, "velocity");
  return bad;
}

}  // namespace game
