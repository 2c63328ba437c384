#pragma once
// The signed distance of a world point to a placed collider (its shape queried in collider space),
// for tests that check where particles ended.
#include "fluid/sph/sph.hpp"

#include <span>

namespace sph_test {

inline float distanceTo(const fluid::SphCollider& c, glm::vec3 x) {
  fluid::ColliderSample sample;
  const glm::vec3 local = fluid::toColliderSpace(c.pose, x);
  c.shape->query(std::span<const glm::vec3>(&local, 1), std::span<fluid::ColliderSample>(&sample, 1));
  return sample.distance;
}

}  // namespace sph_test
