// A system not listed in the scene is never constructed: checked through the world's list and
// null pointers, through the profiler (its phase never runs), and through Bullet's allocator
// (no Bullet object is ever allocated when rigid_bodies is absent), and through a counting
// global operator new (without sph_fluid/fluid_surface, stepping and meshing allocate nothing).
#include "engine/fluid_render/fluid_render.hpp"
#include "game/paths.hpp"
#include "game/world/blob_monster.hpp"
#include "game/world/world.hpp"

#include <LinearMath/btAlignedAllocator.h>
#include <SDL.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>

// GCC 12 flags free() on memory from the replaced operator new below; both use malloc/free.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> g_count_new{false};
std::atomic<long> g_new_calls{0};
}  // namespace

// Counting replacement of the global operator new/delete (the array and sized forms forward
// here by default). Counts only while g_count_new is set.
void* operator new(std::size_t size) {
  if (g_count_new.load(std::memory_order_relaxed)) g_new_calls.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (g_count_new.load(std::memory_order_relaxed)) g_new_calls.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

std::atomic<long> g_bullet_allocations{0};

void* countingAlloc(size_t size) {
  ++g_bullet_allocations;
  return std::malloc(size);
}
void countingFree(void* memory) { std::free(memory); }

// Routes Bullet's allocations through the counter for the test's lifetime.
struct BulletAllocationCounter {
  BulletAllocationCounter() {
    g_bullet_allocations = 0;
    btAlignedAllocSetCustom(countingAlloc, countingFree);
  }
  ~BulletAllocationCounter() { btAlignedAllocSetCustom(nullptr, nullptr); }
  long count() const { return g_bullet_allocations.load(); }
};

game::SceneConfig parse(const std::string& text) {
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

void runSteps(game::World& world, engine::Profiler& profiler, int steps) {
  for (int i = 0; i < steps; ++i) {
    engine::beginFrame(profiler);
    game::stepWorld(world, &profiler);
    engine::endFrame(profiler);
  }
}

TEST(EffectGating, WithoutRigidBodiesNoBulletObjectIsEverAllocated) {
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"sprite_particles": {"rate": 300}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 30);
  game::playerThrow(world);  // left click without the effect: nothing happens
  runSteps(world, profiler, 1);
  EXPECT_EQ(world.systems, std::vector<std::string>{"sprite_particles"});
  EXPECT_EQ(game::findState<game::RigidBodies>(world), nullptr);
  ASSERT_NE(game::findState<game::SpriteParticles>(world), nullptr);
  // No GL context here: the GPU sprites are built but not attached, so they do not run (their
  // GL side is tested in gl_engine: Headless.ASceneWithoutSpritesCreatesNoGlParticleResources).
  EXPECT_FALSE(game::findState<game::SpriteParticles>(world)->attached);
  EXPECT_EQ(game::liveSprites(*game::findState<game::SpriteParticles>(world)), 0u);
  EXPECT_EQ(counter.count(), 0) << "Bullet allocated memory although rigid_bodies is not listed";
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 0u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 0u);
}

TEST(EffectGating, WithRigidBodiesTheCounterSeesBullet) {
  // The positive control: the same counter does see Bullet when the effect is listed.
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 3}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 10);
  EXPECT_EQ(world.systems, std::vector<std::string>{"rigid_bodies"});
  EXPECT_EQ(game::findState<game::SpriteParticles>(world), nullptr);
  ASSERT_NE(game::findState<game::RigidBodies>(world), nullptr);
  EXPECT_EQ(game::findState<game::RigidBodies>(world)->crates.size(), 3u);
  EXPECT_GT(counter.count(), 0);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 10u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 0u);
  const std::size_t before = game::findState<game::RigidBodies>(world)->crates.size();
  game::playerThrow(world);
  EXPECT_EQ(game::findState<game::RigidBodies>(world)->crates.size(), before + 1);
  world = game::World{};  // destroy before the counter restores Bullet's allocator
}

