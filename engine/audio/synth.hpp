#pragma once
// Sound synthesised from the simulation: sound events (a bubble, a wooden knock, a blast) become
// voices mixed into 32-bit float stereo. Plain math, no SDL: the live device (engine/audio/device.hpp)
// and the offline render (`fluiddemo replay --wav`) pull the same mixer through renderMixer, so a
// replay's samples depend only on the events queued and the listener set before each render call.
//
// The water's voice is the bubble of Moss, Yeh, Hong, Lin & Manocha 2010, "Sounding Liquids:
// Automatic Sound Synthesis from Fluid Simulation" (ACM TOG 29(3)), §3: each bubble entrained at an
// impact rings as a damped sinusoid at its Minnaert frequency, its pitch rising as it nears the
// surface. The crates are modal (a few damped wood-like modes); the blast is filtered noise over a
// falling low boom. Events are spatialised when they become voices: equal-power stereo panning by
// the listener's right vector, 1/r distance attenuation beyond a reference distance, and a delay of
// distance / speed of sound.
//
// Threading: queueSounds and setListener may run on one thread while renderMixer runs on another
// (SDL's audio callback); both take Mixer::lock. Everything else is single-threaded.

#include <glm/vec3.hpp>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace engine::audio {

// What made a sound: the statistics (events, loudness) are kept per kind.
enum class SoundKind : std::uint8_t { drop, jet, pump, goo, crate, crate_splash, blast, count };
constexpr std::size_t kSoundKinds = static_cast<std::size_t>(SoundKind::count);
std::string_view soundKindName(SoundKind kind);

// How a sound is made.
enum class VoiceShape : std::uint8_t {
  bubble,  // Moss et al. 2010 §3: p(t) = A sin(2 pi f(t) t) exp(-beta t), f(t) = f0 (1 + xi beta t)
  wood,    // four damped modes over a short contact click (a crate's knock)
  blast,   // low-passed noise burst over a boom falling from 80 to 35 Hz
};

struct SoundEvent {
  SoundKind kind = SoundKind::drop;
  VoiceShape shape = VoiceShape::bubble;
  glm::vec3 position{0.0f};  // m, world
  float onset = 0.0f;        // s after the start of the render call that takes it, before the travel delay
  float amplitude = 0.0f;    // linear pressure amplitude at 1 m (before the master volume)
  float radius = 0.0f;       // bubble: radius (m), > 0
  float frequency = 0.0f;    // wood: lowest mode (Hz)
  float damping = 1.0f;      // bubble and wood: multiplies the decay rate (goo > 1: a duller squelch)
  float duration = 0.3f;     // blast: the noise's decay time constant (s)
  std::uint32_t seed = 0;    // blast and wood: the noise's seed
};

struct Listener {
  glm::vec3 position{0.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};  // need not be normalised; up is +y
};

struct MixerParams {
  int sample_rate = 22050;          // Hz, >= 8000
  int max_voices = 192;             // more: the quietest voice is replaced, or the new one dropped
  float volume = 0.5f;              // master gain in [0, 4]
  bool mute = false;                // render silence (voices still advance, so unmuting is seamless)
  float xi = 0.1f;                  // Moss et al. 2010 §3 (after van den Doel 2005): pitch rise per decay
  float speed_of_sound = 343.0f;    // m/s, the travel delay; 0 = no delay
  float reference_distance = 2.0f;  // m: closer sounds are not louder (1/r beyond it)
  float limit = 0.89f;              // the limiter's ceiling (linear; 0.89 = -1 dBFS)
};

// Per kind of sound, over everything rendered so far.
struct KindStats {
  std::uint64_t events = 0;   // events queued
  std::uint64_t dropped = 0;  // not voiced (bad, inaudible, or quieter than every voice) or cut short by a louder one
  std::uint64_t active_frames = 0;  // frames with at least one voice of the kind sounding
  double sum_squares = 0.0;         // of the kind's own mono sum (after volume, before the limiter), active frames
  float peak = 0.0f;                // largest |sample| of the same
  float min_frequency = 0.0f, max_frequency = 0.0f;  // bubble and wood starting pitches (Hz); 0 = none
};

