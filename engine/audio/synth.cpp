#include "engine/audio/synth.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace engine::audio {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;
constexpr std::size_t kChunk = 256;  // frames per inner block: the scratch is sized once, at init
constexpr float kSilent = 1e-5f;     // a voice whose envelope falls below this (-100 dB) ends

// Free-free bar modes (Euler-Bernoulli: (2n+1)^2 pi^2/4 ratios 1, 2.756, 5.404, 8.933): a plank's
// ringing, which is what a crate's boards sound like when knocked.
constexpr std::array<float, 3> kWoodRatios{2.756f, 5.404f, 8.933f};
constexpr std::array<float, 3> kWoodAmps{0.5f, 0.3f, 0.15f};
// Wood's loss factor eta: each mode decays at beta = pi f eta, so higher modes die sooner, which
// is most of what makes a knock sound wooden rather than metallic (eta ~ 0.01 for a tuned bar; a
// nailed crate with its joints is duller).
constexpr float kWoodLoss = 0.06f;

std::uint32_t xorshift(std::uint32_t& s) {
  s ^= s << 13;
  s ^= s >> 17;
  s ^= s << 5;
  return s;
}
float whiteNoise(std::uint32_t& s) { return static_cast<float>(xorshift(s)) * (2.0f / 4294967296.0f) - 1.0f; }

float decayPerFrame(float rate_per_second, float sample_rate) { return std::exp(-rate_per_second / sample_rate); }

// The event as heard by the listener: panning, attenuation and the frame it starts on.
bool spatialise(const Mixer& m, const SoundEvent& e, Voice& v) {
  const glm::vec3 to = e.position - m.listener.position;
  const float distance = glm::length(to);
  if (!std::isfinite(distance) || !std::isfinite(e.amplitude) || !std::isfinite(e.onset)) return false;
  glm::vec3 right = glm::cross(m.listener.forward, glm::vec3(0.0f, 1.0f, 0.0f));
  const float right_length = glm::length(right);
  float pan = 0.0f;  // -1 left, +1 right
  if (distance > 1e-4f && right_length > 1e-6f) pan = glm::dot(to / distance, right / right_length);
  pan = std::clamp(pan, -1.0f, 1.0f);
  const float angle = (pan + 1.0f) * 0.25f * std::numbers::pi_v<float>;  // equal power: l^2 + r^2 = 1
  const float reference = m.params.reference_distance;
  const float attenuation = reference / std::max(reference, distance);
  v.gain_left = std::cos(angle) * attenuation;
  v.gain_right = std::sin(angle) * attenuation;
  const float travel = m.params.speed_of_sound > 0.0f ? distance / m.params.speed_of_sound : 0.0f;
  const float rate = static_cast<float>(m.params.sample_rate);
  v.start = m.clock + static_cast<std::int64_t>(std::llround(std::max(0.0f, e.onset + travel) * rate));
  v.kind = e.kind;
  v.shape = e.shape;
  v.amplitude = std::max(0.0f, e.amplitude);
  return v.amplitude > 0.0f;
}

void noteFrequency(KindStats& s, float f) {
  s.min_frequency = s.min_frequency == 0.0f ? f : std::min(s.min_frequency, f);
  s.max_frequency = std::max(s.max_frequency, f);
}

