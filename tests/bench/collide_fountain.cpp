// The fountain level's baked depth-map colliders (content/colliders/fountain.colliders, Kolb et
// al. 2004 §4) measured three ways, for docs/collide.md:
//   1. per model (ground, basin, statue) against the exact distance to the same OBJ mesh
//      (fluid::MeshDistance): the default six axis maps as sprite_particles bakes them today,
//      and the recipe of content/colliders;
//   2. the whole fountain (ground ∪ basin ∪ statue, baked) against the analytic FountainShape
//      (tests/support/fountain_shape.hpp, the reference), and the exact meshes against it
//      (how far the OBJ models themselves are from the CSG cylinders);
//   3. the SPH step cost of the boundary: the game's SPH fountain (game::initSphFluid: the baked
//      colliders, each a fluid::ReachCulledCollider), the same colliders queried by every particle,
//      the analytic FountainShape, and the baked colliders culled to their reach boxes only (the
//      grid of one cell: the game before the reach grid), from the same filled state; variants
//      0, 1, 2, 3 in that order.
// Usage: bench_collide_fountain [--points N] [--frames N] [--threads 1,2] [--variants 0,3,1,2] [--tables 0|1]
// (--variants picks the SPH rows by number, see 3.; --tables 0 skips the accuracy tables.)
#include "fluid/collide/collider_cache.hpp"
#include "game/world/collider_model.hpp"
#include "game/scene/scene_config.hpp"
#include "game/world/sph_fluid.hpp"
#include "game/world/world.hpp"
#include "load_average.hpp"
#include "tests/support/fountain_shape.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
const fs::path kContent = fs::path(FLUIDDEMO_SOURCE_DIR) / "content";
// The game's SPH support: 4 r (fluid::SphParams) with the fountain scene's particle_radius, set in main.
float support_radius = 0.0f;

struct Model {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  fluid::MeshView view() const { return {positions, indices}; }
};

struct Errors {
  std::size_t points = 0, wrong = 0, band = 0, beyond_reach = 0;
  double sum_d = 0.0, max_d = 0.0, deepest_wrong = 0.0;
};

// `got` against `reference` on `points`: misclassification over all points; beyond-reach count
// and |Δd| over the band |d_ref| < support_radius.
Errors compare(const std::vector<fluid::ColliderSample>& reference, const std::vector<fluid::ColliderSample>& got) {
  Errors e;
  e.points = reference.size();
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const bool in_ref = reference[k].distance < 0.0f, in_got = got[k].valid && got[k].distance < 0.0f;
    e.wrong += in_ref != in_got;
    if (in_ref != in_got) e.deepest_wrong = std::max(e.deepest_wrong, std::fabs(double(reference[k].distance)));
    if (std::fabs(reference[k].distance) >= support_radius) continue;
    ++e.band;
    if (!got[k].valid) {
      ++e.beyond_reach;
      continue;
    }
    const double dd = std::fabs(double(got[k].distance) - reference[k].distance);
    e.sum_d += dd;
    e.max_d = std::max(e.max_d, dd);
  }
  return e;
}

std::vector<glm::vec3> uniformPoints(glm::vec3 lo, glm::vec3 hi, std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> points(count);
  for (glm::vec3& p : points) p = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
  return points;
}

// Union of static colliders (CSG): the smallest valid distance; invalid where all are.
void unionQuery(const std::vector<const fluid::SignedDistanceShape*>& shapes, const std::vector<glm::vec3>& points,
                std::vector<fluid::ColliderSample>& out) {
  std::vector<fluid::ColliderSample> part(points.size());
  out.assign(points.size(), fluid::ColliderSample{});
  for (std::size_t k = 0; k < out.size(); ++k) out[k].valid = false;
  for (const fluid::SignedDistanceShape* s : shapes) {
    fluid::queryParallel(*s, points, part);
    for (std::size_t k = 0; k < out.size(); ++k)
      if (part[k].valid && (!out[k].valid || part[k].distance < out[k].distance)) out[k] = part[k];
  }
}

