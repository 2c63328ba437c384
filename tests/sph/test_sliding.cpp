// Floor-hugging flow: a layer of the game's water sliding down a slope (the water a blast throws
// along the basin floor) must neither stick nor be pushed. A slope of angle theta is a floor with
// gravity tilted by theta. The layer's mean velocity along the slope is its momentum over its mass:
// internal forces cancel, so only the floor's tangential reaction (friction) changes it.
//  - frictionless answer: v = g sin(theta) t;
//  - frictional answer for the wall friction nu taken as a Coulomb coefficient (the block the
//    friction could hold at most): v = g (sin(theta) - nu cos(theta)) t.
// The boundary pressure carries the layer's weight (it keeps water about a radius off the wall),
// so the friction of Kolb et al. 2004 §3.3.2 acts only at the contacts of the double check; the
// layer must stay between the two answers, and on a frictionless wall on the first.
#include "fluid/sph/sph_scenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

using namespace fluid;

constexpr float kPi = 3.14159265f;

struct Slide {
  double mean_speed = 0.0;  // m/s along the slope after `seconds`
  double frictionless = 0.0;
  double coulomb = 0.0;
  std::size_t contacts = 0;
};

// The game's water (content/scenes/fountain.json, game/world/sph_fluid.hpp): r = 4 cm, nu = 0.02,
// CFL 0.9, steps up to 1/60 s, density error 0.5 %, no force bound; stepped in calls of 1/120 s
// (60 Hz, two substeps). A layer 3 particles deep and 2.5 m long on a wide floor, walls far away.
Slide slideLayer(float theta_degrees, float friction, double seconds) {
  const float theta = theta_degrees * kPi / 180.0f;
  SphScene scene;
  SphWorld& world = scene.world;
  SphParams& p = world.params;
  p.particle_radius = 0.04f;
  p.viscosity = 0.02f;
  p.cfl = 0.9f;
  p.max_time_step = 0.0167f;
  p.max_density_error = 0.005f;
  p.force_bound = 0.0f;
  p.gravity = 9.81f * glm::vec3(std::sin(theta), -std::cos(theta), 0.0f);
  p.domain_min = glm::vec3(-31.0f, -1.0f, -1.0f);
  p.domain_max = glm::vec3(31.0f, 3.0f, 2.0f);
  CollisionMaterial wall;
  wall.friction = friction;
  wall.resilience = 0.0f;  // as the game's colliders (game/world/sph_fluid.cpp)
  addSphContainer(scene, glm::vec3(-30.0f, 0.0f, 0.0f), glm::vec3(30.0f, 2.0f, 0.96f), wall);
  addSphBlock(world, glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(2.5f, 0.24f, 0.96f));
  Slide out;
  const int calls = static_cast<int>(std::lround(seconds * 120.0));
  for (int k = 0; k < calls; ++k) {
    const SphStatus st = advanceSph(world, 1.0 / 120.0, [&](const SphStepStats& s) { out.contacts += s.collisions; });
    EXPECT_TRUE(st.ok()) << st.error;
  }
  double vx = 0.0;
  for (const glm::vec3& v : world.particles.velocity) vx += v.x;
  out.mean_speed = vx / static_cast<double>(world.particles.size());
  out.frictionless = 9.81 * std::sin(theta) * world.time;
  out.coulomb = 9.81 * (std::sin(theta) - friction * std::cos(theta)) * world.time;
  return out;
}

TEST(SphSliding, LayerOnAFrictionlessSlopeAcceleratesAsTheAnalyticAnswer) {
  const Slide s = slideLayer(20.0f, 0.0f, 1.0);
  std::printf("[ metric ] frictionless 20 deg slope: %.3f m/s after 1 s, analytic %.3f (%zu contacts)\n", s.mean_speed,
              s.frictionless, s.contacts);
  EXPECT_NEAR(s.mean_speed, s.frictionless, 0.01 * s.frictionless);
}

TEST(SphSliding, LayerWithTheGamesWallFrictionDoesNotStick) {
  for (const float theta : {10.0f, 20.0f}) {
    const Slide s = slideLayer(theta, 0.1f, 1.0);
    std::printf(
        "[ metric ] %g deg slope, wall friction 0.1: %.3f m/s after 1 s; frictionless %.3f, Coulomb %.3f (%zu "
        "contacts)\n",
        static_cast<double>(theta), s.mean_speed, s.frictionless, s.coulomb, s.contacts);
    EXPECT_GE(s.mean_speed, s.coulomb) << theta << " deg: slower than a Coulomb block of the wall's friction";
    EXPECT_LE(s.mean_speed, 1.01 * s.frictionless) << theta << " deg: faster than free sliding";
  }
}

}  // namespace