TEST(EffectGating, AnEmptyEffectListBuildsNothing) {
  BulletAllocationCounter counter;
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {}})"), game::contentDir(), world, error)) << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 5);
  EXPECT_TRUE(world.systems.empty());
  EXPECT_EQ(game::findState<game::RigidBodies>(world), nullptr);
  EXPECT_EQ(game::findState<game::SpriteParticles>(world), nullptr);
  EXPECT_EQ(counter.count(), 0);
  for (const engine::PhaseStats& stats : profiler.stats) EXPECT_EQ(stats.frames, 0u);
}

// Sound (issue 39): a scene without `audio` makes no mixer, asks Bullet for no contact lists and
// never starts SDL's audio; with it, the mixer exists but only a rendered run (attachGpu) opens a
// device.
TEST(EffectGating, WithoutAudioThereIsNoMixerNoContactListAndNoAudioDevice) {
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 3}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 30);
  EXPECT_EQ(world.links.audio, nullptr);
  const game::RigidBodies* bodies = game::findState<game::RigidBodies>(world);
  ASSERT_NE(bodies, nullptr);
  EXPECT_FALSE(bodies->physics->record_contacts);
  EXPECT_TRUE(bodies->physics->contacts.empty());
  EXPECT_EQ(SDL_WasInit(SDL_INIT_AUDIO), 0u);
}

TEST(EffectGating, AudioMakesAMixerButNoDeviceWithoutARenderedRun) {
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 3}, "audio": {}}})"),
                               game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runSteps(world, profiler, 30);
  ASSERT_NE(world.links.audio, nullptr);
  EXPECT_EQ(world.systems.back(), "audio");
  EXPECT_TRUE(game::findState<game::RigidBodies>(world)->physics->record_contacts);
  EXPECT_EQ(SDL_WasInit(SDL_INIT_AUDIO), 0u);
}

TEST(EffectGating, ThrownCratesAreCappedAndRecycled) {
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 2}}})"), game::contentDir(), world, error))
      << error;
  for (int i = 0; i < game::RigidBodies::kMaxThrown + 5; ++i) {
    game::playerThrow(world);
    game::stepWorld(world, nullptr);
  }
  EXPECT_EQ(game::findState<game::RigidBodies>(world)->crates.size(), 2u + game::RigidBodies::kMaxThrown);
  EXPECT_EQ(world.nonfinite_state, "");
}

TEST(EffectGating, MissingModelIsNamed) {
  game::World world;
  std::string error;
  EXPECT_FALSE(game::buildWorld(parse(R"({"effects": {"rigid_bodies": {}}})"), "/nonexistent/content", world, error));
  EXPECT_NE(error.find("/nonexistent/content/models/basin.obj"), std::string::npos) << error;
}

// Counts global operator new calls made while it is alive.
struct NewCounter {
  NewCounter() {
    g_new_calls = 0;
    g_count_new = true;
  }
  ~NewCounter() { g_count_new = false; }
  long count() const { return g_new_calls.load(); }
};

void runFrames(game::World& world, engine::Profiler& profiler, int frames) {
  for (int i = 0; i < frames; ++i) {
    engine::beginFrame(profiler);
    game::stepWorld(world, &profiler);
    game::meshWorld(world, &profiler);
    engine::endFrame(profiler);
  }
}

TEST(EffectGating, WithoutTheFluidEffectsNothingFluidIsBuiltOrRun) {
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"sprite_particles": {"rate": 300}}})"), game::contentDir(), world, error))
      << error;
  engine::Profiler profiler;
  runFrames(world, profiler, 5);  // warm-up
  long allocations = 0;
  {
    NewCounter counter;
    runFrames(world, profiler, 30);
    allocations = counter.count();
  }
  EXPECT_EQ(game::findState<game::SphFluid>(world), nullptr);
  EXPECT_EQ(game::findState<game::FluidSurface>(world), nullptr);
  EXPECT_EQ(allocations, 0) << "stepping/meshing allocated although no fluid effect is listed";
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::meshing)].frames, 0u);
}

