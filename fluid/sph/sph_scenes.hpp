#pragma once
// Measurement scenes for fluid/sph, shared by `fluiddemo simulate`, the tests and the benchmarks.
// Every scene is in metres with gravity 9.81 m/s^2 along -y, inside a closed box of six planes.
//
//   dambreak      column of width a, height height_ratio*a, thickness depth, against the wall
//                 x = 0, released at t = 0 into a box reaching length_ratio*a along +x; its
//                 viscosity key defaults to the least the spacing resolves (sph_scenes.cpp),
//                 the other scenes' to 0.01.
//   column        a block of water at rest filling the bottom of a box (hydrostatic test).
//   fountain      a nozzle at the centre of a basin shooting up; a drain in one corner of the
//                 floor removes particles; particle budget `budget`.
//   dambreak_box  SPlisHSPlasH's standard dam break: tank 4 x 3 x 1.5 m, a 1 m^3 block in a
//                 corner sampled as 29^3 = 24,389 particles of radius 1/60 m, viscosity 0.01.
//
// Keys (`--set key=value`): sphSceneKeys() lists every key with its default and meaning; unknown
// keys and unparsable or out-of-range values are errors naming the key and value.

#include "fluid/sph/sph.hpp"

#include <string>
#include <utility>
#include <vector>

namespace fluid {

struct SphSceneKey {
  std::string name;
  float value = 0.0f;
  std::string help;
};

struct SphScene {
  std::string name;
  SphWorld world;
  std::vector<SphSceneKey> keys;  // effective values after overrides
  glm::vec3 box_min{0.0f};        // the closed container
  glm::vec3 box_max{0.0f};
  float column_width = 0.0f;  // dam breaks: a (surge front is reported as max x / a)
  std::vector<std::shared_ptr<const SignedDistanceShape>> shapes;  // keeps the colliders alive
};

std::vector<std::string> sphSceneNames();
// Defaults and documentation of every key of `scene` (scene keys first, then solver keys).
SphStatus sphSceneKeys(const std::string& scene, std::vector<SphSceneKey>& out);
SphStatus makeSphScene(const std::string& scene, SphSolverKind solver,
                       const std::vector<std::pair<std::string, std::string>>& overrides, SphScene& out);

// Adds the six inward-facing planes of the closed box [lo, hi] as colliders.
void addSphContainer(SphScene& scene, glm::vec3 lo, glm::vec3 hi, const CollisionMaterial& material);

// Largest x of any particle (m), the dam-break surge front; 0 without particles.
float sphSurgeFront(const SphWorld& world);
// The q-quantile of the particles' x (q in [0, 1]; m), a surge front that single drops thrown ahead
// of the sheet do not move (q = 0.995 against Martin & Moyce); 0 without particles. `scratch` is
// caller-owned and reused.
float sphSurgeFrontQuantile(const SphWorld& world, double q, std::vector<float>& scratch);

}  // namespace fluid