// A map list for a table cell: as written when short, else its depth cubes counted
// ("axes + 8 cubes@…:128"), the full list being the recipe's in content/colliders.
std::string shortMapList(const std::string& maps) {
  if (maps.size() <= 40) return maps;
  std::string kept, cube_resolution;
  int cubes = 0;
  std::size_t start = 0;
  while (start <= maps.size()) {
    const std::size_t comma = std::min(maps.find(',', start), maps.size());
    const std::string token = maps.substr(start, comma - start);
    if (token.rfind("cube@", 0) == 0) {
      ++cubes;
      const std::size_t last = token.rfind(':');
      if (std::count(token.begin(), token.end(), ':') == 4) cube_resolution = token.substr(last + 1);
    } else if (!token.empty()) {
      kept += (kept.empty() ? "" : ",") + token;
    }
    start = comma + 1;
  }
  if (cubes > 0)
    kept += " + " + std::to_string(cubes) + (cubes == 1 ? " cube" : " cubes") +
            (cube_resolution.empty() ? "" : " (" + cube_resolution + "² faces)");
  return kept;
}

void printErrors(const std::string& head, const Errors& e, const std::string& tail) {
  std::printf("| %s | %.3f | %.4f | %zu | %zu | %.4f | %.3f |%s\n", head.c_str(),
              100.0 * double(e.wrong) / double(e.points), e.deepest_wrong, e.band, e.beyond_reach,
              e.band > e.beyond_reach ? e.sum_d / double(e.band - e.beyond_reach) : 0.0, e.max_d, tail.c_str());
}

bool loadModels(std::vector<fluid::LevelColliderEntry>& entries, std::vector<Model>& models) {
  if (const fluid::CacheStatus st = fluid::readLevelColliders(kContent / "colliders" / "fountain.colliders", entries);
      !st.ok()) {
    std::fprintf(stderr, "bench_collide_fountain: %s\n", st.error.c_str());
    return false;
  }
  const fluid::ModelLoader loader = game::colliderModelLoader();
  for (const fluid::LevelColliderEntry& e : entries) {
    Model m{e.name, {}, {}};
    std::string error;
    if (!loader(kContent / e.model, m.positions, m.indices, error)) {
      std::fprintf(stderr, "bench_collide_fountain: %s\n", error.c_str());
      return false;
    }
    models.push_back(std::move(m));
  }
  return true;
}

int perModelTable(const std::vector<fluid::LevelColliderEntry>& entries, const std::vector<Model>& models,
                  std::size_t count) {
  std::printf(
      "| model | maps | depth maps | margin (m) | misclass %% | deepest misclassified (m) | points with \\|d\\| < %.2f "
      "m | "
      "beyond reach there | mean \\|Δd\\| there (m) | max \\|Δd\\| there (m) | bytes |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n",
      support_radius);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const fluid::Bounds b = fluid::meshBounds(models[m].view());
    // The ground is an 80 m slab: measure it over the fountain's courtyard, not all of it.
    const bool ground = entries[m].name == "ground";
    const glm::vec3 size = b.hi - b.lo, pad(0.1f * std::max({size.x, size.y, size.z}));
    const glm::vec3 lo = ground ? glm::vec3(-4.0f, -1.2f, -4.0f) : b.lo - pad;
    const glm::vec3 hi = ground ? glm::vec3(4.0f, 0.5f, 4.0f) : b.hi + pad;
    const std::vector<glm::vec3> points = uniformPoints(lo, hi, count, 42);
    const fluid::MeshDistance exact(models[m].view());
    std::vector<fluid::ColliderSample> reference(count), got(count);
    fluid::queryParallel(exact, points, reference);
    // Today's in-memory bake (game/world/sprite_particles.cpp), then the shipped recipe.
    fluid::BakeRecipe today = entries[m].recipe;
    today.maps = ground ? "y" : "axes";
    today.margin = 0.0f;
    for (const fluid::BakeRecipe& recipe : {today, entries[m].recipe}) {
      std::vector<fluid::MapSpec> specs;
      std::string error;
      fluid::DepthMapCollider collider;
      if (!fluid::recipeMapSpecs(recipe, b, specs, error) ||
          !fluid::bakeDepthMaps(models[m].view(), specs, {recipe.normal_resolution, 0}, collider).ok()) {
        std::fprintf(stderr, "bench_collide_fountain: %s: bake failed %s\n", entries[m].name.c_str(), error.c_str());
        return 1;
      }
      fluid::queryParallel(collider, points, got);
      char tail[96];
      std::snprintf(tail, sizeof tail, ", %d² | %d | %.2f", recipe.resolution, collider.depthMapCount(),
                    static_cast<double>(recipe.margin));
      const std::string head = entries[m].name + " | " + shortMapList(recipe.maps) + tail;
      char bytes[32];
      std::snprintf(bytes, sizeof bytes, " %zu |", collider.bytes());
      printErrors(head, compare(reference, got), bytes);
    }
  }
  std::printf("\n");
  return 0;
}

