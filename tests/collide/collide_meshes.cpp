#include "collide_meshes.hpp"

#include <algorithm>
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

Mesh makeLatheLoop(const std::vector<glm::vec2>& profile, int segments) {
  Mesh m;
  const auto rows = static_cast<std::uint32_t>(profile.size());
  for (const glm::vec2& p : profile) {
    for (int s = 0; s < segments; ++s) {
      const float a = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      m.positions.push_back({p.x * std::cos(a), p.x * std::sin(a), p.y});
    }
  }
  auto at = [&](std::uint32_t row, int s) {
    return (row % rows) * static_cast<std::uint32_t>(segments) + static_cast<std::uint32_t>(s % segments);
  };
  for (std::uint32_t r = 0; r < rows; ++r) {
    for (int s = 0; s < segments; ++s) {
      const std::uint32_t a = at(r, s), b = at(r, s + 1), c = at(r + 1, s + 1), d = at(r + 1, s);
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
  }
  return m;
}

void orientOutward(Mesh& m) {
  double volume6 = 0.0;
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const glm::dvec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
                     c = m.positions[m.indices[t + 2]];
    volume6 += glm::dot(a, glm::cross(b, c));
  }
  if (volume6 >= 0.0) return;
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) std::swap(m.indices[t + 1], m.indices[t + 2]);
}

void append(Mesh& m, const Mesh& part) {
  const auto base = static_cast<std::uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
  for (std::uint32_t i : part.indices) m.indices.push_back(base + i);
}

Mesh makeBowl(int segments) {
  // Outer sphere from the bottom pole up to z = 0.2, the rim, the inner sphere back down.
  const float outer = 0.5f, inner = 0.45f, rim = 0.2f;
  const int steps = std::max(4, segments / 4);
  std::vector<glm::vec2> profile;
  const float outer_top = std::acos(-rim / outer), inner_top = std::acos(-rim / inner);
  for (int i = 0; i <= steps; ++i) {
    const float t = outer_top * static_cast<float>(i) / static_cast<float>(steps);
    profile.push_back({outer * std::sin(t), -outer * std::cos(t)});
  }
  for (int i = steps; i >= 0; --i) {
    const float t = inner_top * static_cast<float>(i) / static_cast<float>(steps);
    profile.push_back({inner * std::sin(t), -inner * std::cos(t)});
  }
  profile.front().x = 0.0f;
  profile.back().x = 0.0f;
  Mesh m = makeLathe(profile, segments);
  orientOutward(m);
  return m;
}

Mesh makeMug(int segments) {
  Mesh m = makeLathe({{0.0f, 0.0f}, {0.4f, 0.0f}, {0.4f, 1.0f}, {0.35f, 1.0f}, {0.35f, 0.1f}, {0.0f, 0.1f}}, segments);
  orientOutward(m);
  // The handle: a torus about z turned into the x-z plane (a rotation about x, so its winding
  // stays outward), beside the wall.
  Mesh handle = makeTorus(0.25f, 0.05f, segments, std::max(8, segments / 4));
  for (glm::vec3& p : handle.positions) p = glm::vec3(p.x + 0.73f, -p.z, p.y + 0.5f);
  orientOutward(handle);
  append(m, handle);
  return m;
}

Mesh makePipe(int segments) {
  Mesh m = makeLatheLoop({{0.25f, -1.0f}, {0.3f, -1.0f}, {0.3f, 1.0f}, {0.25f, 1.0f}}, segments);
  orientOutward(m);
  return m;
}

Mesh makeDish(int segments) {
  const int steps = std::max(4, segments / 4);
  std::vector<glm::vec2> profile;
  // Underside out to the rim, then the dished top back to the axis: one paraboloid 0.015 apart.
  auto dished = [](float r) { return 0.06f * (r / 0.5f) * (r / 0.5f); };
  for (int i = 0; i <= steps; ++i) {
    const float r = 0.5f * static_cast<float>(i) / static_cast<float>(steps);
    profile.push_back({r, dished(r)});
  }
  for (int i = steps; i >= 0; --i) {
    const float r = 0.5f * static_cast<float>(i) / static_cast<float>(steps);
    profile.push_back({r, 0.015f + dished(r)});
  }
  Mesh m = makeLathe(profile, segments);
  orientOutward(m);
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
