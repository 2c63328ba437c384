// State hashes of a World (contract and coverage: state_hash.hpp).
#include "game/replay/state_hash.hpp"

#include "game/world/world.hpp"

namespace game {

void hashWorldState(const World& world, StateHashScratch& scratch, StateHash& out) {
  out.parts.clear();
  for (const std::unique_ptr<Effect>& effect : world.effects) {
    Fnv1a64 part;
    if (effect->hashState(part, scratch)) out.parts.push_back({effect->name(), part.value});
  }
  Fnv1a64 h;
  h.add(world.steps);
  for (const SubsystemHash& part : out.parts) {
    h.bytes(part.name.data(), part.name.size());
    h.add(part.value);
  }
  out.combined = h.value;
}

}  // namespace game