int fountainTable(const std::vector<fluid::CachedCollider>& baked, const std::vector<Model>& models,
                  std::size_t count) {
  const fountainref::FountainShape analytic;
  const std::vector<glm::vec3> points =
      uniformPoints(glm::vec3(-3.6f, -0.3f, -3.6f), glm::vec3(3.6f, 2.8f, 3.6f), count, 7);
  std::vector<fluid::ColliderSample> reference(count), got;
  fluid::queryParallel(analytic, points, reference);
  std::printf(
      "| collider | misclass %% | deepest misclassified (m) | points with \\|d\\| < %.2f m | beyond reach there | "
      "mean \\|Δd\\| there (m) | max \\|Δd\\| there (m) |\n|---|---|---|---|---|---|---|\n",
      support_radius);
  std::vector<std::unique_ptr<fluid::MeshDistance>> exact;
  std::vector<const fluid::SignedDistanceShape*> exact_shapes, baked_shapes;
  for (const Model& m : models) exact.push_back(std::make_unique<fluid::MeshDistance>(m.view()));
  for (const auto& e : exact) exact_shapes.push_back(e.get());
  for (const fluid::CachedCollider& c : baked) baked_shapes.push_back(&c.collider);
  unionQuery(exact_shapes, points, got);
  printErrors("exact distance to the OBJ meshes (the models' own difference)", compare(reference, got), "");
  unionQuery(baked_shapes, points, got);
  printErrors("baked content/colliders (" + std::to_string(baked.size()) + " colliders)", compare(reference, got), "");
  std::printf("\n");
  return 0;
}

bool buildFountain(game::SphFluid& out, std::string& error) {
  game::SceneConfig scene;
  game::SceneStatus st = game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene);
  const game::SectionConfig* section = st.ok() ? scene.effect("sph_fluid") : nullptr;
  if (section == nullptr) {
    error = st.ok() ? "fountain.json has no sph_fluid effect" : st.error;
    return false;
  }
  game::SphFluidParams params;
  std::shared_ptr<const game::LevelColliders> colliders;
  return game::sphParamsFrom(*section, params, error) && game::ensureFountainColliders(kContent, colliders, error) &&
         game::initSphFluid(out, params, game::FountainGeometry{}, colliders, game::sceneGravity(scene), error);
}

// The timed frames of one variant, out of line so a profiler can collect just them
// (valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*timedFrames*').
[[gnu::noinline]] bool timedFrames(game::SphFluid& f, int frames, std::vector<double>& ms, double& steps,
                                   double& collisions, std::size_t& emitted, std::size_t& pumped,
                                   std::size_t& removed) {
  for (int frame = 0; frame < frames; ++frame) {
    double frame_ms = 0.0;
    if (!game::stepSphFluid(f, 1.0 / 60.0, [&](const fluid::SphStepStats& x) {
          frame_ms += x.step_ms;
          steps += 1.0;
          collisions += static_cast<double>(x.collisions);
          emitted += x.emitted;
          pumped += x.pumped;
          removed += x.removed;
        }))
      return false;
    ms.push_back(frame_ms);
  }
  return true;
}

