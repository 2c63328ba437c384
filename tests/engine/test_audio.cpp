// The synthesiser (engine/audio): Minnaert pitch and its rise (Moss et al. 2010 §3), silence,
// no clipping or NaN under overload, panning, the travel delay, the radius distribution following
// the drop size (§4-5), determinism across render-call sizes, and the WAV file.
#include "engine/audio/bubbles.hpp"
#include "engine/audio/device.hpp"
#include "engine/audio/synth.hpp"

#include <SDL.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

namespace {

using engine::audio::Mixer;
using engine::audio::SoundEvent;
using engine::audio::SoundKind;
using engine::audio::VoiceShape;

std::vector<float> render(Mixer& m, std::size_t frames) {
  std::vector<float> out(2 * frames);
  engine::audio::renderMixer(m, out.data(), frames);
  return out;
}

// Frequency from the upward zero crossings of the left channel in frames [begin, end).
double crossingFrequency(const std::vector<float>& stereo, std::size_t begin, std::size_t end, int rate) {
  std::vector<double> at;
  for (std::size_t f = begin + 1; f < end; ++f) {
    const float a = stereo[2 * (f - 1)], b = stereo[2 * f];
    if (a < 0.0f && b >= 0.0f) at.push_back(static_cast<double>(f - 1) + a / (a - b));
  }
  if (at.size() < 2) return 0.0;
  return rate * static_cast<double>(at.size() - 1) / (at.back() - at.front());
}

SoundEvent bubble(float radius, float amplitude, glm::vec3 position = glm::vec3(0.0f)) {
  SoundEvent e;
  e.shape = VoiceShape::bubble;
  e.radius = radius;
  e.amplitude = amplitude;
  e.position = position;
  return e;
}

TEST(AudioSynth, MinnaertFrequencyIsAbout326OverTheRadius) {
  EXPECT_NEAR(engine::audio::minnaertFrequency(0.001f), 3260.0f, 1.0f);
  EXPECT_NEAR(engine::audio::minnaertFrequency(0.002f) * 2.0f, engine::audio::minnaertFrequency(0.001f), 1e-2f);
  EXPECT_EQ(engine::audio::minnaertFrequency(0.0f), 0.0f);
  EXPECT_EQ(engine::audio::minnaertFrequency(std::numeric_limits<float>::quiet_NaN()), 0.0f);
}

TEST(AudioSynth, NothingQueuedRendersExactSilence) {
  Mixer m;
  engine::audio::initMixer(m, {});
  const std::vector<float> out = render(m, 22050);
  EXPECT_TRUE(std::all_of(out.begin(), out.end(), [](float x) { return x == 0.0f; }));
  EXPECT_EQ(m.clock, 22050);
}

TEST(AudioSynth, ABubbleRingsAtItsMinnaertPitchAndThePitchRises) {
  Mixer m;
  engine::audio::MixerParams params;
  params.sample_rate = 44100;
  engine::audio::initMixer(m, params);
  const SoundEvent e = bubble(0.003f, 0.5f);
  engine::audio::queueSounds(m, std::span(&e, 1));
  const std::vector<float> out = render(m, 44100 / 20);  // 50 ms
  const double f0 = engine::audio::minnaertFrequency(0.003f);
  const double early = crossingFrequency(out, 0, 44100 * 4 / 1000, 44100);
  const double late = crossingFrequency(out, 44100 * 20 / 1000, 44100 * 30 / 1000, 44100);
  EXPECT_NEAR(early, f0, 0.04 * f0);
  // f(t) = f0 (1 + xi beta t): at t = 25 ms the rise is xi beta t of f0.
  const double beta = engine::audio::bubbleDecayRate(static_cast<float>(f0));
  EXPECT_NEAR(late / f0 - 1.0, 0.1 * beta * 0.025, 0.05);
  EXPECT_GT(late, early * 1.1);
  // It decays: the last 5 ms are much quieter than the first.
  float first = 0.0f, last = 0.0f;
  for (std::size_t i = 0; i < 2 * 220; ++i) first = std::max(first, std::abs(out[i]));
  for (std::size_t i = out.size() - 2 * 220; i < out.size(); ++i) last = std::max(last, std::abs(out[i]));
  EXPECT_LT(last, 0.2f * first);
  EXPECT_EQ(m.stats[0].events, 1u);
}

TEST(AudioSynth, OverloadNeverClipsAndNeverGoesNonFinite) {
  Mixer m;
  engine::audio::MixerParams params;
  params.volume = 4.0f;
  params.max_voices = 64;
  engine::audio::initMixer(m, params);
  std::vector<SoundEvent> events;
  for (int i = 0; i < 500; ++i) events.push_back(bubble(0.001f + 0.0001f * i, 20.0f, glm::vec3(0.1f * i, 0, 0)));
  for (int i = 0; i < 10; ++i) {
    SoundEvent blast;
    blast.kind = SoundKind::blast;
    blast.shape = VoiceShape::blast;
    blast.amplitude = 50.0f;
    blast.seed = 7u + i;
    events.push_back(blast);
  }
  SoundEvent bad = bubble(0.002f, 1.0f, glm::vec3(std::numeric_limits<float>::quiet_NaN()));
  events.push_back(bad);
  bad = bubble(std::numeric_limits<float>::infinity(), 1.0f);
  events.push_back(bad);
  engine::audio::queueSounds(m, events);
  const std::vector<float> out = render(m, 22050);
  float peak = 0.0f;
  for (float x : out) {
    ASSERT_TRUE(std::isfinite(x));
    peak = std::max(peak, std::abs(x));
  }
  EXPECT_LE(peak, m.params.limit + 1e-6f);  // the limiter's ceiling, under 0 dBFS
  EXPECT_GT(peak, 0.5f * m.params.limit);   // and it was loud
  EXPECT_EQ(m.clipped, 0u);
  EXPECT_LE(m.voices.size(), 64u);
  EXPECT_GE(m.stats[0].dropped, 500u - 64u);  // the voice cap and the two bad events
}

TEST(AudioSynth, PanningFollowsTheListenersRight) {
  Mixer m;
  engine::audio::initMixer(m, {});
  engine::audio::setListener(m, {glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f)});  // right is +x
  const SoundEvent e = bubble(0.004f, 0.5f, glm::vec3(3.0f, 0.0f, 0.0f));
  engine::audio::queueSounds(m, std::span(&e, 1));
  std::vector<float> out = render(m, 4410);
  double left = 0.0, right = 0.0;
  for (std::size_t f = 0; f < 4410; ++f) {
    left += out[2 * f] * out[2 * f];
    right += out[2 * f + 1] * out[2 * f + 1];
  }
  EXPECT_GT(right, 100.0 * left);
  // Facing the other way it swaps sides.
  engine::audio::setListener(m, {glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f)});
  engine::audio::queueSounds(m, std::span(&e, 1));
  out = render(m, 4410);
  left = right = 0.0;
  for (std::size_t f = 0; f < 4410; ++f) {
    left += out[2 * f] * out[2 * f];
    right += out[2 * f + 1] * out[2 * f + 1];
  }
  EXPECT_GT(left, 100.0 * right);
}

