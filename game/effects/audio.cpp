// The `audio` effect: the demo's sound, synthesised from the simulation (no sample files). Each
// step it reads what the effects before it did and queues sound events into a mixer
// (engine/audio/synth.hpp):
//   water   particles stopped or turned in one step (fluid/core/impacts.hpp) are drops landing and
//           the jet entering the water; the pump's intake swallows water; each becomes bubbles
//           (engine/audio/bubbles.hpp, Moss et al. 2010 §4-5) ringing at their Minnaert pitch (§3)
//   crates  a sudden rise of a Bullet contact's impulse is a knock (wood-like modes, lower and louder
//           for bigger impulses); a crate dropping through the pool's surface is a big splash
//   blasts  a noise burst over a low boom, heard after distance / speed of sound
//   goo     the blob's particle impacts (tentacles whipping, slaps): the same bubbles, lower and
//           damped more
// The mixer is pulled live by SDL's audio thread (attachGpu opens the device: only a windowed or
// rendered run has one) and offline by `fluiddemo replay --wav` (EffectLinks::audio), the same
// renderMixer either way. Every event comes from the simulation state and a seeded generator, so a
// replay's samples are the same at any thread count. The audio state is output only: nothing reads
// it back, so it is not part of the replay state hash.
#include "engine/audio/bubbles.hpp"
#include "engine/audio/device.hpp"
#include "engine/audio/synth.hpp"
#include "fluid/blob/blob.hpp"
#include "fluid/core/impacts.hpp"
#include "game/effects/effect.hpp"
#include "game/effects/params.hpp"
#include "game/world/rigid_bodies.hpp"
#include "game/world/sph_fluid.hpp"

#include <imgui.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <vector>