// Fills the shape-specific state of a voice; false when the event cannot sound (bad or inaudible).
bool shapeVoice(Mixer& m, const SoundEvent& e, Voice& v) {
  const float rate = static_cast<float>(m.params.sample_rate);
  const float nyquist = 0.45f * rate;
  KindStats& stats = m.stats[static_cast<std::size_t>(e.kind)];
  switch (e.shape) {
    case VoiceShape::bubble: {
      const float f0 = minnaertFrequency(e.radius);
      if (!(f0 > 0.0f) || f0 > nyquist) return false;
      // Moss et al. 2010 §3: the bubble's pitch rises as it nears the surface, f(t) = f0 (1 + xi beta t)
      // (xi = 0.1 after van den Doel 2005): a linear sweep of f0 xi beta Hz per second.
      const float beta = bubbleDecayRate(f0) * std::max(0.05f, e.damping);
      v.frequency = f0;
      v.decay = decayPerFrame(beta, rate);
      v.rise = f0 * m.params.xi * beta / rate;
      noteFrequency(stats, f0);
      return true;
    }
    case VoiceShape::wood: {
      const float f1 = e.frequency;
      if (!(f1 > 20.0f) || f1 > nyquist) return false;
      const float damping = std::max(0.05f, e.damping);
      v.frequency = f1;
      v.decay = decayPerFrame(std::numbers::pi_v<float> * f1 * kWoodLoss * damping, rate);
      for (std::size_t k = 0; k < kWoodRatios.size(); ++k) {
        const float fk = f1 * kWoodRatios[k];
        v.mode_freq[k] = fk;
        v.mode_amp[k] = fk < nyquist ? kWoodAmps[k] * v.amplitude : 0.0f;
        v.mode_decay[k] = decayPerFrame(std::numbers::pi_v<float> * fk * kWoodLoss * damping, rate);
      }
      // The contact itself: a 2 ms click of low-passed noise.
      v.noise = 0.6f * v.amplitude;
      v.noise_decay = decayPerFrame(500.0f, rate);
      v.lowpass_coeff = 1.0f - std::exp(-kTwoPi * 3000.0f / rate);
      v.rng = e.seed | 1u;
      noteFrequency(stats, f1);
      return true;
    }
    case VoiceShape::blast: {
      // The boom: a sine falling from 80 Hz to 35 Hz (mode_freq[0] holds the excess over 35 Hz,
      // shrinking with a 0.15 s time constant), decaying over 0.6 s; the noise: a burst decaying
      // over `duration`, low-passed at 1.2 kHz (a distant blast is mostly its low end).
      v.frequency = 35.0f;
      v.mode_freq[0] = 45.0f;
      v.mode_decay[0] = decayPerFrame(1.0f / 0.15f, rate);
      v.decay = decayPerFrame(1.0f / 0.6f, rate);
      v.noise = 0.8f * v.amplitude;
      v.noise_decay = decayPerFrame(1.0f / std::clamp(e.duration, 0.02f, 3.0f), rate);
      v.lowpass_coeff = 1.0f - std::exp(-kTwoPi * 1200.0f / rate);
      v.rng = e.seed | 1u;
      return true;
    }
  }
  return false;
}

float loudness(const Voice& v) { return (v.amplitude + v.noise) * std::max(v.gain_left, v.gain_right); }

void addVoice(Mixer& m, const SoundEvent& e) {
  KindStats& stats = m.stats[static_cast<std::size_t>(e.kind)];
  ++stats.events;
  Voice v;
  if (!spatialise(m, e, v) || !shapeVoice(m, e, v)) {
    ++stats.dropped;
    return;
  }
  if (m.voices.size() < static_cast<std::size_t>(m.params.max_voices)) {
    m.voices.push_back(v);
    return;
  }
  // Full: the new voice replaces the quietest, if it is louder (first such in voice order).
  std::size_t quietest = 0;
  for (std::size_t i = 1; i < m.voices.size(); ++i)
    if (loudness(m.voices[i]) < loudness(m.voices[quietest])) quietest = i;
  if (loudness(m.voices[quietest]) < loudness(v)) {
    ++m.stats[static_cast<std::size_t>(m.voices[quietest].kind)].dropped;
    m.voices[quietest] = v;
  } else {
    ++stats.dropped;
  }
}

// One voice's mono sample at its current state; advances it by one frame.
float advance(Voice& v, float sample_rate) {
  const float inv_rate = 1.0f / sample_rate;
  float s = 0.0f;
  switch (v.shape) {
    case VoiceShape::bubble:
      s = v.amplitude * std::sin(static_cast<float>(v.phase));
      v.phase += kTwoPi * v.frequency * inv_rate;
      v.frequency += v.rise;
      v.amplitude *= v.decay;
      break;
    case VoiceShape::wood: {
      s = v.amplitude * std::sin(static_cast<float>(v.phase));
      v.phase += kTwoPi * v.frequency * inv_rate;
      v.amplitude *= v.decay;
      for (std::size_t k = 0; k < v.mode_amp.size(); ++k) {
        s += v.mode_amp[k] * std::sin(static_cast<float>(v.mode_phase[k]));
        v.mode_phase[k] += kTwoPi * v.mode_freq[k] * inv_rate;
        v.mode_amp[k] *= v.mode_decay[k];
      }
      v.lowpass += v.lowpass_coeff * (whiteNoise(v.rng) - v.lowpass);
      s += v.noise * v.lowpass;
      v.noise *= v.noise_decay;
      break;
    }
    case VoiceShape::blast: {
      s = v.amplitude * std::sin(static_cast<float>(v.phase));
      v.phase += kTwoPi * (v.frequency + v.mode_freq[0]) * inv_rate;
      v.mode_freq[0] *= v.mode_decay[0];
      v.amplitude *= v.decay;
      v.lowpass += v.lowpass_coeff * (whiteNoise(v.rng) - v.lowpass);
      s += 2.0f * v.noise * v.lowpass;  // the one-pole filter takes about half the noise's level
      v.noise *= v.noise_decay;
      break;
    }
  }
  // Keep the phases small so float sin stays accurate over long voices.
  if (v.phase > 1e4) v.phase = std::fmod(v.phase, 2.0 * std::numbers::pi);
  for (double& p : v.mode_phase)
    if (p > 1e4) p = std::fmod(p, 2.0 * std::numbers::pi);
  ++v.age;
  return s;
}

