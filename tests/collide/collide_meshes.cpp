#include "collide_meshes.hpp"

#include <cmath>
#include <numbers>

namespace collide_test {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;
}

Mesh makeSphere(float radius, int rings, int segments) {
  std::vector<glm::vec2> profile;
  for (int i = 0; i <= rings; ++i) {
    const float theta = kPi * static_cast<float>(i) / static_cast<float>(rings);
    profile.push_back({radius * std::sin(theta), -radius * std::cos(theta)});
  }
  profile.front().x = 0.0f;
  profile.back().x = 0.0f;
  return makeLathe(profile, segments);
}

Mesh makeTorus(float major_radius, float minor_radius, int major_segments, int minor_segments) {
  Mesh m;
  for (int i = 0; i < major_segments; ++i) {
    const float u = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(major_segments);
    for (int j = 0; j < minor_segments; ++j) {
      const float v = 2.0f * kPi * static_cast<float>(j) / static_cast<float>(minor_segments);
      const float r = major_radius + minor_radius * std::cos(v);
      m.positions.push_back({r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v)});
    }
  }
  auto id = [&](int i, int j) {
    return static_cast<std::uint32_t>((i % major_segments) * minor_segments + (j % minor_segments));
  };
  for (int i = 0; i < major_segments; ++i) {
    for (int j = 0; j < minor_segments; ++j) {
      m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

Mesh makeBox(glm::vec3 lo, glm::vec3 hi) {
  Mesh m;
  for (int k = 0; k < 8; ++k) m.positions.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
  const std::uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
  return m;
}

Mesh makeLathe(const std::vector<glm::vec2>& profile, int segments) {
  Mesh m;
  // Vertex rows: profile points on the axis become one pole vertex.
  std::vector<std::uint32_t> row_start;
  for (const glm::vec2& p : profile) {
    row_start.push_back(static_cast<std::uint32_t>(m.positions.size()));
    if (p.x == 0.0f) {
      m.positions.push_back({0.0f, 0.0f, p.y});
      continue;
    }
    for (int s = 0; s < segments; ++s) {
      const float a = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      m.positions.push_back({p.x * std::cos(a), p.x * std::sin(a), p.y});
    }
  }
  auto at = [&](std::size_t row, int s) {
    return profile[row].x == 0.0f ? row_start[row] : row_start[row] + static_cast<std::uint32_t>(s % segments);
  };
  for (std::size_t r = 0; r + 1 < profile.size(); ++r) {
    for (int s = 0; s < segments; ++s) {
      const std::uint32_t a = at(r, s), b = at(r, s + 1), c = at(r + 1, s + 1), d = at(r + 1, s);
      if (a != b) m.indices.insert(m.indices.end(), {a, b, c});
      if (c != d) m.indices.insert(m.indices.end(), {a, c, d});
    }
  }
  return m;
}

Mesh makeBasin(int segments) {
  // Profile from the bottom centre, out along the base, up the outer wall, over the rim,
  // down the overhanging inner wall and across the floor back to the axis.
  const std::vector<glm::vec2> profile = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.2f, 0.6f},   {1.0f, 1.0f},
                                          {0.8f, 1.0f}, {1.0f, 0.6f}, {0.85f, 0.15f}, {0.0f, 0.15f}};
  return makeLathe(profile, segments);
}

}  // namespace collide_test
