// Every effect the game knows, in build and step order: an effect may read what the effects
// above it publish (EffectLinks), and steps after them. One line per effect.
#include "game/effects/effect.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <vector>

namespace game {

const EffectDesc& rigidBodiesEffect();
const EffectDesc& explosivesEffect();
const EffectDesc& sphFluidEffect();
const EffectDesc& spriteParticlesEffect();
const EffectDesc& fluidSurfaceEffect();
const EffectDesc& blobEffect();
const EffectDesc& gullsEffect();
const EffectDesc& audioEffect();

std::span<const EffectDesc* const> effectRegistry() {
  static const std::array kEffects = {
      &rigidBodiesEffect(),      // publishes gravity and the crates
      &explosivesEffect(),       // fuses after the physics step; publishes this step's blasts
      &sphFluidEffect(),         // couples to the crates; publishes the particles
      &spriteParticlesEffect(),  // sprays from this step's particles
      &fluidSurfaceEffect(),     // meshes the particles per frame
      &blobEffect(),             // the blob monster: crates both ways, this step's blasts, chases the player
      &gullsEffect(),            // circle over the fountain, scatter from this step's blasts
      &audioEffect(),            // hears what every effect above did this step (output only)
  };
  return kEffects;
}

const EffectDesc* findEffectDesc(std::string_view name) {
  for (const EffectDesc* desc : effectRegistry())
    if (desc->name == name) return desc;
  return nullptr;
}

std::span<const ColumnSpec> frameColumnCatalogue() {
  static const std::vector<ColumnSpec> catalogue = [] {
    std::vector<ColumnSpec> columns;
    for (const EffectDesc* desc : effectRegistry())
      for (const ColumnSpec& column : desc->columns) {
        const auto same = [&](const ColumnSpec& c) { return c.name == column.name; };
        const auto known = std::find_if(columns.begin(), columns.end(), same);
        assert(known == columns.end() || known->format == column.format);  // one column, one format
        if (known == columns.end()) columns.push_back(column);
      }
    return columns;
  }();
  return catalogue;
}

int frameColumnIndex(std::string_view name) {
  const std::span<const ColumnSpec> columns = frameColumnCatalogue();
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].name == name) return static_cast<int>(i);
  return -1;
}

void FrameColumns::set(std::string_view name, double value) {
  const int index = frameColumnIndex(name);
  assert(index >= 0 && "FrameColumns::set: a column no effect declares");
  if (index >= 0) values[static_cast<std::size_t>(index)] = value;
}

void FrameColumns::add(std::string_view name, double value) {
  const int index = frameColumnIndex(name);
  assert(index >= 0 && "FrameColumns::add: a column no effect declares");
  if (index >= 0) values[static_cast<std::size_t>(index)] += value;
}

double FrameColumns::get(std::string_view name) const {
  const int index = frameColumnIndex(name);
  return index >= 0 ? values[static_cast<std::size_t>(index)] : 0.0;
}

}  // namespace game