namespace game {
namespace {

struct AudioParams {
  float volume = 1.0f;
  bool mute = false;
  bool live_device = true;     // open the sound card in a rendered run (fixed at construction)
  int sample_rate = 22050;     // Hz (fixed at construction)
  int max_voices = 256;        // (fixed at construction)
  float bubble_rate = 1.0f;    // bubbles per impact, relative
  float radius_min = 0.0012f;  // m
  float radius_max = 0.015f;   // m
  float radius_exponent = 2.0f;
  float size_ratio = 0.05f;  // top bubble radius / the radius of what fell
  float bubble_gain = 0.03f;
  float rising_pitch = 0.1f;    // Moss et al. 2010 §3 xi
  float min_speed = 1.0f;       // m/s
  float min_speed_loss = 1.2f;  // m/s lost in a step
  float impact_cell = 0.25f;    // m
  float jet_gain = 0.4f;
  float pump_gain = 0.5f;
  float crate_gain = 0.25f;
  float crate_min_impulse = 6.0f;  // N s
  float splash_gain = 2.0f;
  float blast_gain = 1.0f;
  float goo_gain = 0.6f;
  float goo_rate = 0.25f;
  float goo_damping = 4.0f;
  float goo_pitch = 0.35f;  // the goo's bubbles sound at this fraction of the water's pitch
  float speed_of_sound = 343.0f;
  float reference_distance = 2.0f;
};

const ParamTable<AudioParams>& table() {
  using P = AudioParams;
  static const ParamTable<P> rows{
      param<&P::volume>("volume", 0.0, 4.0, "master gain (a peak limiter keeps the output under -1 dBFS)"),
      param<&P::mute>("mute", "silence the output (M in the window toggles it)"),
      fixed(param<&P::live_device>("live_device",
                                   "open the sound card in a rendered run (SDL; SDL_AUDIODRIVER=dummy without one); "
                                   "replay --wav renders offline either way")),
      fixed(param<&P::sample_rate>("sample_rate", 8000, 48000, "mixer rate in Hz")),
      fixed(param<&P::max_voices>("max_voices", 1, 1024, "voices mixed at once; a new sound replaces the quietest")),
      param<&P::bubble_rate>("bubble_rate", 0.0, 20.0, "bubbles per impact, relative (0 = no water sounds)"),
      param<&P::radius_min>("radius_min", 0.0003, 0.05, "smallest bubble radius (m); Minnaert pitch 3.26/r Hz"),
      param<&P::radius_max>("radius_max", 0.0005, 0.1, "largest bubble radius (m)"),
      param<&P::radius_exponent>("radius_exponent", 0.0, 6.0, "bubble radii follow p(r) ~ r^-exponent"),
      param<&P::size_ratio>("size_ratio", 0.0, 1.0,
                            "an impact's largest bubble as a fraction of the radius of what fell (bigger drops, "
                            "lower notes)"),
      param<&P::bubble_gain>("bubble_gain", 0.0, 1.0, "a 3 mm bubble's amplitude at 1 m (linear)"),
      param<&P::rising_pitch>("rising_pitch", 0.0, 1.0, "Moss et al. 2010 xi: f(t) = f0 (1 + xi beta t)"),
      param<&P::min_speed>("min_speed", 0.0, 50.0, "particles slower than this (m/s) make no impact"),
      param<&P::min_speed_loss>("min_speed_loss", 0.01, 50.0,
                                "speed a particle must lose in one step beyond gravity's (m/s) to be an impact"),
      param<&P::impact_cell>("impact_cell", 0.01, 5.0, "impacts closer than this (m) in one step are one splash"),
      param<&P::jet_gain>("jet_gain", 0.0, 10.0,
                          "the jet landing in the dish, relative to a drop: the running fountain's steady bed"),
      param<&P::pump_gain>("pump_gain", 0.0, 10.0, "the pump intake's gurgle, relative"),
      param<&P::crate_gain>("crate_gain", 0.0, 10.0, "a crate's knock at 50 N s, 1 m away (linear)"),
      param<&P::crate_min_impulse>("crate_min_impulse", 0.0, 1000.0,
                                   "a contact's impulse must rise by this much in a step (N s) to knock"),
      param<&P::splash_gain>("splash_gain", 0.0, 20.0, "a crate landing in water, relative to a drop"),
      param<&P::blast_gain>("blast_gain", 0.0, 10.0, "a blast's amplitude at 1 m (linear, before the limiter)"),
      param<&P::goo_gain>("goo_gain", 0.0, 20.0, "the goo's squelches, relative to the water's bubbles"),
      param<&P::goo_rate>("goo_rate", 0.0, 20.0,
                          "the goo's bubbles per impact, relative to the water's (the body is always moving)"),
      param<&P::goo_damping>("goo_damping", 0.1, 50.0, "the goo's bubbles decay this many times faster"),
      param<&P::goo_pitch>("goo_pitch", 0.05, 2.0, "the goo's bubbles at this fraction of the water's pitch"),
      param<&P::speed_of_sound>("speed_of_sound", 0.0, 10000.0, "m/s: the delay of distant sounds; 0 = none"),
      param<&P::reference_distance>("reference_distance", 0.1, 100.0, "m: sounds fall off as 1/distance beyond this"),
  };
  return rows;
}

// The calling thread's CPU time (ms).
double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

engine::audio::MixerParams mixerParams(const AudioParams& p) {
  engine::audio::MixerParams m;
  m.sample_rate = p.sample_rate;
  m.max_voices = p.max_voices;
  m.volume = p.volume;
  m.mute = p.mute;
  m.xi = p.rising_pitch;
  m.speed_of_sound = p.speed_of_sound;
  m.reference_distance = p.reference_distance;
  return m;
}

engine::audio::BubbleParams waterBubbles(const AudioParams& p) {
  engine::audio::BubbleParams b;
  b.radius_min = p.radius_min;
  b.radius_max = std::max(p.radius_min, p.radius_max);
  b.exponent = p.radius_exponent;
  b.size_ratio = p.size_ratio;
  b.rate_scale = p.bubble_rate;
  b.amplitude = p.bubble_gain;
  return b;
}

// The goo: the same bubbles, lower (radii / goo_pitch: f0 ~ 1/r) and damped more.
engine::audio::BubbleParams gooBubbles(const AudioParams& p) {
  engine::audio::BubbleParams b = waterBubbles(p);
  b.radius_min /= p.goo_pitch;
  b.radius_max /= p.goo_pitch;
  b.amplitude *= p.goo_gain;
  b.rate_scale *= p.goo_rate;
  b.damping = p.goo_damping;
  return b;
}

fluid::ImpactParams impactParams(const AudioParams& p) {
  fluid::ImpactParams i;
  i.min_speed = p.min_speed;
  i.min_speed_loss = p.min_speed_loss;
  i.cell_size = p.impact_cell;
  return i;
}

// A Bullet contact between two bodies: key = (lower id << 32) | higher id.
struct PairImpulse {
  std::uint64_t key = 0;
  float impulse = 0.0f;  // N s
  glm::vec3 point{0.0f};
};

struct AudioState {
  AudioParams params;
  engine::audio::Mixer mixer;
  engine::audio::AudioDevice device;
  engine::audio::Rng rng;
  fluid::ImpactTracker water_tracker, goo_tracker;
  std::vector<fluid::Impact> impacts;             // scratch
  std::vector<engine::audio::SoundEvent> events;  // scratch: this step's
  std::vector<PairImpulse> contact_impulse;       // per body pair (sorted by key): the last step's largest impulse
  std::vector<PairImpulse> contact_now;           // scratch
  std::vector<float> crate_bottom;                // per crate: the last step's bottom height (m)
  std::size_t pump_held = 0;                      // the pump's fill count after the last step
  float pool_surface = -1e30f;                    // m: the pool's surface height (crateSplashes refreshes it)
  std::uint64_t pool_surface_step = 0;            // steps + 1 when it was last measured; 0 = never
  std::uint64_t steps = 0;
  engine::audio::ProducerCost cost;  // of step, on the main thread
  std::string device_error;
};

class AudioEffect final : public EffectOf<AudioState> {
 public:
  explicit AudioEffect(const EffectLinks& links) : level_(links.level) {}
  ~AudioEffect() override { engine::audio::closeAudioDevice(state.device); }

