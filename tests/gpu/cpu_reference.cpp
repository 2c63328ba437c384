#include "tests/gpu/cpu_reference.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace gputest {

engine::GpuColliderDesc TestCollider::gpu() {
  engine::GpuColliderDesc d;
  engine::describeCollider(shape, pose, views, normal_table, d);
  return d;
}

fluid::ColliderSample TestCollider::sampleWorld(glm::vec3 world) const {
  fluid::ColliderSample s = shape.sample(fluid::toColliderSpace(pose, world));
  if (s.valid) s.normal = fluid::toWorldDirection(pose, s.normal);
  return s;
}

TestCollider makeGroundCollider(int n) {
  fluid::DepthMap m;
  m.format = fluid::DepthMapFormat::float32;
  m.compare = fluid::DepthCompare::less;
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
      std::memcpy(m.texels.data() +
                      (static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)) * 16,
                  texel, 16);
    }
  }
  std::vector<fluid::DepthMap> maps;
  maps.push_back(std::move(m));
  return TestCollider{fluid::DepthMapCollider(std::move(maps), 256), {}, {}, {}};
}

TestCollider makeSphereCollider(glm::vec3 centre, float radius, int resolution, fluid::DepthMapFormat format) {
  // UV sphere, outward counter-clockwise winding.
  constexpr int rings = 24, segments = 48;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  for (int r = 0; r <= rings; ++r) {
    const float theta = static_cast<float>(r) / rings * 3.14159265f;
    for (int s = 0; s <= segments; ++s) {
      const float phi = static_cast<float>(s) / segments * 6.2831853f;
      positions.push_back(centre + radius * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                      std::sin(theta) * std::sin(phi)));
    }
  }
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const auto a = static_cast<std::uint32_t>(r * (segments + 1) + s), b = a + segments + 1;
      indices.insert(indices.end(), {a, a + 1, b, a + 1, b + 1, b});
    }
  }
  const fluid::MeshView mesh{positions, indices};
  std::vector<fluid::MapSpec> specs;
  if (format == fluid::DepthMapFormat::cube8) {
    specs.push_back(fluid::cubeMapSpec(centre, glm::vec3(radius * 1.2f), resolution, fluid::DepthCompare::greater));
  } else {
    specs = fluid::defaultMapSpecs(fluid::meshBounds(mesh), resolution, format, false);
  }
  TestCollider out;
  fluid::BakeDesc desc;
  desc.normal_resolution = 256;
  desc.threads = 1;
  const fluid::BakeStatus status = fluid::bakeDepthMaps(mesh, specs, desc, out.shape);
  if (!status.ok()) throw std::runtime_error("sphere bake failed: " + status.error);
  return out;
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
                          static_cast<std::size_t>(size.x) +
                      static_cast<std::size_t>(x)];
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
    p.state1.push_back(desc.integrator == engine::Integrator::euler
                           ? batch.velocities[k]
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

}  // namespace

void cpuStep(CpuParticles& p, float time, const CpuStepDesc& d) {
  // Integration of every live particle, then the collide module's batch collision per collider.
  std::vector<std::size_t> live;
  p.previous.clear();
  p.predicted.clear();
  p.velocity.clear();
  for (std::size_t k = 0; k < p.position.size(); ++k) {
    if (!p.alive[k] || time >= p.death[k]) {
      p.alive[k] = 0;
      continue;
    }
    const glm::vec3 x = p.position[k];
    glm::vec3 next, v;
    if (d.integrator == engine::Integrator::euler) {
      v = p.state1[k] + acceleration(x, p.state1[k], d) * d.dt;
      next = x + v * d.dt;
    } else {
      const glm::vec3 x2 = p.state1[k];
      next = 2.0f * x - x2 + acceleration(x, (x - x2) / d.dt, d) * (d.dt * d.dt);
      v = (next - x) / d.dt;
    }
    live.push_back(k);
    p.previous.push_back(x);
    p.predicted.push_back(next);
    p.velocity.push_back(v);
  }
  std::vector<std::uint8_t> hit(live.size(), 0);
  std::vector<glm::vec3> before;
  fluid::CollideDesc cd;
  cd.material = d.params.material;
  cd.dt = d.dt;
  cd.skin = d.params.skin;
  cd.parallel.threads = 1;
  const int iterations = std::clamp(d.params.push_out_iterations, 0, 8);
  for (TestCollider* c : d.colliders) {
    before = p.predicted;
    fluid::collideParticles(c->shape, c->pose, p.previous, p.predicted, p.velocity, cd, p.scratch);
    for (std::size_t i = 0; i < live.size(); ++i) {
      if (p.predicted[i] == before[i]) continue;  // no reaction: the position is untouched
      hit[i] = 1;
      // Extra push-out (GpuStepParams::push_out_iterations), as in collide.glsl.
      for (int it = 0; it < iterations; ++it) {
        const fluid::ColliderSample again = c->sampleWorld(p.predicted[i]);
        if (!again.valid || again.distance >= 0.0f) break;
        p.predicted[i] += again.normal * (d.params.skin - again.distance);
      }
    }
  }
  for (std::size_t i = 0; i < live.size(); ++i) {
    const std::size_t k = live[i];
    if (d.integrator == engine::Integrator::euler) {
      p.state1[k] = p.velocity[i];
    } else {
      p.state1[k] = hit[i] ? p.predicted[i] - p.velocity[i] * d.dt : p.previous[i];
    }
    p.position[k] = p.predicted[i];
  }
}

}  // namespace gputest