int sphCostTable(const std::vector<fluid::CachedCollider>& baked, int frames, const std::vector<int>& threads,
                 const std::vector<int>& variants) {
  game::SphFluid filled;
  std::string error;
  if (!buildFountain(filled, error)) {
    std::fprintf(stderr, "bench_collide_fountain: %s\n", error.c_str());
    return 1;
  }
  // The scene's settled pool at load (issue 33: the pump's water starts in the basin); a scene that
  // starts with less is filled with the game's colliders until the budget is nearly reached.
  const double target = 0.9 * static_cast<double>(filled.world.params.max_particles);
  while (static_cast<double>(filled.world.particles.size()) < target && filled.world.time < 60.0)
    if (!game::stepSphFluid(filled, 1.0 / 60.0)) {
      std::fprintf(stderr, "bench_collide_fountain: %s\n", filled.error.c_str());
      return 1;
    }
  // The level's colliders are the first `parts` of the world's (game::initSphFluid): the game's
  // (baked, each culled to its reach box), the same baked colliders queried by every particle,
  // and the analytic FountainShape (1-Lipschitz: end-of-step queries of far particles skipped).
  const std::size_t parts = baked.size();
  // The game's parts (fluid::ReachCulledCollider), and the same with a one-cell grid: culled to
  // the reach box only (what the game did before the grid). How many of the filled state's
  // particles each part culls, against how many its full sample puts beyond the support.
  std::vector<fluid::SphCollider> box_only;
  std::printf(
      "| part | grid cells | cell (m) | far cells | build (ms) | particles culled | beyond the support |\n"
      "|---|---|---|---|---|---|---|\n");
  for (std::size_t k = 0; k < parts; ++k) {
    const auto* rc = dynamic_cast<const fluid::ReachCulledCollider*>(filled.world.colliders[k].shape.get());
    if (rc == nullptr) {
      std::fprintf(stderr, "bench_collide_fountain: part %zu is not a ReachCulledCollider\n", k);
      return 1;
    }
    fluid::ReachGridDesc desc;
    desc.reach = support_radius;
    const auto t0 = std::chrono::steady_clock::now();
    const fluid::ReachCulledCollider rebuilt(std::make_shared<fluid::DepthMapCollider>(baked[k].collider), rc->box(),
                                             desc);
    const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    desc.max_cells = 1;
    fluid::SphCollider s = filled.world.colliders[k];
    s.shape = std::make_shared<fluid::ReachCulledCollider>(std::make_shared<fluid::DepthMapCollider>(baked[k].collider),
                                                           rc->box(), desc);
    box_only.push_back(s);
    std::size_t culled = 0, beyond = 0;
    for (const glm::vec3& p : filled.world.particles.position) {
      culled += rc->culled(p);
      const fluid::ColliderSample full = baked[k].collider.sample(p);
      beyond += !full.valid || full.distance >= support_radius;
    }
    const glm::ivec3 d = rc->cells();
    std::printf("| %s | %d×%d×%d | %.3f×%.3f×%.3f | %.1f %% | %.0f | %zu of %zu | %zu |\n", baked[k].name.c_str(), d.x,
                d.y, d.z, rc->cell().x, rc->cell().y, rc->cell().z, 100.0 * rc->farFraction(), build_ms, culled,
                filled.world.particles.size(), beyond);
  }
  std::printf("\n");
  const fluid::SphCollider level = filled.world.colliders.front();
  std::vector<fluid::SphCollider> unculled, analytic(1, level);
  for (const fluid::CachedCollider& c : baked) {
    fluid::SphCollider s = level;
    s.shape = std::make_shared<fluid::DepthMapCollider>(c.collider);
    unculled.push_back(s);
  }
  analytic[0].shape = std::make_shared<fountainref::FountainShape>();
  analytic[0].lipschitz_distance = true;
  const char* names[] = {"baked, culled by each part's reach grid (the game)", "baked, every particle queries all 3",
                         "analytic FountainShape (1 collider, Lipschitz skip)",
                         "baked, culled to each part's reach box only (before the grid)"};
  std::printf(
      "| SPH boundary (threads) | particles | ms per 1/60 s frame (median) | worst frame (ms) | SPH steps per frame | "
      "collisions per step | taken by the pump | given back at the nozzle | removed |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  for (const int t : threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(t));
    for (const int variant : variants) {
      game::SphFluid f = filled;
      if (variant > 0) {
        const std::vector<fluid::SphCollider>& with = variant == 1 ? unculled : variant == 2 ? analytic : box_only;
        f.world.colliders.erase(f.world.colliders.begin(), f.world.colliders.begin() + static_cast<long>(parts));
        f.world.colliders.insert(f.world.colliders.begin(), with.begin(), with.end());
      }
      std::vector<double> ms;
      double steps = 0.0, collisions = 0.0;
      std::size_t emitted = 0, pumped = 0, removed = 0;
      if (!timedFrames(f, frames, ms, steps, collisions, emitted, pumped, removed)) {
        std::fprintf(stderr, "bench_collide_fountain: %s\n", f.error.c_str());
        return 1;
      }
      std::vector<double> sorted = ms;
      std::sort(sorted.begin(), sorted.end());
      std::printf("| %s (%d) | %zu | %.2f | %.2f | %.1f | %.0f | %zu | %zu | %zu |\n", names[variant], t,
                  f.world.particles.size(), sorted[sorted.size() / 2], sorted.back(), steps / frames,
                  collisions / std::max(steps, 1.0), pumped, emitted, removed);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t points = 200000;
  int frames = 60;
  std::vector<int> threads{1};
  std::vector<int> variants{0, 3, 1, 2};
  bool tables = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--points")
      points = std::strtoull(argv[i + 1], nullptr, 10);
    else if (k == "--frames")
      frames = std::atoi(argv[i + 1]);
    else if (k == "--threads") {
      threads.clear();
      for (const char* c = argv[i + 1]; *c; ++c)
        if (*c >= '1' && *c <= '9') threads.push_back(*c - '0');
    } else if (k == "--variants") {
      variants.clear();
      for (const char* c = argv[i + 1]; *c; ++c)
        if (*c >= '0' && *c <= '3') variants.push_back(*c - '0');
    } else if (k == "--tables")
      tables = std::string(argv[i + 1]) != "0";
    else
      points = 0;
  }
  if (argc % 2 == 0 || points == 0 || frames < 1 || threads.empty() || threads.size() > 2 || variants.empty()) {
    std::fprintf(stderr,
                 "usage: bench_collide_fountain [--points N] [--frames N] [--threads 1,2] [--variants 0,3,1,2] "
                 "[--tables 0|1]\n");
    return 2;
  }
  const std::string load_before = benchplot::loadAverage();
  {
    game::SceneConfig scene;
    const game::SceneStatus st = game::loadSceneFile((kContent / "scenes" / "fountain.json").string(), scene);
    const game::SectionConfig* sph = st.ok() ? scene.effect("sph_fluid") : nullptr;
    if (sph == nullptr) {
      std::fprintf(stderr, "bench_collide_fountain: fountain.json: %s\n",
                   st.ok() ? "no sph_fluid effect" : st.error.c_str());
      return 1;
    }
    support_radius = 4.0f * static_cast<float>(sph->number("particle_radius"));
  }
  std::vector<fluid::LevelColliderEntry> entries;
  std::vector<Model> models;
  if (!loadModels(entries, models)) return 1;
  std::vector<fluid::CachedCollider> baked;
  if (const fluid::CacheStatus st = fluid::loadLevelColliders(kContent, "fountain", game::colliderModelLoader(),
                                                              fluid::CachePolicy::load_only, baked);
      !st.ok()) {
    std::fprintf(stderr, "bench_collide_fountain: %s\n", st.error.c_str());
    return 1;
  }
  if (tables) {
    std::printf("### Per model, against the exact distance to its own mesh\n\n");
    if (perModelTable(entries, models, points) != 0) return 1;
    std::printf("### The fountain against the analytic FountainShape\n\n");
    if (fountainTable(baked, models, points) != 0) return 1;
  }
  std::printf("### SPH step cost, %d frames of 1/60 s from the same filled state\n\n", frames);
  if (sphCostTable(baked, frames, threads, variants) != 0) return 1;
  std::printf("\nLoad average (1, 5, 15 min) from /proc/loadavg: %s at the start, %s at the end.\n",
              load_before.c_str(), benchplot::loadAverage().c_str());
  return 0;
}
