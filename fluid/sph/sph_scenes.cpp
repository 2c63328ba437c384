#include "fluid/sph/sph_scenes.hpp"

#include "fluid/sph/analytic_colliders.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace fluid {
namespace {

struct KeySpec {
  const char* name;
  float value;
  float lo, hi;
  const char* help;
};

constexpr float kContainerResilience = 0.0f;

const KeySpec kDambreak[] = {
    {"width", 0.2f, 0.01f, 100.0f, "column width a (m)"},
    {"height_ratio", 2.0f, 0.1f, 10.0f, "column height / a"},
    {"depth", 0.05f, 0.0f, 100.0f, "thickness along z (m); 0 = 4 particle layers"},
    {"spacing", 0.0f, 0.0f, 10.0f, "particle spacing d = 2r (m); 0 = a/20"},
    {"length_ratio", 8.0f, 1.0f, 100.0f, "box length along +x / a (>= 8 for Martin & Moyce)"},
};
const KeySpec kColumn[] = {
    {"width", 0.1f, 0.01f, 100.0f, "column width along x (m)"},
    {"height", 0.2f, 0.01f, 100.0f, "water height (m)"},
    {"depth", 0.1f, 0.01f, 100.0f, "column depth along z (m)"},
    {"spacing", 0.01f, 1e-4f, 10.0f, "particle spacing d = 2r (m)"},
};
const KeySpec kFountain[] = {
    {"spacing", 0.02f, 1e-4f, 10.0f, "particle spacing d = 2r (m)"},
    {"basin_size", 1.0f, 0.1f, 100.0f, "basin width along x and z (m)"},
    {"basin_height", 1.5f, 0.1f, 100.0f, "basin wall height (m)"},
    {"nozzle_speed", 3.5f, 0.01f, 100.0f, "jet speed (m/s)"},
    {"nozzle_radius", 0.04f, 0.0f, 10.0f, "jet radius (m)"},
    {"nozzle_height", 0.25f, 0.0f, 100.0f,
     "nozzle above the floor (m); keep it above the water level (budget d^3 / basin_size^2), or new particles "
     "are inserted into the water"},
    {"rate", 3000.0f, 0.0f, 1e7f, "particles emitted per second"},
    {"budget", 10000.0f, 0.0f, 1e8f, "maximum particle count"},
    {"drain_size", 0.2f, 0.0f, 100.0f, "edge of the square drain in a floor corner (m)"},
};
const KeySpec kDambreakBox[] = {
    {"particle_radius", 1.0f / 60.0f, 1e-4f, 1.0f,
     "particle radius r (m); block is (1 m - 2r) / 2r particles per side"},
};
// Solver knobs, shared by all scenes. Each reads and writes one field, so its default is the
// field's own (SphParams{}, CollisionMaterial{}), written once there; only the walls' resilience
// is the scenes' choice: the measurement containers do not bounce (Kolb's epsilon = 0), where a
// CollisionMaterial's default of 0.3 suits the game's props.
struct SolverKnob {
  const char* name;
  float lo, hi;
  const char* help;
  float (*read)(const SphParams&, const CollisionMaterial&);
  void (*write)(SphParams&, CollisionMaterial&, float);
};
using M = CollisionMaterial;
const SolverKnob kSolver[] = {
    {"cfl", 0.01f, 1.0f, "CFL number: dt <= cfl * d / v_max", [](const SphParams& p, const M&) { return p.cfl; },
     [](SphParams& p, M&, float v) { p.cfl = v; }},
    {"force_bound", 0.0f, 1.0f, "DFSPH force condition |g| dt^2 <= force_bound * cfl * d; 0 = off",
     [](const SphParams& p, const M&) { return p.force_bound; }, [](SphParams& p, M&, float v) { p.force_bound = v; }},
    {"warm_start", 0.0f, 1.0f, "DFSPH warm start of the constant-density solve (1 = on, 0 = off)",
     [](const SphParams& p, const M&) { return p.warm_start ? 1.0f : 0.0f; },
     [](SphParams& p, M&, float v) { p.warm_start = v != 0.0f; }},
    {"max_dt", 1e-7f, 1.0f, "upper bound of the time step (s)",
     [](const SphParams& p, const M&) { return p.max_time_step; },
     [](SphParams& p, M&, float v) {
       p.max_time_step = v;
       p.min_time_step = std::min(p.min_time_step, v);
     }},
    {"viscosity", 0.0f, 100.0f, "kinematic viscosity nu of the Laplacian term (m^2/s)",
     [](const SphParams& p, const M&) { return p.viscosity; }, [](SphParams& p, M&, float v) { p.viscosity = v; }},
    {"xsph", 0.0f, 1.0f, "XSPH epsilon", [](const SphParams& p, const M&) { return p.xsph; },
     [](SphParams& p, M&, float v) { p.xsph = v; }},
    {"density_error", 1e-7f, 1.0f, "DFSPH: mean density error tolerance (0.0005 = 0.05 %)",
     [](const SphParams& p, const M&) { return p.max_density_error; },
     [](SphParams& p, M&, float v) { p.max_density_error = v; }},
    {"divergence_error", 1e-7f, 1.0f, "DFSPH: divergence error tolerance",
     [](const SphParams& p, const M&) { return p.max_divergence_error; },
     [](SphParams& p, M&, float v) { p.max_divergence_error = v; }},
    {"min_iterations", 0.0f, 10000.0f, "DFSPH: minimum constant-density iterations per step (paper: 2)",
     [](const SphParams& p, const M&) { return static_cast<float>(p.min_iterations); },
     [](SphParams& p, M&, float v) { p.min_iterations = static_cast<int>(v); }},
    {"max_iterations", 1.0f, 10000.0f, "DFSPH: iteration cap per solve",
     [](const SphParams& p, const M&) { return static_cast<float>(p.max_iterations); },
     [](SphParams& p, M&, float v) { p.max_iterations = static_cast<int>(v); }},
    // c_s = 0 asks for the scene's rule (10 x its expected top speed), set after the scene is built.
    {"sound_speed", 0.0f, 1e5f, "WCSPH: c_s (m/s); 0 = 10 x the scene's expected max speed",
     [](const SphParams&, const M&) { return 0.0f; }, [](SphParams& p, M&, float v) { p.sound_speed = v; }},
    {"artificial_viscosity", 0.0f, 10.0f, "WCSPH: B&T alpha",
     [](const SphParams& p, const M&) { return p.artificial_viscosity; },
     [](SphParams& p, M&, float v) { p.artificial_viscosity = v; }},
    {"friction", 0.0f, 1.0f, "wall friction (Kolb 2004 nu)", [](const SphParams&, const M& m) { return m.friction; },
     [](SphParams&, M& m, float v) { m.friction = v; }},
    {"resilience", 0.0f, 1.0f, "wall resilience (Kolb 2004 epsilon)",
     [](const SphParams&, const M&) { return kContainerResilience; },
     [](SphParams&, M& m, float v) { m.resilience = v; }},
    {"max_speed", 0.0f, 1e6f, "velocity clamp (m/s), 0 = off", [](const SphParams& p, const M&) { return p.max_speed; },
     [](SphParams& p, M&, float v) { p.max_speed = v; }},
};

// Solver keys whose default differs in one scene. The dam break reproduces Martin & Moyce's
// experiment (1952), which collapsed columns of water. The shared 0.01 m^2/s is SPlisHSPlasH's
// dambreak_box value for a 1 m block; on a 5.7 cm column it is a Reynolds number of about 6
// (honey) and the front lags the experiment by a third. Water's 1.0e-6 m^2/s is far below what the
// particles resolve: a shear layer thinner than the kernel is not represented, and without that
// dissipation both solvers gain energy where the surge hits the far wall (tests/sph, KE above the
// potential energy released: +6 % DFSPH, +76 % WCSPH at a = 0.1 m, d = 0.01 m). So the default is
// the least viscosity the spacing resolves, a cell Reynolds number U d / nu = kCellReynolds with U =
// sqrt(2 g H) the column's free-fall speed (and never below water's). The front is insensitive to
// the choice within a factor of two either way (mean error against the experiment 2.3 % at 8, 2.1 %
// at 4, 4.4 % at 2: tests/sph/test_dambreak_experiment.cpp); energy holds over that range.
// At 0.01 m^2/s the explicit viscosity's bound (0.125 d^2 / nu, time_step.cpp) was also the
// binding step there, where the Laplacian term's fastest (checkerboard) mode is multiplied by
// about -0.8 a step instead of decaying, so the front depended on how the steps fell: at 0.3 s
// 7.1 a in 1 ms calls and 5.5 a on the solver's own steps (simulate's route since 064f382); with
// steps at half that bound it converges to 5.13 a. At U d / 4 the CFL bound binds first.
constexpr float kAutomatic = -1.0f;  // a default computed from the scene (the range check skips it)
constexpr float kCellReynolds = 4.0f;
constexpr float kWaterViscosity = 1.0e-6f;  // m^2/s at 20 C
struct SceneDefault {
  const char* scene;
  const char* key;
  float value;
  const char* help;
};
constexpr const char* kDambreakViscosityHelp =
    "kinematic viscosity nu (m^2/s); auto: the least the spacing resolves, sqrt(2 g H) d / 4 for water "
    "height H (at least water's 1e-6)";
const SceneDefault kSceneDefaults[] = {
    {"dambreak", "viscosity", kAutomatic, kDambreakViscosityHelp},
};

float automaticViscosity(float water_height, float spacing) {
  return std::max(kWaterViscosity, std::sqrt(2.0f * 9.81f * water_height) * spacing / kCellReynolds);
}

std::vector<KeySpec> allSpecs(const std::string& scene, std::span<const KeySpec> specs) {
  std::vector<KeySpec> keys(specs.begin(), specs.end());
  const SphParams defaults;
  const CollisionMaterial material;
  for (const SolverKnob& knob : kSolver)
    keys.push_back({knob.name, knob.read(defaults, material), knob.lo, knob.hi, knob.help});
  for (const SceneDefault& d : kSceneDefaults)
    if (scene == d.scene)
      for (KeySpec& k : keys)
        if (std::string(k.name) == d.key) {
          k.value = d.value;
          k.help = d.help;
        }
  return keys;
}

std::span<const KeySpec> sceneSpecs(const std::string& scene) {
  if (scene == "dambreak") return kDambreak;
  if (scene == "column") return kColumn;
  if (scene == "fountain") return kFountain;
  if (scene == "dambreak_box") return kDambreakBox;
  return {};
}

std::string joinNames() {
  std::string s;
  for (const std::string& n : sphSceneNames()) s += (s.empty() ? "" : "|") + n;
  return s;
}

}  // namespace