TEST(EffectGating, SphFluidAndSurfaceRunWhenListed) {
  game::World world;
  std::string error;
  ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {"sph_fluid": {"pump": false, "max_particles": 400},
                                                    "fluid_surface": {}}})"),
                               game::contentDir(), world, error))
      << error;
  EXPECT_EQ(world.systems, (std::vector<std::string>{"sph_fluid", "fluid_surface"}));
  ASSERT_NE(game::findState<game::SphFluid>(world), nullptr);
  ASSERT_NE(game::findState<game::FluidSurface>(world), nullptr);
  EXPECT_EQ(game::findState<game::SpriteParticles>(world), nullptr);
  EXPECT_EQ(game::findState<game::RigidBodies>(world), nullptr);
  engine::Profiler profiler;
  // The positive control of the allocation check above: the fluid does allocate (its mesh).
  long allocations = 0;
  {
    NewCounter counter;
    runFrames(world, profiler, 60);
    allocations = counter.count();
  }
  EXPECT_GT(allocations, 0);
  EXPECT_EQ(world.nonfinite_state, "");
  const std::size_t n = game::findState<game::SphFluid>(world)->world.particles.size();
  EXPECT_GT(n, 100u);
  EXPECT_LE(n, 400u);
  EXPECT_GT(game::findState<game::FluidSurface>(world)->job.mesh.indices.size(), 0u);
  EXPECT_EQ(game::findState<game::FluidSurface>(world)->meshes, 60u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 60u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::meshing)].frames, 60u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 0u);
  // The jet rises from the nozzle: the highest particle is above the spire top.
  float top = 0.0f;
  for (const glm::vec3& p : game::findState<game::SphFluid>(world)->world.particles.position) top = std::max(top, p.y);
  EXPECT_GT(top, world.links.level.spire_top);
}

TEST(EffectGating, SphFluidWithoutSurfaceDoesNotMesh) {
  game::World world;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"sph_fluid": {"pump": false, "max_particles": 200, "solver": "wcsph"}}})"),
                       game::contentDir(), world, error))
      << error;
  EXPECT_EQ(game::findState<game::FluidSurface>(world), nullptr);
  engine::Profiler profiler;
  runFrames(world, profiler, 20);
  EXPECT_EQ(game::findState<game::SphFluid>(world)->world.params.solver, fluid::SphSolverKind::wcsph);
  EXPECT_GT(game::findState<game::SphFluid>(world)->world.particles.size(), 0u);
  EXPECT_EQ(world.nonfinite_state, "");
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 20u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::meshing)].frames, 0u);
}

TEST(EffectGating, FluidSurfaceWithoutSphFluidIsAnErrorNamingFileAndEffect) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "surface_only_scene.json";
  {
    std::ofstream out(file);
    out << R"({"effects": {"fluid_surface": {}}})";
  }
  game::SceneConfig scene;
  const game::SceneStatus status = game::loadSceneFile(file, scene);
  ASSERT_TRUE(status.ok()) << status.error;
  game::World world;
  std::string error;
  EXPECT_FALSE(game::buildWorld(scene, game::contentDir(), world, error));
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("fluid_surface requires effect sph_fluid"), std::string::npos) << error;
  EXPECT_EQ(game::findState<game::FluidSurface>(world), nullptr);
  std::filesystem::remove(file);
}

TEST(EffectGating, UnknownSolverAndOrderAreNamed) {
  // The schema lists the accepted words, so a bad one is refused when the scene is read,
  // before any system is built, with the file, the key and the value named.
  game::SceneConfig scene;
  std::string error = game::parseSceneText(R"({"effects": {"sph_fluid": {"solver": "flip"}}})", "s.json", scene).error;
  EXPECT_NE(error.find("s.json: effects.sph_fluid.solver"), std::string::npos) << error;
  EXPECT_NE(error.find("flip"), std::string::npos) << error;
  error =
      game::parseSceneText(R"({"effects": {"sph_fluid": {}, "fluid_surface": {"order": "random"}}})", "o.json", scene)
          .error;
  EXPECT_NE(error.find("o.json: effects.fluid_surface.order"), std::string::npos) << error;
  EXPECT_NE(error.find("random"), std::string::npos) << error;

  scene = parse(R"({"effects": {"sph_fluid": {}, "fluid_surface": {}}})");
  scene.name = "t";
  error = game::applyOverride(scene, "fluid_surface.order=random").error;
  EXPECT_NE(error.find("is not one of: sorted, unsorted, exact"), std::string::npos) << error;
  EXPECT_EQ(scene.effect("fluid_surface")->text("order"), "sorted");  // a refused override changes nothing
  EXPECT_TRUE(game::applyOverride(scene, "sph_fluid.solver=wcsph").ok());
  game::World world;
  EXPECT_TRUE(game::buildWorld(scene, game::contentDir(), world, error)) << error;
}