  std::string_view name() const override { return "audio"; }

  void applyLive(const SectionConfig& section, EffectLinks&) override {
    const AudioParams fresh = table().parseLive(section, state.params);
    state.params = fresh;
    const std::lock_guard<std::mutex> hold(state.mixer.lock);
    engine::audio::setMixerLive(state.mixer, mixerParams(fresh));
  }

  StepOutcome step(const StepContext& ctx) override {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = threadCpuMs();
    state.events.clear();
    const float dt = static_cast<float>(ctx.step_seconds);
    if (ctx.links.fluid != nullptr) waterSounds(*ctx.links.fluid, ctx.links.gravity, dt);
    if (ctx.links.bodies != nullptr) crateSounds(*ctx.links.bodies, ctx.links.fluid, dt);
    for (const fluid::Blast& blast : ctx.links.blasts) blastSound(blast);
    if (ctx.links.blob != nullptr) gooSounds(*ctx.links.blob, ctx.links.gravity, dt);
    if (!state.events.empty()) engine::audio::queueSounds(state.mixer, state.events);
    ++state.steps;
    engine::audio::ProducerCost& c = state.cost;
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const double cpu = threadCpuMs() - cpu_start;
    ++c.steps;
    c.last_wall_ms = wall;
    c.wall_ms_sum += wall;
    c.wall_ms_max = std::max(c.wall_ms_max, wall);
    c.cpu_ms_sum += cpu;
    c.cpu_ms_max = std::max(c.cpu_ms_max, cpu);
    const std::lock_guard<std::mutex> hold(state.mixer.lock);
    state.mixer.producer = c;
    return {};
  }

