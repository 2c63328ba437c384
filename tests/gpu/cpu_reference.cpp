#include "tests/gpu/cpu_reference.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace gputest {

engine::GpuDepthMapView TestDepthMap::view() const {
  engine::GpuDepthMapView v;
  v.format = format;
  v.compare = compare;
  v.resolution = resolution;
  v.collider_to_map = collider_to_map;
  v.z_scale = z_scale;
  v.cube_scale = cube_scale;
  v.encloses_collider = encloses_collider;
  v.texels = texels;
  return v;
}

std::vector<engine::GpuDepthMapView> TestCollider::views() const {
  std::vector<engine::GpuDepthMapView> out;
  for (const TestDepthMap& m : maps) out.push_back(m.view());
  return out;
}

glm::ivec2 l1Texel(glm::vec3 n, int resolution) {
  const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  const glm::vec3 p = n / l1;
  auto sgnp = [](float x) { return x >= 0.0f ? 1.0f : -1.0f; };
  glm::vec2 ab = p.z >= 0.0f ? glm::vec2(p.x, p.y)
                             : glm::vec2(sgnp(p.x) * (1.0f - std::fabs(p.y)), sgnp(p.y) * (1.0f - std::fabs(p.x)));
  const glm::vec2 st = ab * 0.5f + 0.5f;
  const float r = static_cast<float>(resolution);
  return {std::min(static_cast<int>(std::floor(st.x * r)), resolution - 1),
          std::min(static_cast<int>(std::floor(st.y * r)), resolution - 1)};
}

std::vector<float> l1NormalTable(int resolution) {
  std::vector<float> out(3u * static_cast<std::size_t>(resolution) * static_cast<std::size_t>(resolution));
  for (int j = 0; j < resolution; ++j) {
    for (int i = 0; i < resolution; ++i) {
      const float s = static_cast<float>((i + 0.5) / resolution), t = static_cast<float>((j + 0.5) / resolution);
      const float a = 2.0f * s - 1.0f, b = 2.0f * t - 1.0f;
      glm::vec3 v;
      if (std::fabs(a) + std::fabs(b) <= 1.0f) {
        v = {a, b, 1.0f - std::fabs(a) - std::fabs(b)};
      } else {  // eq. (3), lower half of the octahedron
        v = {std::copysign(1.0f - std::fabs(b), a), std::copysign(1.0f - std::fabs(a), b),
             1.0f - std::fabs(a) - std::fabs(b)};
      }
      v = glm::normalize(v);
      const std::size_t k = 3u * (static_cast<std::size_t>(j) * static_cast<std::size_t>(resolution) + static_cast<std::size_t>(i));
      out[k] = v.x;
      out[k + 1] = v.y;
      out[k + 2] = v.z;
    }
  }
  return out;
}

namespace {

struct Winner {
  float f = -FLT_MAX;
  const TestDepthMap* map = nullptr;
  std::uint32_t texel = 0;
};

void vote(Winner& w, float fi, const TestDepthMap* map, std::uint32_t texel, bool& any) {
  any = true;
  const bool take = fi >= 0.0f ? (w.f < 0.0f || fi < w.f) : (w.f < 0.0f && fi > w.f);
  if (take) {
    w.f = fi;
    w.map = map;
    w.texel = texel;
  }
}

glm::vec3 transformPoint(const glm::mat4& m, glm::vec3 p) {
  return glm::vec3(m[0]) * p.x + glm::vec3(m[1]) * p.y + glm::vec3(m[2]) * p.z + glm::vec3(m[3]);
}

constexpr float kFixedDepthStep = static_cast<float>(1.0 / 65535.0);

}  // namespace

fluid::ColliderSample TestCollider::sample(glm::vec3 p) const {
  fluid::ColliderSample out{FLT_MAX, {0.0f, 0.0f, 1.0f}, false};
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return out;
  Winner w;
  bool any = false;
  for (const TestDepthMap& map : maps) {
    const glm::vec3 q = transformPoint(map.collider_to_map, p);
    auto invalid = [&]() {
      if (map.encloses_collider) vote(w, FLT_MAX, nullptr, 0, any);
    };
    if (!(q.x >= 0.0f && q.x < 1.0f && q.y >= 0.0f && q.y < 1.0f && q.z >= 0.0f && q.z <= 1.0f)) {
      invalid();
      continue;
    }
    const int n = static_cast<int>(map.resolution);
    const int i = std::min(static_cast<int>(q.x * static_cast<float>(n)), n - 1);
    const int j = std::min(static_cast<int>(q.y * static_cast<float>(n)), n - 1);
    const auto texel = static_cast<std::uint32_t>(j * n + i);
    const float sign_less = map.compare == 0 ? 1.0f : -1.0f;
    if (map.format == 1) {
      float depth;
      std::memcpy(&depth, map.texels.data() + texel * 16 + 12, 4);
      if (depth < 0.0f) {
        invalid();
        continue;
      }
      vote(w, sign_less * map.z_scale * (depth - q.z), &map, texel, any);
    } else {  // fixed8
      const std::uint8_t* t = map.texels.data() + texel * 4;
      const auto code = static_cast<std::uint16_t>((t[2] << 8) | t[3]);
      if (code == 0xFFFF) {
        invalid();
        continue;
      }
      vote(w, sign_less * map.z_scale * (static_cast<float>(code) * kFixedDepthStep - q.z), &map, texel, any);
    }
  }
  if (!any || w.map == nullptr) return out;
  out.valid = true;
  out.distance = w.f;
  if (w.map->format == 1) {
    float n[3];
    std::memcpy(n, w.map->texels.data() + w.texel * 16, 12);
    out.normal = {n[0], n[1], n[2]};
  } else {
    const std::uint8_t* t = w.map->texels.data() + w.texel * 4;
    const std::size_t k = 3u * (static_cast<std::size_t>(t[1]) * static_cast<std::size_t>(normal_resolution) + t[0]);
    out.normal = {normal_table[k], normal_table[k + 1], normal_table[k + 2]};
  }
  return out;
}