std::vector<std::string> sphSceneNames() { return {"dambreak", "column", "fountain", "dambreak_box"}; }

SphStatus sphSceneKeys(const std::string& scene, std::vector<SphSceneKey>& out) {
  out.clear();
  const auto specs = sceneSpecs(scene);
  if (specs.empty()) return {"unknown scene '" + scene + "' (expected " + joinNames() + ")"};
  for (const KeySpec& k : allSpecs(scene, specs)) out.push_back({k.name, k.value, k.help});
  return {};
}

void addSphContainer(SphScene& scene, glm::vec3 lo, glm::vec3 hi, const CollisionMaterial& material) {
  for (int a = 0; a < 3; ++a) {
    for (int side = 0; side < 2; ++side) {
      glm::vec3 n(0.0f);
      n[a] = side == 0 ? 1.0f : -1.0f;
      const float offset = side == 0 ? lo[a] : -hi[a];
      auto shape = std::make_shared<PlaneShape>(n, offset);
      scene.shapes.push_back(shape);
      SphCollider c;
      c.shape = shape;
      c.material = material;
      c.integrate_pose = false;
      // An exact distance that never moves: the end-of-step check may skip particles whose step
      // stayed farther from the wall than they moved (a plane's normal never flips, so the result
      // is the same as querying them).
      c.lipschitz_distance = true;
      scene.world.colliders.push_back(c);
    }
  }
}