TEST(AudioSynth, DistantSoundsArriveLateAndQuieter) {
  const auto firstSound = [](float distance, float& peak) {
    Mixer m;
    engine::audio::initMixer(m, {});
    SoundEvent e;
    e.kind = SoundKind::blast;
    e.shape = VoiceShape::blast;
    e.amplitude = 1.0f;
    e.position = glm::vec3(0.0f, 0.0f, -distance);
    engine::audio::queueSounds(m, std::span(&e, 1));
    const std::vector<float> out = render(m, 22050);
    std::size_t first = out.size();
    peak = 0.0f;
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (out[i] != 0.0f && first == out.size()) first = i / 2;
      peak = std::max(peak, std::abs(out[i]));
    }
    return first;
  };
  float near_peak = 0.0f, far_peak = 0.0f;
  const std::size_t near = firstSound(1.0f, near_peak);
  const std::size_t far = firstSound(34.3f + 1.0f, far_peak);
  // 34.3 m more at 343 m/s: 0.1 s, 2205 frames at 22.05 kHz.
  EXPECT_NEAR(static_cast<double>(far) - static_cast<double>(near), 2205.0, 2.0);
  EXPECT_LT(far_peak, 0.2f * near_peak);  // 1/r beyond the 2 m reference: 2 / 35.3
}

