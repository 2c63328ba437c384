#pragma once
// The live audio device: SDL pulls the mixer (engine/audio/synth.hpp) from its audio thread, the
// same renderMixer the offline render calls. Where there is no sound card SDL's dummy or disk
// driver stands in (SDL_AUDIODRIVER=dummy); a device that cannot open leaves the game silent, never
// stopped.

#include "engine/audio/synth.hpp"

#include <cstdint>
#include <string>

namespace engine::audio {

struct AudioDevice {
  std::uint32_t id = 0;    // SDL_AudioDeviceID; 0 = not open
  bool subsystem = false;  // this device initialised SDL's audio subsystem (quit on close)
  bool dummy = false;      // no sound card: SDL_AudioInit("dummy") stands in (SDL_AudioQuit on close)
  Mixer* mixer = nullptr;  // pulled by the callback; outlives the device
  std::string driver;      // SDL's driver name, for the overlay
};

// Opens the default output as stereo float at the mixer's sample rate and starts it; when no sound
// card opens and SDL_AUDIODRIVER is unset, SDL's dummy driver instead (driver "dummy"). False +
// message (SDL's) when nothing opens; `device` is then closed.
bool openAudioDevice(AudioDevice& device, Mixer& mixer, std::string& error);
// Stops the callback (it is not running when this returns) and closes the device.
void closeAudioDevice(AudioDevice& device);

}  // namespace engine::audio