  // The listener follows the camera of each rendered frame.
  bool prepareFrame(const FrameContext& frame, std::string&) override {
    engine::audio::setListener(state.mixer, {frame.eye, frame.view_dir});
    return true;
  }

  // Only a rendered run attaches: that is when a player can hear it.
  void attachGpu(const GpuContext&) override {
    if (!state.params.live_device || state.device.id != 0) return;
    if (!engine::audio::openAudioDevice(state.device, state.mixer, state.device_error))
      std::fprintf(stderr, "fluiddemo: audio silent: %s\n", state.device_error.c_str());
  }
  void detachGpu() override { engine::audio::closeAudioDevice(state.device); }

  void drawStatus() const override {
    const float peak = state.mixer.meter_peak.load(std::memory_order_relaxed);
    const float rms = state.mixer.meter_rms.load(std::memory_order_relaxed);
    const auto db = [](float x) { return x > 1e-6f ? 20.0f * std::log10(x) : -120.0f; };
    const engine::audio::ProducerCost& c = state.cost;
    ImGui::Text("audio: %s%s, main thread %.3f ms/step (mean %.3f, max %.3f), M mutes",
                state.device.id != 0 ? state.device.driver.c_str() : "no device", state.params.mute ? " (muted)" : "",
                c.last_wall_ms, c.steps > 0 ? c.wall_ms_sum / static_cast<double>(c.steps) : 0.0, c.wall_ms_max);
    // The level meter: RMS as the bar, the peak in the text, both in dBFS over a 60 dB range.
    char label[64];
    std::snprintf(label, sizeof label, "rms %.0f dB  peak %.0f dB", db(rms), db(peak));
    ImGui::ProgressBar(std::clamp((db(rms) + 60.0f) / 60.0f, 0.0f, 1.0f), ImVec2(240.0f, 0.0f), label);
    ImGui::Text("  voices %u", state.mixer.meter_voices.load(std::memory_order_relaxed));
  }

 private:
  void waterSounds(const SphFluid& fluid, glm::vec3 gravity, float dt) {
    const fluid::ParticleStore& p = fluid.world.particles;
    fluid::findImpacts(p.position.data(), sizeof(glm::vec3), p.velocity.data(), sizeof(glm::vec3), p.id.data(),
                       p.position.size(), gravity, dt, impactParams(state.params), state.water_tracker, state.impacts);
    const engine::audio::BubbleParams bubbles = waterBubbles(state.params);
    const float r = fluid.world.params.particle_radius;
    for (const fluid::Impact& impact : state.impacts) {
      engine::audio::Splash splash;
      // The jet lands in the statue's dish; everything else is a drop (spray, a slosh, a blast's rain).
      const glm::vec2 xz(impact.position.x - level_.nozzle.x, impact.position.z - level_.nozzle.z);
      const bool in_dish = glm::length(xz) < level_.dish_radius && impact.position.y > level_.dish_bottom;
      splash.kind = in_dish ? engine::audio::SoundKind::jet : engine::audio::SoundKind::drop;
      splash.position = impact.position;
      splash.speed = impact.speed;
      splash.particles = static_cast<float>(impact.particles);
      splash.drop_radius = r * std::cbrt(splash.particles);
      if (in_dish) splash.loudness = state.params.jet_gain;  // a steady bed under the splashes
      engine::audio::bubblesFromSplash(splash, bubbles, dt, state.rng, state.events);
    }
    // The pump's intake: what it swallowed this step gurgles at the intake (slow water drawing air).
    const std::size_t held = fluid.world.pump.held.size();
    const std::size_t swallowed = held > state.pump_held ? held - state.pump_held : 0;
    state.pump_held = held;
    if (swallowed > 0 && state.params.pump_gain > 0.0f) {
      for (const fluid::SphSink& sink : fluid.world.sinks) {
        if (sink.kind != fluid::SphSinkKind::intake) continue;
        engine::audio::Splash splash;
        splash.kind = engine::audio::SoundKind::pump;
        splash.position = 0.5f * (sink.min + sink.max);
        splash.speed = bubbles.reference_speed;
        splash.particles = static_cast<float>(swallowed);
        splash.drop_radius = r * std::cbrt(splash.particles);
        splash.loudness = state.params.pump_gain;
        engine::audio::bubblesFromSplash(splash, bubbles, dt, state.rng, state.events);
        break;
      }
    }
  }