TEST(AudioSynth, BiggerDropsMakeBiggerBubblesAndLowerPitch) {
  engine::audio::BubbleParams params;
  params.max_per_impact = 1000;
  const auto medianRadius = [&](float drop_radius) {
    engine::audio::Rng rng;
    std::vector<SoundEvent> events;
    for (int i = 0; i < 200; ++i) {
      engine::audio::Splash splash;
      splash.speed = 4.0f;
      splash.particles = 8.0f;
      splash.drop_radius = drop_radius;
      engine::audio::bubblesFromSplash(splash, params, 1.0f / 60.0f, rng, events);
    }
    std::vector<float> radii;
    for (const SoundEvent& e : events) {
      EXPECT_GE(e.radius, params.radius_min);
      EXPECT_LE(e.radius, params.radius_max);
      radii.push_back(e.radius);
    }
    EXPECT_GT(radii.size(), 100u);
    std::sort(radii.begin(), radii.end());
    return radii[radii.size() / 2];
  };
  const float small = medianRadius(0.04f);  // one SPH particle's radius
  const float large = medianRadius(0.16f);  // 64 of them together
  EXPECT_GT(large, 1.3f * small);
  EXPECT_LT(engine::audio::minnaertFrequency(large), engine::audio::minnaertFrequency(small) / 1.3f);
  // The top of the range is what the drop sets.
  EXPECT_FLOAT_EQ(engine::audio::topRadius(params, 0.16f), 0.05f * 0.16f);
}

TEST(AudioSynth, PowerLawRadiiFollowTheirCdf) {
  // p(r) ~ r^-2 on [1, 4]: CDF(r) = (1 - 1/r) / (3/4); the median is 1.6.
  EXPECT_NEAR(engine::audio::drawRadius(1.0f, 4.0f, 2.0f, 0.5f), 1.6f, 1e-4f);
  EXPECT_FLOAT_EQ(engine::audio::drawRadius(1.0f, 4.0f, 2.0f, 0.0f), 1.0f);
  EXPECT_NEAR(engine::audio::drawRadius(1.0f, 4.0f, 2.0f, 1.0f), 4.0f, 1e-4f);
  EXPECT_NEAR(engine::audio::drawRadius(1.0f, 4.0f, 1.0f, 0.5f), 2.0f, 1e-4f);  // log-uniform
}

TEST(AudioSynth, TheSamplesDoNotDependOnTheRenderCallSizes) {
  std::vector<SoundEvent> events;
  for (int i = 0; i < 40; ++i) {
    SoundEvent e = bubble(0.001f + 0.0003f * i, 0.1f, glm::vec3(i - 20.0f, 0.0f, -3.0f));
    e.onset = 0.001f * i;
    events.push_back(e);
  }
  SoundEvent knock;
  knock.kind = SoundKind::crate;
  knock.shape = VoiceShape::wood;
  knock.frequency = 300.0f;
  knock.amplitude = 0.3f;
  knock.seed = 99;
  events.push_back(knock);
  Mixer a, b;
  engine::audio::initMixer(a, {});
  engine::audio::initMixer(b, {});
  engine::audio::queueSounds(a, events);
  engine::audio::queueSounds(b, events);
  const std::vector<float> whole = render(a, 3000);
  std::vector<float> parts = render(b, 367);
  for (std::size_t n : {368u, 1000u, 1265u}) {
    const std::vector<float> more = render(b, n);
    parts.insert(parts.end(), more.begin(), more.end());
  }
  ASSERT_EQ(whole.size(), parts.size());
  EXPECT_EQ(whole, parts);
  EXPECT_GT(*std::max_element(whole.begin(), whole.end()), 0.0f);
}