bool finished(const Voice& v) {
  float envelope = v.amplitude + v.noise;
  for (float a : v.mode_amp) envelope += a;
  return envelope < kSilent;
}

// One block of at most kChunk frames into out (interleaved stereo).
void renderChunk(Mixer& m, float* out, std::size_t frames) {
  const float rate = static_cast<float>(m.params.sample_rate);
  std::fill(out, out + 2 * frames, 0.0f);
  std::fill(m.kind_mix.begin(), m.kind_mix.end(), 0.0f);
  std::array<std::uint64_t, kSoundKinds> active{};
  std::array<std::uint32_t, kSoundKinds> first_active{}, last_active{};
  first_active.fill(static_cast<std::uint32_t>(frames));
  for (std::size_t i = 0; i < m.voices.size();) {
    Voice& v = m.voices[i];
    const std::int64_t begin = std::max<std::int64_t>(0, v.start - m.clock);
    const std::size_t k = static_cast<std::size_t>(v.kind);
    bool bad = false, done = false;
    for (std::size_t f = static_cast<std::size_t>(std::min<std::int64_t>(begin, static_cast<std::int64_t>(frames)));
         f < frames && !done; ++f) {
      const float s = advance(v, rate);
      if (!std::isfinite(s)) {
        bad = true;
        break;
      }
      // Ends on the frame its envelope falls silent, whatever the render calls' sizes.
      done = finished(v);
      out[2 * f] += s * v.gain_left;
      out[2 * f + 1] += s * v.gain_right;
      m.kind_mix[k * kChunk + f] += 0.5f * s * (v.gain_left + v.gain_right);
      first_active[k] = std::min(first_active[k], static_cast<std::uint32_t>(f));
      last_active[k] = std::max(last_active[k], static_cast<std::uint32_t>(f + 1));
    }
    if (bad) ++m.nonfinite;
    // Ended voices leave in place (the order of the others, hence of the sum, is kept): the output
    // does not depend on where render calls split the stream.
    if (bad || done) {
      m.voices.erase(m.voices.begin() + static_cast<std::ptrdiff_t>(i));
    } else {
      ++i;
    }
  }
  const float volume = m.params.volume;
  for (std::size_t k = 0; k < kSoundKinds; ++k) {
    if (first_active[k] >= last_active[k]) continue;
    KindStats& s = m.stats[k];
    active[k] = last_active[k] - first_active[k];
    s.active_frames += active[k];
    for (std::uint32_t f = first_active[k]; f < last_active[k]; ++f) {
      const float x = volume * m.kind_mix[k * kChunk + f];
      s.sum_squares += static_cast<double>(x) * x;
      s.peak = std::max(s.peak, std::abs(x));
    }
  }
  // Master: volume, then a peak limiter with an instant attack (never over `limit`) and a 100 ms
  // release, so a blast next to the listener ducks the mix instead of clipping it.
  const float release = 1.0f - std::exp(-1.0f / (0.1f * rate));
  const float limit = m.params.limit;
  for (std::size_t f = 0; f < frames; ++f) {
    float& l = out[2 * f];
    float& r = out[2 * f + 1];
    l *= volume;
    r *= volume;
    const float peak = std::max(std::abs(l), std::abs(r));
    float g = m.limiter_gain + release * (1.0f - m.limiter_gain);
    if (peak * g > limit) g = limit / peak;
    m.limiter_gain = g;
    l *= g;
    r *= g;
    if (!(std::abs(l) <= 1.0f) || !(std::abs(r) <= 1.0f)) {
      ++m.clipped;
      l = std::isfinite(l) ? std::clamp(l, -1.0f, 1.0f) : 0.0f;
      r = std::isfinite(r) ? std::clamp(r, -1.0f, 1.0f) : 0.0f;
    }
    if (m.params.mute) l = r = 0.0f;
  }
  m.clock += static_cast<std::int64_t>(frames);
}

}  // namespace

