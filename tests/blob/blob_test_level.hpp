#pragma once
// A small analytic level for the blob tests: ground with a sewer pipe, a wall to coat, thin walls.
#include "fluid/blob/behaviour.hpp"
#include "fluid/blob/blob.hpp"
#include "fluid/sph/analytic_colliders.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace blobtest {

// Ground y < 0 with a vertical pipe of radius `pipe` around the y axis through it: the solid is
// {y < 0} ∩ {x² + z² > pipe²}, distance max(y, pipe − r) (exact outside the corner region, and
// 1-Lipschitz everywhere), normal of the winning term.
class SewerGround final : public fluid::SignedDistanceShape {
 public:
  explicit SewerGround(float pipe) : pipe_(pipe) {}
  void query(std::span<const glm::vec3> pts, std::span<fluid::ColliderSample> out) const override {
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const glm::vec3 p = pts[i];
      const float r = std::sqrt(p.x * p.x + p.z * p.z);
      const float d_pipe = pipe_ - r;
      fluid::ColliderSample s;
      s.valid = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      if (p.y >= d_pipe) {
        s.distance = p.y;
        s.normal = {0.0f, 1.0f, 0.0f};
      } else {
        s.distance = d_pipe;
        s.normal = r > 1e-6f ? glm::vec3(-p.x / r, 0.0f, -p.z / r) : glm::vec3(1.0f, 0.0f, 0.0f);
      }
      out[i] = s;
    }
  }

 private:
  float pipe_;
};

inline fluid::BlobCollider collider(std::shared_ptr<const fluid::SignedDistanceShape> shape,
                                    glm::vec3 at = glm::vec3(0.0f)) {
  fluid::BlobCollider c;
  c.shape = std::move(shape);
  c.pose.translation = at;
  return c;
}

inline fluid::BlobCollider ground() {
  return collider(std::make_shared<fluid::PlaneShape>(glm::vec3(0.0f, 1.0f, 0.0f), 0.0f));
}

// A solid box wall: faces x = x0 (toward the blob) .. x0 + thickness, y in [-1, height] (founded in
// the ground, so nothing slips under it), z in [-w, w].
inline fluid::BlobCollider wall(float x0, float thickness, float height = 3.0f, float half_width = 3.0f) {
  return collider(std::make_shared<fluid::BoxShape>(glm::vec3(0.5f * thickness, 0.5f * (height + 1.0f), half_width)),
                  glm::vec3(x0 + 0.5f * thickness, 0.5f * (height - 1.0f), 0.0f));
}

// Smallest signed distance of any particle to collider c (world query).
inline float minDistance(const fluid::BlobWorld& w, std::size_t c) {
  float m = 1e30f;
  const fluid::BlobCollider& col = w.colliders[c];
  for (const glm::vec3& x : w.particles.position) {
    const glm::vec3 local = fluid::toColliderSpace(col.pose, x);
    fluid::ColliderSample s;
    col.shape->query({&local, 1}, {&s, 1});
    if (s.valid) m = std::min(m, s.distance);
  }
  return m;
}

// A world with the default 1,000 particles resting on `at`.
// A blast by the game's law (fluid/core/blast.hpp) whose push on a particle at its core is
// `core_speed` (m/s): impulse_at_1m = core_speed core_radius^2 / (A / m) with the particle's
// cross-section A = pi r^2 and mass m. Beyond the core it falls off as 1/r^2, tapering to 0 at `reach`.
inline fluid::Blast blastOfSpeed(const fluid::BlobWorld& w, glm::vec3 centre, float core_speed, float reach,
                                 float core_radius = 0.25f) {
  const float r = fluid::blobParticleRadius(w.params);
  const float area_over_mass = 3.14159265f * r * r / fluid::blobParticleMass(w.params);
  return {centre, core_speed * core_radius * core_radius / area_over_mass, core_radius, reach};
}

inline fluid::BlobWorld restingBlob(glm::vec3 at = glm::vec3(0.0f)) {
  fluid::BlobWorld w;
  const fluid::BlobStatus st = fluid::initBlob(w, at + glm::vec3(0.0f, 0.45f, 0.0f));
  EXPECT_TRUE(st.ok()) << st.error;
  return w;
}

// Runs `behaviour` for up to `seconds`; returns the time (s) its goal was first reached, or -1.
// Checks every step that nothing is NaN, no particle is lost and speeds stay bounded.
inline float runUntilGoal(fluid::BlobWorld& w, const fluid::BlobBehaviour& b, float seconds,
                          glm::vec3 target = glm::vec3(0.0f), bool stop_at_goal = true) {
  fluid::startBlobBehaviour(w, b, target);
  const std::size_t n = w.particles.size();
  float reached = -1.0f;
  const int steps = static_cast<int>(std::lround(seconds / w.params.step));
  for (int s = 0; s < steps; ++s) {
    fluid::updateBlobBehaviour(w, b, target, w.params.step);
    const fluid::BlobStatus st = fluid::stepBlob(w);
    EXPECT_TRUE(st.ok()) << st.error;
    if (!st.ok()) return -1.0f;
    EXPECT_EQ(w.particles.size(), n);
    if (reached < 0.0f && fluid::blobGoalReached(w, b, target)) {
      reached = static_cast<float>(s + 1) * w.params.step;
      if (stop_at_goal) break;
    }
  }
  EXPECT_TRUE(fluid::blobAllFinite(w.particles));
  EXPECT_LE(fluid::blobMaxSpeed(w.particles.velocity), 1.0001f * w.params.max_speed);
  return reached;
}

}  // namespace blobtest