// The live arrangement: SDL's thread renders while the game's thread queues and moves the listener
// (run under TSan: build with FLUIDDEMO_SANITIZE=thread). Every event queued is counted once.
TEST(AudioSynth, QueueingWhileAnotherThreadRendersIsSafe) {
  Mixer m;
  engine::audio::initMixer(m, {});
  std::atomic<bool> stop{false};
  std::thread device([&] {
    std::vector<float> buffer(2 * 512);
    while (!stop.load()) engine::audio::renderMixer(m, buffer.data(), 512);
  });
  std::vector<SoundEvent> events(20, bubble(0.002f, 0.05f, glm::vec3(1.0f, 0.0f, 0.0f)));
  for (int step = 0; step < 300; ++step) {
    engine::audio::setListener(m, {glm::vec3(0.01f * step, 0.0f, 0.0f), glm::vec3(0.0f, 0.0f, -1.0f)});
    engine::audio::queueSounds(m, events);
    (void)m.meter_peak.load(std::memory_order_relaxed);  // what the overlay reads
    (void)m.meter_voices.load(std::memory_order_relaxed);
  }
  stop = true;
  device.join();
  std::vector<float> rest(2 * 64);
  engine::audio::renderMixer(m, rest.data(), 64);  // voices what the device thread left queued
  const std::lock_guard<std::mutex> hold(m.lock);
  EXPECT_EQ(m.stats[0].events, 300u * 20u);
}

// The live device where there is no sound card: SDL's dummy driver pulls the same mixer from its
// own thread in real time.
TEST(AudioDevice, TheDummyDriverPullsTheMixerAndClosesCleanly) {
  setenv("SDL_AUDIODRIVER", "dummy", 0);  // keeps a driver the environment chose
  Mixer m;
  engine::audio::initMixer(m, {});
  const SoundEvent e = bubble(0.004f, 0.2f);
  engine::audio::queueSounds(m, std::span(&e, 1));
  engine::audio::AudioDevice device;
  std::string error;
  ASSERT_TRUE(engine::audio::openAudioDevice(device, m, error)) << error;
  EXPECT_FALSE(device.driver.empty());
  for (int i = 0; i < 100; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const std::lock_guard<std::mutex> hold(m.lock);
    if (m.clock > 4096) break;
  }
  engine::audio::closeAudioDevice(device);
  EXPECT_EQ(device.id, 0u);
  EXPECT_GT(m.clock, 0);  // the callback ran
  EXPECT_EQ(m.stats[0].events, 1u);
  EXPECT_EQ(SDL_WasInit(SDL_INIT_AUDIO), 0u);
}

TEST(AudioSynth, MuteSilencesTheOutputButKeepsTheVoices) {
  Mixer m;
  engine::audio::MixerParams params;
  params.mute = true;
  engine::audio::initMixer(m, params);
  const SoundEvent e = bubble(0.01f, 0.5f);
  engine::audio::queueSounds(m, std::span(&e, 1));
  const std::vector<float> out = render(m, 1000);
  EXPECT_TRUE(std::all_of(out.begin(), out.end(), [](float x) { return x == 0.0f; }));
  EXPECT_EQ(m.voices.size(), 1u);
  EXPECT_GT(m.stats[0].peak, 0.0f);  // it sounded, unheard
}

TEST(AudioSynth, WavFileHoldsTheSamples) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "fluiddemo_test_audio.wav";
  const std::vector<float> samples{0.0f, 0.5f, -0.5f, 1.0f, -1.0f, 2.0f};
  std::string error;
  ASSERT_TRUE(engine::audio::writeWav16(path.c_str(), samples, 2, 22050, &error)) << error;
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(bytes.size(), 44u + 2u * samples.size());
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 4), "RIFF");
  EXPECT_EQ(std::string(bytes.begin() + 8, bytes.begin() + 12), "WAVE");
  const auto u16 = [&](std::size_t at) { return bytes[at] | (bytes[at + 1] << 8); };
  const auto u32 = [&](std::size_t at) { return static_cast<unsigned>(u16(at) | (u16(at + 2) << 16)); };
  EXPECT_EQ(u16(22), 2);       // channels
  EXPECT_EQ(u32(24), 22050u);  // rate
  EXPECT_EQ(u16(34), 16);      // bits
  EXPECT_EQ(u32(40), 2u * samples.size());
  EXPECT_EQ(static_cast<std::int16_t>(u16(44 + 2)), 16384);   // 0.5
  EXPECT_EQ(static_cast<std::int16_t>(u16(44 + 10)), 32767);  // 2.0 clamped
  std::filesystem::remove(path);
  EXPECT_FALSE(engine::audio::writeWav16("/nonexistent/dir/x.wav", samples, 2, 22050, &error));
  EXPECT_NE(error.find("/nonexistent/dir/x.wav"), std::string::npos);
}

}  // namespace
