// fluiddemo bake-collider / query-collider: depth-map colliders (fluid/collide, Kolb et al.
// 2004 §4) baked from a model file and queried for signed distance and normal.
// Models are loaded with assimp here, in the game; fluid/collide only sees plain arrays.
#include "game/commands.hpp"

#include "fluid/collide/collide.hpp"
#include "fluid/collide/coverage.hpp"
#include "fluid/collide/mesh_checks.hpp"
#include "fluid/core/fnv1a.hpp"
#include "fluid/io/particle_io.hpp"
#include "game/commands/cli_outputs.hpp"
#include "game/commands/cli_parse.hpp"
#include "game/world/collider_model.hpp"
#include "game/paths.hpp"
#include "game/world/sph_fluid.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <CLI/CLI.hpp>
#include <assimp/Importer.hpp>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

namespace game {

namespace {

// "\r"-updated progress on stderr when it is a terminal; silent when piped or redirected.
class BakeProgress {
 public:
  explicit BakeProgress(std::size_t maps) : maps_(maps), shown_(isatty(STDERR_FILENO) != 0) {}
  void map(std::size_t k, const fluid::MapSpec& spec) {
    if (!shown_) return;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "\rbake-collider: map %zu of %zu (%s %dx%d%s), %.1f s ", k + 1, maps_,
                 fluid::formatName(spec.format), spec.resolution, spec.resolution,
                 spec.kind == fluid::MapKind::cube ? "x6" : "", seconds);
    std::fflush(stderr);
  }
  ~BakeProgress() {
    if (shown_) std::fprintf(stderr, "\r\033[K");  // clear the line before the summary
  }

