#include "engine/audio/device.hpp"

#include <SDL.h>

namespace engine::audio {
namespace {

void pull(void* user, Uint8* stream, int bytes) {
  auto* mixer = static_cast<Mixer*>(user);
  renderMixer(*mixer, reinterpret_cast<float*>(stream), static_cast<std::size_t>(bytes) / (2 * sizeof(float)));
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
  SDL_AudioSpec want{};
  want.freq = mixer.params.sample_rate;
  want.format = AUDIO_F32SYS;
  want.channels = 2;
  want.samples = 512;  // about 23 ms at 22.05 kHz
  want.callback = &pull;
  want.userdata = &mixer;
  SDL_AudioSpec have{};
  // No changes allowed: SDL converts if the hardware wants another rate or format.
  const SDL_AudioDeviceID id = SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
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
  device.subsystem = false;
}

}  // namespace engine::audio
