#include "engine/audio/device.hpp"

#include <SDL.h>

#include <cstdlib>

namespace engine::audio {
namespace {

void pull(void* user, Uint8* stream, int bytes) {
  auto* mixer = static_cast<Mixer*>(user);
  renderMixer(*mixer, reinterpret_cast<float*>(stream), static_cast<std::size_t>(bytes) / (2 * sizeof(float)));
}

SDL_AudioDeviceID openDefault(Mixer& mixer) {
  SDL_AudioSpec want{};
  want.freq = mixer.params.sample_rate;
  want.format = AUDIO_F32SYS;
  want.channels = 2;
  want.samples = 512;  // about 23 ms at 22.05 kHz
  want.callback = &pull;
  want.userdata = &mixer;
  SDL_AudioSpec have{};
  // No changes allowed: SDL converts if the hardware wants another rate or format.
  return SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
}

}  // namespace

bool openAudioDevice(AudioDevice& device, Mixer& mixer, std::string& error) {
  closeAudioDevice(device);
  if (SDL_WasInit(SDL_INIT_AUDIO) == 0) {
    if (SDL_InitSubSystem(SDL_INIT_AUDIO) != 0) {
      error = std::string("SDL audio: ") + SDL_GetError();
      return false;
    }
    device.subsystem = true;
  }
  SDL_AudioDeviceID id = openDefault(mixer);
  // No sound card (a server, CI): unless the user chose a driver, fall back to SDL's dummy
  // driver, which pulls the callback in real time and discards the samples, so the game runs the
  // same with or without one.
  const char* chosen = std::getenv("SDL_AUDIODRIVER");
  if (id == 0 && device.subsystem && (chosen == nullptr || *chosen == '\0')) {
    error = std::string("SDL audio: ") + SDL_GetError();
    SDL_QuitSubSystem(SDL_INIT_AUDIO);
    device.subsystem = false;
    if (SDL_AudioInit("dummy") == 0) {
      device.dummy = true;
      id = openDefault(mixer);
    }
  }
  if (id == 0) {
    error = std::string("SDL audio: ") + SDL_GetError();
    closeAudioDevice(device);
    return false;
  }
  device.id = id;
  device.mixer = &mixer;
  const char* driver = SDL_GetCurrentAudioDriver();
  device.driver = driver ? driver : "?";
  SDL_PauseAudioDevice(id, 0);
  return true;
}

void closeAudioDevice(AudioDevice& device) {
  if (device.id != 0) SDL_CloseAudioDevice(device.id);  // waits for a running callback
  device.id = 0;
  device.mixer = nullptr;
  if (device.subsystem) SDL_QuitSubSystem(SDL_INIT_AUDIO);
  if (device.dummy) SDL_AudioQuit();
  device.subsystem = device.dummy = false;
}

}  // namespace engine::audio