void TestCollider::query(std::span<const glm::vec3> local_points, std::span<fluid::ColliderSample> out) const {
  for (std::size_t k = 0; k < local_points.size(); ++k) out[k] = sample(local_points[k]);
}

fluid::ColliderSample TestCollider::sampleWorld(glm::vec3 world) const {
  fluid::ColliderSample s = sample(fluid::toColliderSpace(pose, world));
  if (s.valid) s.normal = fluid::toWorldDirection(pose, s.normal);
  return s;
}

TestCollider makeGroundCollider(int n) {
  TestCollider c;
  TestDepthMap m;
  m.format = 1;
  m.compare = 0;
  m.resolution = static_cast<std::uint32_t>(n);
  // P' = ((x+2)/4, (z+2)/4, (1−y)/2): looking down from y = 1 over y ∈ [−1, 1].
  m.collider_to_map = glm::mat4(glm::vec4(0.25f, 0.0f, 0.0f, 0.0f), glm::vec4(0.0f, 0.0f, -0.5f, 0.0f),
                                glm::vec4(0.0f, 0.25f, 0.0f, 0.0f), glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
  m.z_scale = 2.0f;
  m.texels.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * 16);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const bool border = i == 0 || j == 0 || i == n - 1 || j == n - 1;  // §4.1: one background texel
      const float texel[4] = {0.0f, 1.0f, 0.0f, border ? -1.0f : 0.5f};
      std::memcpy(m.texels.data() + (static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)) * 16,
                  texel, 16);
    }
  }
  c.maps.push_back(std::move(m));
  return c;
}

TestCollider makeSphereCollider(glm::vec3 centre, float radius, int n, int normal_resolution) {
  TestCollider c;
  c.normal_resolution = normal_resolution;
  c.normal_table = l1NormalTable(normal_resolution);
  const float h = radius * 1.25f;  // view volume half size
  const glm::vec3 lo = centre - glm::vec3(h);
  // P' = (P − lo)/(2h): looking along +z.
  const glm::mat4 t(glm::vec4(0.5f / h, 0.0f, 0.0f, 0.0f), glm::vec4(0.0f, 0.5f / h, 0.0f, 0.0f),
                    glm::vec4(0.0f, 0.0f, 0.5f / h, 0.0f), glm::vec4(-lo * (0.5f / h), 1.0f));
  for (std::uint32_t compare : {0u, 1u}) {
    TestDepthMap m;
    m.format = 2;
    m.compare = compare;
    m.resolution = static_cast<std::uint32_t>(n);
    m.collider_to_map = t;
    m.z_scale = 2.0f * h;
    m.texels.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * 4, 0xFF);
    for (int j = 1; j < n - 1; ++j) {
      for (int i = 1; i < n - 1; ++i) {
        const float x = lo.x + (static_cast<float>(i) + 0.5f) / static_cast<float>(n) * 2.0f * h;
        const float y = lo.y + (static_cast<float>(j) + 0.5f) / static_cast<float>(n) * 2.0f * h;
        const float dx = x - centre.x, dy = y - centre.y;
        const float r2 = radius * radius - dx * dx - dy * dy;
        if (r2 <= 0.0f) continue;
        const float dz = std::sqrt(r2) * (compare == 0 ? -1.0f : 1.0f);
        const float z = centre.z + dz;
        const float depth = (z - lo.z) / (2.0f * h);
        const auto q = static_cast<std::uint16_t>(std::clamp(std::lround(depth * 65535.0f), 0L, 65534L));
        const glm::ivec2 nt = l1Texel(glm::vec3(dx, dy, dz) / radius, normal_resolution);
        std::uint8_t* texel = m.texels.data() + (static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)) * 4;
        texel[0] = static_cast<std::uint8_t>(nt.x);
        texel[1] = static_cast<std::uint8_t>(nt.y);
        texel[2] = static_cast<std::uint8_t>(q >> 8);
        texel[3] = static_cast<std::uint8_t>(q & 0xFF);
      }
    }
    c.maps.push_back(std::move(m));
  }
  return c;
}