TEST(EffectGating, SortedSurfaceIsBackToFrontForTheCamera) {
  // The same particles meshed with order sorted/exact and unsorted: the sorted meshes have far
  // fewer triangle pairs out of back-to-front order for the camera's eye than the plain sweep.
  auto outOfOrder = [](const char* order, std::uint64_t& triangles) {
    game::World world;
    std::string error;
    // Camera behind the fountain looking along +z: the plain +z sweep is then front-to-back.
    const std::string text =
        std::string(R"({"camera": {"position": [0.3, 3, -8], "yaw_degrees": 88, "pitch_degrees": -5},
                        "effects": {"sph_fluid": {"pump": false, "max_particles": 400}, "fluid_surface": {"order": ")") +
        order + R"("}}})";
    EXPECT_TRUE(game::buildWorld(parse(text), game::contentDir(), world, error)) << error;
    engine::Profiler profiler;
    runFrames(world, profiler, 45);
    const fluid::SurfaceMesh& mesh = game::findState<game::FluidSurface>(world)->job.mesh;
    const engine::OutOfOrder o = engine::countOutOfOrderPairs(mesh.positions, mesh.indices, world.camera.position);
    triangles = o.triangles;
    return static_cast<double>(o.pairs) / std::max<double>(1.0, 0.5 * double(o.triangles) * double(o.triangles));
  };
  std::uint64_t t_sorted = 0, t_unsorted = 0, t_exact = 0;
  const double sorted = outOfOrder("sorted", t_sorted);
  const double unsorted = outOfOrder("unsorted", t_unsorted);
  const double exact = outOfOrder("exact", t_exact);
  std::printf("out-of-order pair fraction: sorted %.4f exact %.4f unsorted %.4f (%llu triangles)\n", sorted, exact,
              unsorted, static_cast<unsigned long long>(t_sorted));
  ASSERT_GT(t_sorted, 50u);
  EXPECT_EQ(t_sorted, t_unsorted);  // same particles, same triangles, other order
  EXPECT_EQ(t_sorted, t_exact);
  EXPECT_LT(sorted, 0.5 * unsorted) << "sorted " << sorted << " unsorted " << unsorted;
  EXPECT_LT(exact, 0.5 * unsorted) << "exact " << exact << " unsorted " << unsorted;
}

}  // namespace