 private:
  std::size_t maps_;
  bool shown_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace

namespace {

// bake-collider --level: every collider of CONTENT/colliders/LEVEL.colliders, re-baked where the
// model or the recipe changed (or, with --check, an error naming the stale file).
int bakeLevelColliders(const std::string& content, const std::string& level, bool check) {
  std::vector<fluid::CachedCollider> parts;
  const fluid::CacheStatus st =
      fluid::loadLevelColliders(content, level, colliderModelLoader(),
                                check ? fluid::CachePolicy::load_only : fluid::CachePolicy::load_or_bake, parts);
  if (!st.ok()) {
    std::fprintf(stderr, "bake-collider: %s\n", st.error.c_str());
    return 1;
  }
  for (const fluid::CachedCollider& part : parts) {
    std::printf("%s: %s (%s, %d depth maps, %zu bytes; %s)\n", part.name.c_str(),
                part.rebaked ? "re-baked" : "up to date", part.source.model.c_str(), part.collider.depthMapCount(),
                part.collider.bytes(), part.rebaked ? part.rebake_reason.c_str() : part.source.recipe.c_str());
  }
  return 0;
}

// One map at a time so a terminal sees how far the bake is; each map is baked exactly as in one
// call (the maps do not depend on each other).
fluid::BakeStatus bakeWithProgress(const fluid::MeshView& view, const std::vector<fluid::MapSpec>& specs,
                                   const fluid::BakeDesc& desc, std::vector<fluid::DepthMap>& baked) {
  fluid::BakeStatus status;
  BakeProgress progress(specs.size());
  for (std::size_t k = 0; k < specs.size() && status.ok(); ++k) {
    progress.map(k, specs[k]);
    fluid::DepthMapCollider one;
    status = fluid::bakeDepthMaps(view, std::span(&specs[k], 1), desc, one);
    if (status.ok()) baked.push_back(one.maps().front());
  }
  return status;
}

// The model's file name and hash and the recipe, so that a cache can tell when a file no longer
// matches its model.
fluid::ColliderSource sourceRecord(const std::string& model, const fluid::BakeRecipe& recipe) {
  fluid::ColliderSource source;
  source.model = std::filesystem::path(model).filename().string();
  source.recipe = fluid::bakeRecipeText(recipe);
  std::ifstream in(model, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  source.model_fnv1a64 = fluid::fnv1a64(bytes.data(), bytes.size());
  return source;
}

// What the coverage check of a bake found (fluid/collide/coverage.hpp).
struct CoverageOutcome {
  std::string error;
  std::string maps;  // --maps auto: the maps chosen ("axes,cube@...")
  std::size_t cubes = 0;
  fluid::CoverageReport before, after;  // the axis maps alone (auto), and the collider written
  float spacing = 0.0f;
  glm::vec3 first_point{0.0f};  // the first point not covered, its exact distance and the answer
  float first_exact = 0.0f;
  std::string first_answer;
};

// Measures the baked maps over the points within `reach` of the surface (exact mesh distance) and,
// with auto_maps, adds the concave-region cubes to `baked`.
bool coverBake(const fluid::MeshView& view, const std::vector<fluid::MapSpec>& specs, float reach, bool auto_maps,
               const fluid::ConcaveCubesDesc& desc, std::vector<fluid::DepthMap>& baked, CoverageOutcome& out) {
  const fluid::MeshDistance exact(view);
  fluid::CoverageDesc cd;
  cd.reach = reach;
  cd.threads = desc.threads;
  const fluid::NearSurfaceSamples samples = fluid::nearSurfaceSamples(exact, fluid::meshBounds(view), cd);
  out.spacing = samples.spacing;
  if (auto_maps) {
    fluid::ConcaveCubesResult chosen = fluid::chooseConcaveCubes(view, exact, samples, specs, baked, desc);
    if (!chosen.status.ok()) {
      out.error = chosen.status.error;
      return false;
    }
    baked.insert(baked.end(), chosen.maps.begin(), chosen.maps.end());
    out.maps = "axes" + std::string(chosen.items.empty() ? "" : ",") + chosen.items;
    out.cubes = chosen.cubes.size();
    out.before = std::move(chosen.before);
    out.after = std::move(chosen.after);
  } else {
    const fluid::DepthMapCollider collider(baked, desc.normal_resolution);
    out.after = fluid::measureCoverage(collider, samples, fluid::coverageTolerance(specs), desc.threads);
  }
  if (out.after.uncovered() > 0) {
    const std::uint32_t k = out.after.first_uncovered;
    out.first_point = samples.points[k];
    out.first_exact = samples.exact[k].distance;
    const fluid::ColliderSample got = fluid::DepthMapCollider(baked, desc.normal_resolution).sample(out.first_point);
    char text[64];
    std::snprintf(text, sizeof text, "%g", static_cast<double>(got.distance));
    out.first_answer = got.valid ? text : "inf (beyond reach)";
  }
  return true;
}

void printCoverage(const std::string& maps, bool auto_maps, float reach, const CoverageOutcome& c) {
  if (auto_maps) {
    std::printf("bake-collider: maps %s (auto: the six axis maps%s; they alone covered %.2f %%, measured %.2f %%)\n",
                maps.c_str(),
                c.cubes == 0
                    ? ", no concave region needed a cube"
                    : (" and " + std::to_string(c.cubes) + " concave-region cube" + (c.cubes > 1 ? "s" : "")).c_str(),
                100.0 * c.before.coveredShare(), 100.0 * c.before.measuredShare());
  } else {
    std::printf("bake-collider: maps %s\n", maps.c_str());
  }
  const fluid::CoverageReport& r = c.after;
  std::printf(
      "bake-collider: %zu points within --reach %g of the surface (lattice %g): %.2f %% covered (finite, right "
      "sign; %zu beyond reach, %zu wrong sign), %.2f %% measured (%zu margin-ring guesses, %zu read beyond "
      "reach); mean |error| %.3g, max %.3g\n",
      r.near, static_cast<double>(reach), static_cast<double>(c.spacing), 100.0 * r.coveredShare(), r.beyond_reach,
      r.wrong_sign, 100.0 * r.measuredShare(), r.ring_guess, r.off_distance, r.mean_abs_error, r.max_abs_error);
}

}  // namespace

int bakeColliderCommand(const Args& args) {
  CLI::App app{"Bake depth-map colliders (Kolb et al. 2004 §4) from a model (OBJ and anything assimp reads).",
               "fluiddemo bake-collider"};
  std::string model, out_path, maps = "auto", format_name = "front-back16", level;
  // The content folder every subcommand uses (game/paths.hpp), not one relative to where it runs.
  std::string content = contentDir().string();
  int resolution = 256, normal_resolution = 256, threads = 0, max_cubes = 8;
  // The reach a collider must answer within: the support H = 4r of the game's SPH particles
  // (fluid/sph/sph.hpp), r the sph_fluid effect's particle_radius (0.04 m in the fountain scene).
  float reach = 4.0f * SphFluidParams{}.particle_radius;
  float margin = -1.0f;  // -1: --reach with --maps auto, 0 with a list
  bool force = false, allow_open = false, check = false, strict = false;
  app.add_option("MODEL", model, "model file (OBJ, glTF, PLY, ...): a closed surface");
  app.add_option("--out", out_path, "collider file to write (with MODEL)");
  app.add_option("--level", level,
                 "instead of MODEL: bake the colliders listed in CONTENT/colliders/LEVEL.colliders whose files are "
                 "missing or stale (model hash or bake parameters changed)");
  app.add_option("--content", content,
                 "content directory of --level (default: the project's, as play uses; FLUIDDEMO_ROOT overrides it)")
      ->capture_default_str();
  app.add_flag("--check", check, "with --level: bake nothing, fail when a collider file is missing or stale");
  app.add_option("--margin", margin,
                 "silhouette margin of the ortho maps (model units): points this close outside get a finite distance "
                 "(default: --reach with --maps auto, else 0)");
  app.add_option("--reach", reach,
                 "the near-surface band (model units) every point of which should get a finite distance of the right "
                 "sign: the SPH support 4r of the game's particles by default")
      ->capture_default_str();
  app.add_option("--maps", maps,
                 "auto (the six axis maps, then a LESS depth cube for each concave region they leave unmeasured "
                 "within --reach, Kolb et al. 2004 §4.1), or comma-separated maps: axes | x | y | z (front-back pairs "
                 "along an axis), cube (GREATER cube at the centre), cube-less, cube@X:Y:Z:H[:N] (LESS cube for a "
                 "concave region, N its own resolution)")
      ->capture_default_str();
  app.add_option("--max-cubes", max_cubes, "with --maps auto: at most this many concave-region cubes (0..64)")
      ->capture_default_str();
  app.add_flag("--strict", strict,
               "fail (exit 1, nothing written) when a point within --reach of the surface gets no finite distance or "
               "the wrong sign");
  app.add_option("--res", resolution, "texels per side of every map (4..4096)")->capture_default_str();
  app.add_option("--format", format_name, "ortho map format: float | fixed8 | front-back16 (cubes are always cube8)")
      ->capture_default_str();
  app.add_option("--normal-res", normal_resolution, "L1 normal index resolution (2..256)")->capture_default_str();
  app.add_option("--threads", threads, "baking threads (0 = all)")->capture_default_str();
  app.add_flag("--force", force, "replace --out if it exists");
  app.add_flag("--allow-open", allow_open,
               "bake a mesh with holes anyway (warning only); points inside it may then read as outside");
  if (const int code = parseCommandLine(app, "bake-collider", args); code >= 0) return code;
  if (!level.empty()) {
    if (!model.empty() || !out_path.empty()) {
      std::fprintf(stderr, "bake-collider: --level takes no MODEL or --out (the level's list names them)\n");
      return 2;
    }
    return bakeLevelColliders(content, level, check);
  }
  if (model.empty() || out_path.empty() || check) {
    std::fprintf(stderr, "bake-collider: give MODEL and --out FILE, or --level LEVEL [--check]\n");
    return 2;
  }
  fluid::DepthMapFormat format;
  if (!fluid::parseFormat(format_name, format) || format == fluid::DepthMapFormat::cube8) {
    std::fprintf(stderr, "bake-collider: --format '%s' unknown (expected float, fixed8 or front-back16)\n",
                 format_name.c_str());
    return 2;
  }
  if (resolution < 4 || resolution > 4096) {
    std::fprintf(stderr, "bake-collider: --res %d out of range 4..4096\n", resolution);
    return 2;
  }
  if (!(reach > 0.0f && reach <= 1e5f)) {
    std::fprintf(stderr, "bake-collider: --reach %g must be positive and at most 1e5 (model units)\n",
                 static_cast<double>(reach));
    return 2;
  }
  if (margin < 0.0f && margin != -1.0f) {
    std::fprintf(stderr, "bake-collider: --margin %g must be >= 0 (model units)\n", static_cast<double>(margin));
    return 2;
  }
  if (max_cubes < 0 || max_cubes > 64) {
    std::fprintf(stderr, "bake-collider: --max-cubes %d out of range 0..64\n", max_cubes);
    return 2;
  }
  const bool auto_maps = maps == "auto";
  // The default bake answers every point within reach, convex rims included: its ortho maps get a
  // margin ring as wide as the reach. An explicit --maps list keeps the margin it is given (0).
  if (margin == -1.0f) margin = auto_maps ? reach : 0.0f;
  if (const int code = checkOutputFile("bake-collider", "--out", out_path, force); code >= 0) return code;
  ColliderModel mesh;
  std::string error;
  if (!loadColliderModel(model, mesh, error)) {
    std::fprintf(stderr, "bake-collider: %s\n", error.c_str());
    return 1;
  }
  if (const std::string open = openMeshMessage(mesh, model); !open.empty()) {
    if (!allow_open) {
      std::fprintf(stderr, "bake-collider: %s (close the model, or pass --allow-open to bake it anyway)\n",
                   open.c_str());
      return 1;
    }
    std::fprintf(stderr, "bake-collider: warning: %s (baking it anyway: --allow-open)\n", open.c_str());
  }
  const fluid::MeshView view{mesh.positions, mesh.indices};
  std::vector<fluid::MapSpec> specs;
  fluid::BakeRecipe recipe{auto_maps ? "axes" : maps, resolution, format, normal_resolution, margin};
  if (!fluid::recipeMapSpecs(recipe, fluid::meshBounds(view), specs, error)) {
    std::fprintf(stderr, "bake-collider: %s\n", error.c_str());
    return 2;
  }
  std::vector<fluid::DepthMap> baked;
  const fluid::BakeStatus status = bakeWithProgress(view, specs, {normal_resolution, threads}, baked);
  if (!status.ok()) {
    std::fprintf(stderr, "bake-collider: %s: %s\n", model.c_str(), status.error.c_str());
    return 1;
  }
  // Near-surface coverage (coverage.hpp), and with --maps auto the concave-region cubes (§4.1).
  CoverageOutcome coverage;
  if (!coverBake(view, specs, reach, auto_maps, {0.0f, resolution, max_cubes, normal_resolution, threads}, baked,
                 coverage)) {
    std::fprintf(stderr, "bake-collider: %s: %s\n", model.c_str(), coverage.error.c_str());
    return 1;
  }
  if (auto_maps) recipe.maps = coverage.maps;
  printCoverage(recipe.maps, auto_maps, reach, coverage);
  if (strict && coverage.after.uncovered() > 0) {
    const glm::vec3 p = coverage.first_point;
    std::fprintf(stderr,
                 "bake-collider: --strict: %s: %zu of %zu points within --reach %g of the surface are not covered (%zu "
                 "beyond reach, %zu with the wrong sign), the first at (%g, %g, %g), exact distance %g, answered %s; "
                 "nothing written (add maps with --maps, e.g. cube@X:Y:Z:H in the cavity, or leave out --strict)\n",
                 model.c_str(), coverage.after.uncovered(), coverage.after.near, static_cast<double>(reach),
                 coverage.after.beyond_reach, coverage.after.wrong_sign, static_cast<double>(p.x),
                 static_cast<double>(p.y), static_cast<double>(p.z), static_cast<double>(coverage.first_exact),
                 coverage.first_answer.c_str());
    return 1;
  }
  const fluid::DepthMapCollider collider(std::move(baked), normal_resolution);
  // The source record: the model's hash and the recipe, so a cache (fluid::loadOrBakeCollider)
  // can tell when this file no longer matches its model.
  const fluid::ColliderSource source = sourceRecord(model, recipe);
  const fluid::FileStatus saved =
      fluid::saveCollider(out_path, collider, force ? fluid::Overwrite::replace : fluid::Overwrite::refuse, source);
  if (!saved.ok()) {
    std::fprintf(stderr, "bake-collider: %s\n", saved.error.c_str());
    return 1;
  }
  std::printf("%s: %zu triangles (%zu degenerate skipped) -> %s: %zu textures, %d depth maps, %zu bytes\n",
              model.c_str(), mesh.indices.size() / 3, status.degenerate_triangles, out_path.c_str(),
              collider.maps().size(), collider.depthMapCount(), collider.bytes());
  return 0;
}

int queryColliderCommand(const Args& args) {
  CLI::App app{
      "Signed distance (negative inside) and unit outward normal per point, one line `d nx ny nz` per input "
      "point in order. Points no depth map has a distance for (outside the collider) print `inf 0 0 0`.",
      "fluiddemo query-collider"};
  std::string collider_path, points_path;
  int threads = 0;
  app.add_option("FILE", collider_path, "collider file from bake-collider")->required();
  app.add_option("--points", points_path, "points (.xyz, .csv or .ply), collider space")->required();
  app.add_option("--threads", threads, "query threads (0 = all)")->capture_default_str();
  if (const int code = parseCommandLine(app, "query-collider", args); code >= 0) return code;
  fluid::DepthMapCollider collider;
  const fluid::FileStatus loaded = fluid::loadCollider(collider_path, collider);
  if (!loaded.ok()) {
    std::fprintf(stderr, "query-collider: %s\n", loaded.error.c_str());
    return 1;
  }
  fluid::ParticlePositions particles;
  const fluid::IoStatus read = fluid::readParticleFile(points_path, particles);  // rejects NaN/inf with file:line
  if (!read.ok()) {
    std::fprintf(stderr, "query-collider: %s\n", read.error.c_str());
    return 1;
  }
  std::vector<glm::vec3> points(particles.size());
  for (std::size_t k = 0; k < points.size(); ++k) points[k] = particles.at(k);
  std::vector<fluid::ColliderSample> samples(points.size());
  fluid::queryParallel(collider, points, samples, {threads});
  std::size_t unknown = 0;
  for (const fluid::ColliderSample& s : samples) {
    if (!s.valid) {
      ++unknown;
      std::printf("inf 0 0 0\n");
    } else {
      std::printf("%.9g %.9g %.9g %.9g\n", s.distance, s.normal.x, s.normal.y, s.normal.z);
    }
  }
  if (unknown > 0) {
    std::fprintf(stderr, "query-collider: %zu of %zu points are outside every map's reach (printed as inf 0 0 0)\n",
                 unknown, samples.size());
  }
  return 0;
}

}  // namespace game
