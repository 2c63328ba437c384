// The effects' parameter tables are the schema, and a live edit re-derives what depends on it
// exactly as a rebuild does (game/effects/).
#include "game/effects/effect.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <gtest/gtest.h>

namespace {

game::SceneConfig parse(const std::string& text) {
  game::SceneConfig scene;
  const game::SceneStatus status = game::parseSceneText(text, "test.json", scene);
  EXPECT_TRUE(status.ok()) << status.error;
  return scene;
}

// The camera's box (the level's edges) must hold its start: a start outside is refused naming the
// axis, the value and the box; the box reaches the camera the world builds.
TEST(CameraBounds, AStartOutsideTheBoxIsRefusedByName) {
  game::World world;
  std::string error;
  const std::string outside =
      R"({"camera": {"position": [0, 2, 20], "bounds_min": [-15, 0.4, -15], "bounds_max": [15, 10, 15]}, "effects": {}})";
  EXPECT_FALSE(game::buildWorld(parse(outside), game::contentDir(), world, error));
  EXPECT_NE(error.find("camera.position's z = 20"), std::string::npos) << error;
  EXPECT_NE(error.find("-15.0"), std::string::npos) << error;
  const std::string inside =
      R"({"camera": {"position": [0, 2, 9], "bounds_min": [-15, 0.4, -15], "bounds_max": [15, 10, 15]}, "effects": {}})";
  error.clear();
  ASSERT_TRUE(game::buildWorld(parse(inside), game::contentDir(), world, error)) << error;
  EXPECT_EQ(world.camera.bounds_min, glm::vec3(-15.0f, 0.4f, -15.0f));
  EXPECT_EQ(world.camera.bounds_max, glm::vec3(15.0f, 10.0f, 15.0f));
}

// Every effect section of the schema is its registry entry's table, in registry order.
TEST(EffectTables, SchemaSectionsAreTheRegistryTables) {
  std::vector<const game::SectionSpec*> effects;
  for (const game::SectionSpec& section : game::sceneSchema())
    if (section.is_effect) effects.push_back(&section);
  const auto registry = game::effectRegistry();
  ASSERT_EQ(effects.size(), registry.size());
  for (std::size_t i = 0; i < registry.size(); ++i) {
    EXPECT_EQ(effects[i]->name, registry[i]->name);
    EXPECT_EQ(effects[i]->params.data(), registry[i]->params.data()) << registry[i]->name;
    EXPECT_EQ(game::findEffectDesc(registry[i]->name), registry[i]);
  }
  EXPECT_EQ(game::findEffectDesc("no_such_effect"), nullptr);
}

// A section left empty parses to the struct's own initialisers: the table's defaults are the
// struct's, with nothing written twice.
TEST(EffectTables, EmptySectionsParseToTheStructDefaults) {
  const game::SceneConfig scene =
      parse(R"({"effects": {"rigid_bodies": {}, "sph_fluid": {}, "sprite_particles": {}, "fluid_surface": {}}})");
  game::SphFluidParams sph;
  std::string error;
  ASSERT_TRUE(game::sphParamsFrom(*scene.effect("sph_fluid"), sph, error)) << error;
  const game::SphFluidParams sph_default;
  EXPECT_EQ(sph.solver, sph_default.solver);
  EXPECT_EQ(sph.max_particles, sph_default.max_particles);
  EXPECT_EQ(sph.jet_speed, sph_default.jet_speed);
  EXPECT_EQ(sph.density_error, sph_default.density_error);
  EXPECT_EQ(sph.warm_start, sph_default.warm_start);
  EXPECT_EQ(sph.couple_bodies, sph_default.couple_bodies);
  const game::RigidBodyParams rigid = game::rigidParamsFrom(*scene.effect("rigid_bodies"));
  EXPECT_EQ(rigid.gravity, game::RigidBodyParams{}.gravity);
  EXPECT_EQ(rigid.crates, game::RigidBodyParams{}.crates);
  const game::SpriteParticleParams sprites =
      game::spriteParamsFrom(*scene.effect("sprite_particles"), glm::vec3(0.0f), glm::vec3(0.0f));
  EXPECT_EQ(sprites.spread_degrees, game::SpriteParticleParams{}.spread_degrees);
  EXPECT_EQ(sprites.size, game::SpriteParticleParams{}.size);
  EXPECT_EQ(sprites.max_particles, game::SpriteParticleParams{}.max_particles);
  game::FluidSurfaceParams surface;
  ASSERT_TRUE(game::surfaceParamsFrom(*scene.effect("fluid_surface"), surface, error)) << error;
  EXPECT_EQ(surface.method, game::FluidSurfaceParams{}.method);
  EXPECT_EQ(surface.order, game::FluidSurfaceParams{}.order);
  EXPECT_EQ(surface.absorption, game::FluidSurfaceParams{}.absorption);
}

// Raising sph_fluid.jet_speed live gives the solver the speed cap, WCSPH sound speed, nozzle speed
// and stray sinks of a world built with that jet speed (before, only the nozzle speed changed).
TEST(EffectLive, JetSpeedReDerivesLikeABuild) {
  const std::string base = R"({"effects": {"sph_fluid": {"max_particles": 200, "solver": "wcsph"}}})";
  const std::string fast = R"({"effects": {"sph_fluid": {"max_particles": 200, "solver": "wcsph", "jet_speed": 9}}})";
  std::string error;
  game::World live, built;
  ASSERT_TRUE(game::buildWorld(parse(base), game::contentDir(), live, error)) << error;
  ASSERT_TRUE(game::buildWorld(parse(fast), game::contentDir(), built, error)) << error;
  const fluid::SphWorld& before = game::findState<game::SphFluid>(live)->world;
  const float cap_before = before.params.max_speed;
  live.scene.effects[0].params["jet_speed"].number = 9.0;
  game::applyLiveParams(live);
  const fluid::SphWorld& a = game::findState<game::SphFluid>(live)->world;
  const fluid::SphWorld& b = game::findState<game::SphFluid>(built)->world;
  EXPECT_NE(a.params.max_speed, cap_before);
  EXPECT_EQ(a.params.max_speed, b.params.max_speed);
  EXPECT_EQ(a.params.sound_speed, b.params.sound_speed);
  ASSERT_EQ(a.emitters.size(), b.emitters.size());
  EXPECT_EQ(a.emitters[0].speed, b.emitters[0].speed);
  ASSERT_EQ(a.sinks.size(), b.sinks.size());
  for (std::size_t i = 0; i < a.sinks.size(); ++i) {
    EXPECT_EQ(a.sinks[i].min, b.sinks[i].min) << "sink " << i;
    EXPECT_EQ(a.sinks[i].max, b.sinks[i].max) << "sink " << i;
  }
}

}  // namespace
