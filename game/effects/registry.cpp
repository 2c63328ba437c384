// Every effect the game knows, in build and step order: an effect may read what the effects
// above it publish (EffectLinks), and steps after them. One line per effect.
#include "game/effects/effect.hpp"

#include <array>

namespace game {

const EffectDesc& rigidBodiesEffect();
const EffectDesc& explosivesEffect();
const EffectDesc& sphFluidEffect();
const EffectDesc& spriteParticlesEffect();
const EffectDesc& fluidSurfaceEffect();
const EffectDesc& blobEffect();
const EffectDesc& audioEffect();

std::span<const EffectDesc* const> effectRegistry() {
  static const std::array kEffects = {
      &rigidBodiesEffect(),      // publishes gravity and the crates
      &explosivesEffect(),       // fuses after the physics step; publishes this step's blasts
      &sphFluidEffect(),         // couples to the crates; publishes the particles
      &spriteParticlesEffect(),  // sprays from this step's particles
      &fluidSurfaceEffect(),     // meshes the particles per frame
      &blobEffect(),             // the blob monster: crates both ways, this step's blasts, chases the player
      &audioEffect(),            // hears what every effect above did this step (output only)
  };
  return kEffects;
}

const EffectDesc* findEffectDesc(std::string_view name) {
  for (const EffectDesc* desc : effectRegistry())
    if (desc->name == name) return desc;
  return nullptr;
}

}  // namespace game