  void crateSounds(const RigidBodies& bodies, const SphFluid* fluid, float dt) {
    engine::PhysicsWorld& physics = *bodies.physics;
    physics.record_contacts = true;  // from the next step on (the first step's contacts are missed)
    // A knock is a sudden rise of a body pair's contact impulse (a landing, a hit); a resting or
    // sliding contact pushes about the same each step and stays silent.
    std::vector<PairImpulse>& now = state.contact_now;
    now.clear();
    for (const engine::ContactImpulse& c : physics.contacts)
      now.push_back(
          {(static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.a)) << 32) | static_cast<std::uint32_t>(c.b),
           c.impulse, c.point});
    // Per pair, the largest of the step's substeps (first of equals, so the order is total).
    std::stable_sort(now.begin(), now.end(), [](const PairImpulse& a, const PairImpulse& b) {
      return a.key < b.key || (a.key == b.key && a.impulse > b.impulse);
    });
    now.erase(
        std::unique(now.begin(), now.end(), [](const PairImpulse& a, const PairImpulse& b) { return a.key == b.key; }),
        now.end());
    for (const PairImpulse& pair : now) {
      const auto last = std::lower_bound(state.contact_impulse.begin(), state.contact_impulse.end(), pair.key,
                                         [](const PairImpulse& a, std::uint64_t key) { return a.key < key; });
      const bool had = last != state.contact_impulse.end() && last->key == pair.key;
      const float rise = pair.impulse - (had ? last->impulse : 0.0f);
      if (rise < state.params.crate_min_impulse || state.params.crate_gain <= 0.0f) continue;
      engine::audio::SoundEvent e;
      e.kind = engine::audio::SoundKind::crate;
      e.shape = engine::audio::VoiceShape::wood;
      e.position = pair.point;
      // Louder with the impulse (amplitude ~ sqrt: the knock's energy ~ impulse), lower too: a
      // harder hit sets more of the crate's boards moving, so its lowest modes dominate.
      const float relative = rise / 50.0f;
      e.amplitude = state.params.crate_gain * std::min(4.0f, std::sqrt(relative));
      e.frequency = std::clamp(420.0f / std::pow(relative, 0.2f), 90.0f, 900.0f) *
                    (0.9f + 0.2f * engine::audio::uniform01(state.rng));
      e.onset = engine::audio::uniform01(state.rng) * dt;
      e.seed = static_cast<std::uint32_t>(engine::audio::nextRandom(state.rng));
      state.events.push_back(e);
    }
    std::swap(state.contact_impulse, state.contact_now);
    if (fluid != nullptr) crateSplashes(bodies, *fluid, dt);
  }