float sphSurgeFront(const SphWorld& world) {
  float front = 0.0f;
  for (const glm::vec3& p : world.particles.position) front = std::max(front, p.x);
  return front;
}

float sphSurgeFrontQuantile(const SphWorld& world, double q, std::vector<float>& scratch) {
  const auto& position = world.particles.position;
  if (position.empty()) return 0.0f;
  scratch.resize(position.size());
  for (std::size_t i = 0; i < position.size(); ++i) scratch[i] = position[i].x;
  const std::size_t k =
      static_cast<std::size_t>(std::floor(std::clamp(q, 0.0, 1.0) * static_cast<double>(scratch.size() - 1)));
  std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(k), scratch.end());
  return scratch[k];
}

SphStatus makeSphScene(const std::string& scene, SphSolverKind solver,
                       const std::vector<std::pair<std::string, std::string>>& overrides, SphScene& out) {
  out = SphScene{};
  out.name = scene;
  const auto specs = sceneSpecs(scene);
  if (specs.empty()) return {"unknown scene '" + scene + "' (expected " + joinNames() + ")"};
  std::vector<KeySpec> keys = allSpecs(scene, specs);
  for (const auto& [name, text] : overrides) {
    auto it = std::find_if(keys.begin(), keys.end(), [&](const KeySpec& k) { return name == k.name; });
    if (it == keys.end()) {
      std::string valid;
      for (const KeySpec& k : keys) valid += (valid.empty() ? "" : ", ") + std::string(k.name);
      return {"unknown key '" + name + "' for scene " + scene + " (valid: " + valid + ")"};
    }
    errno = 0;
    char* end = nullptr;
    const float v = std::strtof(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v))
      return {"key '" + name + "': '" + text + "' is not a finite number"};
    if (v < it->lo || v > it->hi)
      return {"key '" + name + "' = " + text + " is out of range [" + std::to_string(it->lo) + ", " +
              std::to_string(it->hi) + "]"};
    it->value = v;
  }
  auto get = [&](const char* name) {
    for (const KeySpec& k : keys)
      if (std::string(k.name) == name) return k.value;
    return 0.0f;
  };
  for (const KeySpec& k : keys) out.keys.push_back({k.name, k.value, k.help});

  SphWorld& w = out.world;
  SphParams& p = w.params;
  p.solver = solver;
  CollisionMaterial material;
  for (const SolverKnob& knob : kSolver) knob.write(p, material, get(knob.name));
  p.min_iterations = std::min(p.min_iterations, p.max_iterations);
  float expected_speed = 1.0f;

  if (scene == "dambreak") {
    const float a = get("width");
    const float height = get("height_ratio") * a;
    const float d = get("spacing") > 0.0f ? get("spacing") : a / 20.0f;
    if (p.viscosity == kAutomatic) p.viscosity = automaticViscosity(height, d);
    const float depth = get("depth") > 0.0f ? get("depth") : 4.0f * d;
    p.particle_radius = 0.5f * d;
    out.column_width = a;
    out.box_min = glm::vec3(0.0f);
    out.box_max = glm::vec3(get("length_ratio") * a, 1.5f * height, depth);
    addSphBlock(w, glm::vec3(0.0f), glm::vec3(a, height, depth));
    expected_speed = std::sqrt(2.0f * 9.81f * height);
  } else if (scene == "column") {
    const float d = get("spacing");
    p.particle_radius = 0.5f * d;
    out.box_min = glm::vec3(0.0f);
    out.box_max = glm::vec3(get("width"), 2.0f * get("height"), get("depth"));
    addSphBlock(w, glm::vec3(0.0f), glm::vec3(get("width"), get("height"), get("depth")));
    expected_speed = std::sqrt(2.0f * 9.81f * get("height"));
  } else if (scene == "fountain") {
    const float d = get("spacing");
    const float b = get("basin_size");
    p.particle_radius = 0.5f * d;
    p.max_particles = static_cast<std::size_t>(get("budget"));
    out.box_min = glm::vec3(-0.5f * b, 0.0f, -0.5f * b);
    out.box_max = glm::vec3(0.5f * b, get("basin_height"), 0.5f * b);
    SphEmitter e;
    e.position = glm::vec3(0.0f, std::max(get("nozzle_height"), 2.0f * d), 0.0f);
    e.direction = glm::vec3(0.0f, 1.0f, 0.0f);
    e.speed = get("nozzle_speed");
    e.radius = get("nozzle_radius");
    e.rate = get("rate");
    w.emitters.push_back(e);
    const float ds = get("drain_size");
    if (ds > 0.0f)
      w.sinks.push_back({out.box_min - glm::vec3(1.0f), glm::vec3(out.box_min.x + ds, 1.5f * d, out.box_min.z + ds)});
    expected_speed = e.speed;
  } else {  // dambreak_box
    const float r = get("particle_radius");
    p.particle_radius = r;
    out.box_min = glm::vec3(0.0f);
    out.box_max = glm::vec3(4.0f, 3.0f, 1.5f);
    out.column_width = 1.0f;
    addSphBlock(w, glm::vec3(0.0f), glm::vec3(1.0f - 2.0f * r));  // 29^3 particles at r = 1/60
    expected_speed = std::sqrt(2.0f * 9.81f * 1.0f);
  }
  for (SphSceneKey& k : out.keys)
    if (k.name == "viscosity") k.value = p.viscosity;  // the effective value where it was computed
  p.sound_speed = get("sound_speed") > 0.0f ? get("sound_speed") : 10.0f * expected_speed;
  const glm::vec3 margin(4.0f * p.particle_radius);
  p.domain_min = out.box_min - margin;
  p.domain_max = out.box_max + margin;
  addSphContainer(out, out.box_min, out.box_max, material);
  if (SphStatus s = validateSphParams(p); !s.ok()) return s;
  return {};
}

}  // namespace fluid