std::string_view soundKindName(SoundKind kind) {
  switch (kind) {
    case SoundKind::drop:
      return "drop";
    case SoundKind::jet:
      return "jet";
    case SoundKind::pump:
      return "pump";
    case SoundKind::goo:
      return "goo";
    case SoundKind::crate:
      return "crate";
    case SoundKind::crate_splash:
      return "crate_splash";
    case SoundKind::blast:
      return "blast";
    case SoundKind::count:
      break;
  }
  return "?";
}

float minnaertFrequency(float radius) {
  // sqrt(3 gamma p0 / rho) / (2 pi) with gamma = 1.4, p0 = 101325 Pa, rho = 998 kg/m^3: 3.26 m/s.
  constexpr float kMinnaert = 3.26f;
  return radius > 0.0f && std::isfinite(radius) ? kMinnaert / radius : 0.0f;
}

float bubbleDecayRate(float frequency) { return 0.043f * frequency + 0.0014f * frequency * std::sqrt(frequency); }

void initMixer(Mixer& mixer, const MixerParams& params) {
  const std::lock_guard<std::mutex> hold(mixer.lock);
  mixer.params = params;
  mixer.params.sample_rate = std::clamp(params.sample_rate, 8000, 96000);
  mixer.params.max_voices = std::clamp(params.max_voices, 1, 4096);
  setMixerLive(mixer, params);  // the live clamps (it takes no lock: it only writes fields)
  mixer.pending.clear();
  mixer.pending.reserve(mixer.max_pending);
  mixer.voices.clear();
  mixer.voices.reserve(static_cast<std::size_t>(mixer.params.max_voices));
  mixer.clock = 0;
  mixer.limiter_gain = 1.0f;
  mixer.stats = {};
  mixer.kind_mix.assign(kSoundKinds * kChunk, 0.0f);
  mixer.clipped = mixer.nonfinite = 0;
  mixer.meter_peak = mixer.meter_rms = 0.0f;
  mixer.meter_voices = 0;
}

void setMixerLive(Mixer& mixer, const MixerParams& params) {
  MixerParams& p = mixer.params;
  p.volume = std::isfinite(params.volume) ? std::clamp(params.volume, 0.0f, 4.0f) : 0.0f;
  p.mute = params.mute;
  p.xi = std::isfinite(params.xi) ? std::clamp(params.xi, 0.0f, 1.0f) : 0.1f;
  p.speed_of_sound = std::isfinite(params.speed_of_sound) ? std::clamp(params.speed_of_sound, 0.0f, 10000.0f) : 343.0f;
  p.reference_distance =
      std::isfinite(params.reference_distance) ? std::clamp(params.reference_distance, 0.1f, 100.0f) : 2.0f;
  p.limit = std::isfinite(params.limit) ? std::clamp(params.limit, 0.05f, 1.0f) : 0.89f;
}

void setListener(Mixer& mixer, const Listener& listener) {
  const std::lock_guard<std::mutex> hold(mixer.lock);
  mixer.listener = listener;
}

void queueSounds(Mixer& mixer, std::span<const SoundEvent> events) {
  const std::lock_guard<std::mutex> hold(mixer.lock);
  for (const SoundEvent& e : events) {
    if (mixer.pending.size() < mixer.max_pending) {
      mixer.pending.push_back(e);
    } else {
      KindStats& s = mixer.stats[static_cast<std::size_t>(e.kind)];
      ++s.events;
      ++s.dropped;
    }
  }
}

void renderMixer(Mixer& mixer, float* out, std::size_t frames) {
  const std::lock_guard<std::mutex> hold(mixer.lock);
  for (const SoundEvent& e : mixer.pending) addVoice(mixer, e);
  mixer.pending.clear();
  float peak = 0.0f;
  double sum = 0.0;
  for (std::size_t done = 0; done < frames;) {
    const std::size_t n = std::min(kChunk, frames - done);
    renderChunk(mixer, out + 2 * done, n);
    for (std::size_t i = 2 * done; i < 2 * (done + n); ++i) {
      peak = std::max(peak, std::abs(out[i]));
      sum += static_cast<double>(out[i]) * out[i];
    }
    done += n;
  }
  mixer.meter_peak.store(peak, std::memory_order_relaxed);
  mixer.meter_voices.store(static_cast<std::uint32_t>(mixer.voices.size()), std::memory_order_relaxed);
  mixer.meter_rms.store(frames > 0 ? static_cast<float>(std::sqrt(sum / (2.0 * frames))) : 0.0f,
                        std::memory_order_relaxed);
}

}  // namespace engine::audio