// What producing the events costs the thread that queues them (the game's main thread), per step:
// wall time, and the thread's CPU time (the work itself, without the time a loaded machine kept
// the thread waiting for a core).
struct ProducerCost {
  std::uint64_t steps = 0;
  double last_wall_ms = 0.0;
  double wall_ms_sum = 0.0, wall_ms_max = 0.0;
  double cpu_ms_sum = 0.0, cpu_ms_max = 0.0;
};

struct Voice {
  VoiceShape shape = VoiceShape::bubble;
  SoundKind kind = SoundKind::drop;
  std::int64_t start = 0;  // frame (Mixer::clock) at which it starts
  float gain_left = 0.0f, gain_right = 0.0f;
  float amplitude = 0.0f;  // current envelope (without the pan gains)
  float decay = 1.0f;      // per frame envelope factor
  double phase = 0.0;      // radians
  float frequency = 0.0f;  // Hz, now
  float rise = 0.0f;       // bubble: Hz per frame added to frequency (Moss §3 rising pitch)
  // wood: modes 1-3 beyond the fundamental; blast: the boom's sweep and the noise state.
  std::array<float, 3> mode_amp{}, mode_decay{}, mode_freq{};
  std::array<double, 3> mode_phase{};
  float noise = 0.0f;  // wood: click amplitude; blast: noise amplitude
  float noise_decay = 1.0f;
  float lowpass = 0.0f, lowpass_coeff = 0.0f;
  std::uint32_t rng = 1;
  std::uint32_t age = 0;  // frames since start
};

struct Mixer {
  MixerParams params;
  Listener listener;
  std::mutex lock;                  // queueSounds / setListener vs renderMixer
  std::vector<SoundEvent> pending;  // queued, voiced at the next render call
  // Events beyond this many pending are dropped (counted per kind): a run with no device and no
  // offline render never grows the queue past it.
  std::size_t max_pending = 16384;
  std::vector<Voice> voices;  // sounding (or waiting for their start)
  std::int64_t clock = 0;     // frames rendered so far
  float limiter_gain = 1.0f;
  std::array<KindStats, kSoundKinds> stats{};
  std::vector<float> kind_mix;  // scratch: one render call's mono sum per kind
  std::uint64_t clipped = 0;    // output samples the final clamp touched (0 unless the limiter failed)
  std::uint64_t nonfinite = 0;  // voices dropped for a NaN/inf sample
  ProducerCost producer;        // written by the thread that queues the events (the game's)
  // The overlay's level meter: the last render call's output peak and RMS (linear).
  std::atomic<float> meter_peak{0.0f}, meter_rms{0.0f};
  std::atomic<std::uint32_t> meter_voices{0};  // voices sounding or waiting after that call
};

// Clamps the parameters to their stable ranges and resets the mixer (no voices, clock 0).
void initMixer(Mixer& mixer, const MixerParams& params);
// Live edits that keep the voices: volume, mute, xi, speed of sound, reference distance, limit.
void setMixerLive(Mixer& mixer, const MixerParams& params);
void setListener(Mixer& mixer, const Listener& listener);
// Appends events; they become voices at the start of the next renderMixer call (counted then).
void queueSounds(Mixer& mixer, std::span<const SoundEvent> events);
// Renders `frames` interleaved stereo frames (2 * frames floats) into `out`, in [-1, 1].
void renderMixer(Mixer& mixer, float* out, std::size_t frames);

// Moss et al. 2010 §3, eq. 1 (Minnaert 1933): f0 = (1 / 2 pi r) sqrt(3 gamma p0 / rho) for an air
// bubble of radius r (m) in water, about 3.26 m/s / r.
float minnaertFrequency(float radius);
// The bubble's decay rate beta (1/s) at f0: beta = pi f0 delta with the total damping constant
// delta of radiation, viscosity and heat conduction, in van den Doel 2005's fit (which Moss et
// al. §3 take up): beta = 0.043 f0 + 0.0014 f0^1.5.
float bubbleDecayRate(float frequency);

// Writes 16-bit PCM WAV (interleaved `channels`, samples in [-1, 1], clamped). False + message.
bool writeWav16(const char* path, std::span<const float> samples, int channels, int sample_rate, std::string* error);
// Averages interleaved stereo to mono (out has samples.size() / 2 values).
void stereoToMono(std::span<const float> stereo, std::vector<float>& out);

}  // namespace engine::audio