  // A crate dropping through the pool's surface inside the basin: a big splash.
  void crateSplashes(const RigidBodies& bodies, const SphFluid& fluid, float dt) {
    state.crate_bottom.resize(bodies.crates.size(), 1e30f);
    const float half = 0.5f * bodies.params.crate_size;
    // The pool's surface (a pass over every particle) only while a crate falls inside the basin,
    // at most once a second: most steps cost nothing here.
    bool falling = false;
    for (std::size_t i = 0; i < bodies.crates.size() && i < bodies.current.size(); ++i) {
      const engine::BodyState& b = bodies.current[i];
      falling = falling || (glm::length(glm::vec2(b.position.x, b.position.z)) < level_.basin_inner_radius &&
                            b.linear_velocity.y < -state.params.min_speed);
    }
    if (falling && (state.pool_surface_step == 0 || state.steps >= state.pool_surface_step + 60)) {
      const WaterWhereabouts where = waterWhereabouts(fluid, level_);
      state.pool_surface = where.pool > 0 ? level_.basin_floor + where.pool_level : -1e30f;
      state.pool_surface_step = state.steps + 1;
    }
    for (std::size_t i = 0; i < bodies.crates.size() && i < bodies.current.size(); ++i) {
      const engine::BodyState& b = bodies.current[i];
      const float bottom = b.position.y - half;
      const bool in_basin = glm::length(glm::vec2(b.position.x, b.position.z)) < level_.basin_inner_radius;
      if (in_basin && state.crate_bottom[i] > state.pool_surface && bottom <= state.pool_surface &&
          b.linear_velocity.y < -state.params.min_speed) {
        engine::audio::Splash splash;
        splash.kind = engine::audio::SoundKind::crate_splash;
        splash.position = glm::vec3(b.position.x, state.pool_surface, b.position.z);
        splash.speed = -b.linear_velocity.y;
        splash.drop_radius = std::cbrt(3.0f / (4.0f * 3.14159265f)) * bodies.params.crate_size;
        splash.particles = 40.0f;
        splash.loudness = state.params.splash_gain;
        engine::audio::BubbleParams bubbles = waterBubbles(state.params);
        bubbles.max_per_impact = 64;
        engine::audio::bubblesFromSplash(splash, bubbles, dt, state.rng, state.events);
      }
      state.crate_bottom[i] = bottom;
    }
  }

  void blastSound(const fluid::Blast& blast) {
    engine::audio::SoundEvent e;
    e.kind = engine::audio::SoundKind::blast;
    e.shape = engine::audio::VoiceShape::blast;
    e.position = blast.centre;
    e.amplitude = state.params.blast_gain * std::sqrt(std::max(0.0f, blast.impulse_at_1m) / 60.0f);
    e.duration = 0.35f;
    e.seed = static_cast<std::uint32_t>(engine::audio::nextRandom(state.rng));
    state.events.push_back(e);
  }

  void gooSounds(const fluid::BlobWorld& blob, glm::vec3 gravity, float dt) {
    const fluid::BlobParticles& p = blob.particles;
    fluid::findImpacts(p.position.data(), sizeof(glm::vec3), p.velocity.data(), sizeof(glm::vec3), nullptr, p.size(),
                       gravity, dt, impactParams(state.params), state.goo_tracker, state.impacts);
    const engine::audio::BubbleParams bubbles = gooBubbles(state.params);
    const float r = fluid::blobParticleRadius(blob.params);
    for (const fluid::Impact& impact : state.impacts) {
      engine::audio::Splash splash;
      splash.kind = engine::audio::SoundKind::goo;
      splash.position = impact.position;
      splash.speed = impact.speed;
      splash.particles = static_cast<float>(impact.particles);
      splash.drop_radius = r * std::cbrt(splash.particles);
      engine::audio::bubblesFromSplash(splash, bubbles, dt, state.rng, state.events);
    }
  }

  FountainGeometry level_;
};

std::unique_ptr<Effect> build(const SectionConfig& section, BuildContext& ctx, std::string& /*error*/) {
  auto effect = std::make_unique<AudioEffect>(ctx.links);
  AudioState& s = effect->state;
  s.params = table().parse(section);
  engine::audio::initMixer(s.mixer, mixerParams(s.params));
  s.rng.state = 0x51ed270b27a7c3f1ull ^ ctx.seed;
  if (ctx.links.bodies != nullptr) ctx.links.bodies->physics->record_contacts = true;
  ctx.links.audio = &s.mixer;
  return effect;
}

}  // namespace

const EffectDesc& audioEffect() {
  static const EffectDesc desc{"audio",
                               "sound synthesised from the simulation: bubbles (Moss et al. 2010), crate knocks, "
                               "blasts, the goo; SDL device live, replay --wav offline",
                               table().specs,
                               {},
                               &build};
  return desc;
}

}  // namespace game
