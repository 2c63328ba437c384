// Cost of the sound (issue 39; Google Benchmark, not a ctest test):
//   BM_AudioStepFountain  the audio effect's step on the game's main thread, on the fountain scene
//                         as shipped (13,000 particles, the jet running, the crates at rest): the
//                         world steps untimed, then only the audio effect's step is timed. The
//                         issue's goal is < 0.5 ms per frame.
//   BM_MixerRender        one 512-frame buffer of SDL's callback with N voices sounding (the audio
//                         thread's cost), N = 64, 256.
#include "engine/audio/bubbles.hpp"
#include "engine/audio/synth.hpp"
#include "game/paths.hpp"
#include "game/world/world.hpp"

#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

namespace {

void BM_AudioStepFountain(benchmark::State& state) {
  game::SceneConfig scene;
  if (!game::loadSceneFile(game::scenesDir() / "fountain.json", scene).ok()) {
    state.SkipWithError("cannot load the fountain scene");
    return;
  }
  game::World world;
  std::string error;
  if (!game::buildWorld(scene, game::contentDir(), world, error) || world.links.audio == nullptr) {
    state.SkipWithError(("cannot build the fountain with audio: " + error).c_str());
    return;
  }
  for (int i = 0; i < 120; ++i) game::stepWorld(world, nullptr);  // the jet reaches the pool
  // Take the audio effect out of the world's list so stepWorld leaves it alone; step it by hand.
  std::unique_ptr<game::Effect> audio;
  for (auto& effect : world.effects)
    if (effect->name() == "audio") audio = std::move(effect);
  std::erase(world.effects, nullptr);
  const game::StepContext context{world.step_seconds, world.substeps, nullptr, world.links};
  std::vector<float> sink(2 * 1024);
  std::size_t particles = 0;
  for (auto _ : state) {
    state.PauseTiming();
    game::stepWorld(world, nullptr);
    state.ResumeTiming();
    audio->step(context);
    state.PauseTiming();
    engine::audio::renderMixer(*world.links.audio, sink.data(), 367);  // keep the queue drained
    state.ResumeTiming();
  }
  if (const game::SphFluid* fluid = world.links.fluid) particles = fluid->world.particles.size();
  state.counters["particles"] = static_cast<double>(particles);
}
BENCHMARK(BM_AudioStepFountain)->Unit(benchmark::kMillisecond)->Iterations(120);

void BM_MixerRender(benchmark::State& state) {
  engine::audio::Mixer mixer;
  engine::audio::MixerParams params;
  params.max_voices = static_cast<int>(state.range(0));
  engine::audio::initMixer(mixer, params);
  engine::audio::Rng rng;
  std::vector<engine::audio::SoundEvent> events;
  std::vector<float> out(2 * 512);
  for (auto _ : state) {
    state.PauseTiming();
    // Keep the mixer full: long, low bubbles so every voice sounds through the buffer.
    events.clear();
    while (mixer.voices.size() + events.size() < static_cast<std::size_t>(state.range(0))) {
      engine::audio::SoundEvent e;
      e.radius = 0.01f + 0.005f * engine::audio::uniform01(rng);
      e.amplitude = 0.01f;
      e.position = glm::vec3(engine::audio::uniform01(rng) * 10.0f, 0.0f, -3.0f);
      events.push_back(e);
    }
    engine::audio::queueSounds(mixer, events);
    state.ResumeTiming();
    engine::audio::renderMixer(mixer, out.data(), 512);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["voices"] = static_cast<double>(state.range(0));
}
BENCHMARK(BM_MixerRender)->Arg(64)->Arg(256)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