glm::vec3 CpuFlowField::sample(glm::vec3 p) const {
  const glm::vec3 sz(size);
  glm::vec3 g = (p - origin) / extent * sz - 0.5f;
  g = glm::clamp(g, glm::vec3(0.0f), sz - 1.0f);
  const glm::ivec3 i0(glm::floor(g));
  const glm::vec3 f = g - glm::vec3(i0);
  const glm::ivec3 i1 = glm::min(i0 + 1, size - 1);
  auto at = [&](int x, int y, int z) {
    return velocities[(static_cast<std::size_t>(z) * static_cast<std::size_t>(size.y) + static_cast<std::size_t>(y)) *
                          static_cast<std::size_t>(size.x) + static_cast<std::size_t>(x)];
  };
  const glm::vec3 x00 = glm::mix(at(i0.x, i0.y, i0.z), at(i1.x, i0.y, i0.z), f.x);
  const glm::vec3 x10 = glm::mix(at(i0.x, i1.y, i0.z), at(i1.x, i1.y, i0.z), f.x);
  const glm::vec3 x01 = glm::mix(at(i0.x, i0.y, i1.z), at(i1.x, i0.y, i1.z), f.x);
  const glm::vec3 x11 = glm::mix(at(i0.x, i1.y, i1.z), at(i1.x, i1.y, i1.z), f.x);
  return glm::mix(glm::mix(x00, x10, f.y), glm::mix(x01, x11, f.y), f.z);
}

void cpuSpawn(CpuParticles& p, const engine::BirthBatch& batch, float time, const CpuStepDesc& desc) {
  for (std::size_t k = 0; k < batch.size(); ++k) {
    p.position.push_back(batch.positions[k]);
    p.state1.push_back(desc.integrator == engine::Integrator::euler ? batch.velocities[k]
                                                                    : batch.positions[k] - batch.velocities[k] * desc.dt);
    p.death.push_back(time + batch.lifetimes[k]);
    p.alive.push_back(1);
  }
}

namespace {

glm::vec3 acceleration(glm::vec3 p, glm::vec3 v, const CpuStepDesc& d) {
  const engine::GpuStepParams& s = d.params;
  glm::vec3 a = s.gravity + s.wind;
  for (int k = 0; k < s.attractor_count; ++k) {
    const engine::Attractor& at = s.attractors[static_cast<std::size_t>(k)];
    const glm::vec3 dir = at.position - p;
    const float soft = std::max(at.softening, 1e-4f);
    const float r2 = glm::dot(dir, dir) + soft * soft;
    a += at.strength * dir / (r2 * std::sqrt(r2));
  }
  const float drag = engine::stokesDragRate(s);
  if (drag > 0.0f) a -= drag * (v - (d.flow != nullptr ? d.flow->sample(p) : glm::vec3(0.0f)));
  return a;
}

// fluid::collideParticles for one particle and every collider in turn.
bool collide(glm::vec3 previous, glm::vec3& predicted, glm::vec3& velocity, const CpuStepDesc& d) {
  bool hit = false;
  for (const TestCollider* c : d.colliders) {
    const fluid::ColliderSample after = c->sampleWorld(predicted);
    if (!after.valid || after.distance >= 0.0f) continue;
    const fluid::ColliderSample before = c->sampleWorld(previous);
    const fluid::CollisionResult r =
        fluid::resolveCollision(previous, before, predicted, velocity, after, fluid::colliderVelocityAt(c->pose, predicted),
                                d.dt, d.params.skin, d.params.material);
    predicted = r.position;
    velocity = r.velocity;
    hit = true;
    // Extra push-out (GpuStepParams::push_out_iterations): a push along one texel's normal can
    // land over another texel that is still inside; repeat the projection there.
    for (int it = 0; it < std::clamp(d.params.push_out_iterations, 0, 8); ++it) {
      const fluid::ColliderSample again = c->sampleWorld(predicted);
      if (!again.valid || again.distance >= 0.0f) break;
      predicted += again.normal * (d.params.skin - again.distance);
    }
  }
  return hit;
}

}  // namespace

void cpuStep(CpuParticles& p, float time, const CpuStepDesc& d) {
  for (std::size_t k = 0; k < p.position.size(); ++k) {
    if (!p.alive[k] || time >= p.death[k]) {
      p.alive[k] = 0;
      continue;
    }
    const glm::vec3 x = p.position[k];
    if (d.integrator == engine::Integrator::euler) {
      glm::vec3 v = p.state1[k] + acceleration(x, p.state1[k], d) * d.dt;
      glm::vec3 next = x + v * d.dt;
      collide(x, next, v, d);
      p.position[k] = next;
      p.state1[k] = v;
    } else {
      const glm::vec3 x2 = p.state1[k];
      const glm::vec3 v0 = (x - x2) / d.dt;
      glm::vec3 next = 2.0f * x - x2 + acceleration(x, v0, d) * (d.dt * d.dt);
      glm::vec3 v = (next - x) / d.dt;
      glm::vec3 s1 = x;
      if (collide(x, next, v, d)) s1 = next - v * d.dt;
      p.position[k] = next;
      p.state1[k] = s1;
    }
  }
}

}  // namespace gputest