// Crates and water push each other only when a scene lists both effects (and does not turn
// sph_fluid.couple_bodies off). A crate dropped onto the jet becomes an SPH collider: the jet
// pushes it up, and no water ends up inside it.
TEST(EffectGating, CratesAndWaterCoupleWhenBothAreListed) {
  std::string error;
  {
    game::World fluid_only, switched_off;
    ASSERT_TRUE(game::buildWorld(parse(R"({"effects": {"sph_fluid": {"pump": false, "max_particles": 200}}})"),
                                 game::contentDir(), fluid_only, error))
        << error;
    EXPECT_EQ(game::findState<game::SphFluid>(fluid_only)->coupling, nullptr);
    ASSERT_TRUE(game::buildWorld(
        parse(
            R"({"effects": {"rigid_bodies": {"crates": 0}, "sph_fluid": {"pump": false, "max_particles": 200, "couple_bodies": false}}})"),
        game::contentDir(), switched_off, error))
        << error;
    EXPECT_EQ(game::findState<game::SphFluid>(switched_off)->coupling, nullptr);
  }
  game::World world;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 0, "throw_speed": 0.5, "crate_size": 0.4},
                                                    "sph_fluid": {"pump": false, "max_particles": 800}}})"),
                       game::contentDir(), world, error))
      << error;
  ASSERT_NE(game::findState<game::SphFluid>(world)->coupling, nullptr);
  engine::Profiler profiler;
  runFrames(world, profiler, 40);                                                   // the jet is up
  EXPECT_EQ(game::findState<game::SphFluid>(world)->coupling->forces_applied, 0u);  // no crate yet
  const glm::vec3 nozzle = world.links.level.nozzle;
  // Its bottom 0.6 m above the nozzle, where the jet's drops still rise at about 3 m/s (they leave
  // at 4.5 m/s and turn at about 0.95 m, air drag included).
  game::throwCrate(*game::findState<game::RigidBodies>(world), nozzle + glm::vec3(0.0f, 0.8f, 0.0f),
                   glm::vec3(0.0f, -1.0f, 0.0f));
  double upward_impulse = 0.0;
  int coupled_steps = 0;
  for (int i = 0; i < 40; ++i) {
    game::stepWorld(world, &profiler);
    const game::BodyFluidCoupling& c = *game::findState<game::SphFluid>(world)->coupling;
    if (c.coupled.size() == 1) {
      ++coupled_steps;
      upward_impulse +=
          game::findState<game::SphFluid>(world)->world.colliders[c.first_collider].force.y * world.step_seconds;
    }
  }
  EXPECT_EQ(world.nonfinite_state, "");
  EXPECT_GT(coupled_steps, 10);
  EXPECT_GT(game::findState<game::SphFluid>(world)->coupling->forces_applied, 0u);
  // The crate comes to rest on the statue's top by the nozzle: the jet's drops hit it from below and
  // its crown rains on it from above, so the sign of the sum is the geometry's; that the water
  // pushes it at all is the coupling (the pool's buoyancy: FountainFloating, tests/game/test_fountain_pump.cpp).
  EXPECT_GT(std::abs(upward_impulse), 1.0) << "the water pushes the crate";
  const engine::BodyState crate = engine::bodyState(*game::findState<game::RigidBodies>(world)->physics,
                                                    game::findState<game::RigidBodies>(world)->crates.back());
  std::size_t inside = 0;
  for (const glm::vec3& x : game::findState<game::SphFluid>(world)->world.particles.position) {
    const glm::vec3 local = glm::inverse(crate.rotation) * (x - crate.position);
    // Half a particle radius of slack (20 mm): the SPH resolves the water against the crate's pose at
    // the end of the fluid step, and Bullet then moves the crate on (up to about 10 mm a step here,
    // resting on the statue's top by the nozzle, where a particle caught between the two is left
    // outside the still statue: still colliders win).
    inside += glm::all(glm::lessThan(glm::abs(local), glm::vec3(0.2f - 0.02f)));
  }
  EXPECT_EQ(inside, 0u);
  std::printf(
      "[ metric ] crate on the jet: coupled %d of 40 steps, upward impulse %.2f N s, forces capped %llu times\n",
      coupled_steps, upward_impulse,
      static_cast<unsigned long long>(game::findState<game::SphFluid>(world)->coupling->clamped));
}

TEST(EffectGating, TheBlobIsBuiltOnlyWhenListed) {
  game::World without;
  std::string error;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"effects": {"rigid_bodies": {"crates": 2}}})"), game::contentDir(), without, error))
      << error;
  EXPECT_EQ(game::findState<game::BlobMonster>(without), nullptr);
  game::World with;
  ASSERT_TRUE(
      game::buildWorld(parse(R"({"scene": {"level": "blob_monster"}, "effects": {"blob": {"particles": 300}}})"),
                       game::contentDir(), with, error))
      << error;
  EXPECT_EQ(with.systems, std::vector<std::string>{"blob"});
  ASSERT_NE(game::findState<game::BlobMonster>(with), nullptr);
  EXPECT_EQ(game::findState<game::BlobMonster>(with)->world.particles.size(), 300u);
  engine::Profiler profiler;
  runSteps(with, profiler, 5);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::fluid)].frames, 5u);
  EXPECT_EQ(profiler.stats[static_cast<int>(engine::Phase::physics)].frames, 0u);
}
