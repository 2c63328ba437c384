#pragma once
// What an effect reports outside the frame it draws, declared in its own file and looped over by
// the readers: the replay's state hash (Effect::hashState), the replay CSV's columns
// (EffectDesc::columns, Effect::reportColumns) and the soak checks (Effect::soakCheck). The
// readers (game/replay/state_hash.cpp, game/replay/frame_times.cpp, game/soak_monitor.cpp) name
// no effect.

#include "fluid/core/fnv1a.hpp"

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace game {

using Fnv1a64 = fluid::Fnv1a64;  // fluid/core/fnv1a.hpp

inline void hashVec3(Fnv1a64& h, const glm::vec3& v) {
  h.add(v.x);
  h.add(v.y);
  h.add(v.z);
}

inline void hashQuat(Fnv1a64& h, const glm::quat& q) {
  h.add(q.x);
  h.add(q.y);
  h.add(q.z);
  h.add(q.w);
}

// Caller-owned scratch so hashing every checkpoint allocates nothing after the first.
struct StateHashScratch {
  std::vector<std::uint32_t> order;
};

// How a column's value is written: counts as integers, times with 4 decimals, ratios with 9
// significant digits (a float survives the text round trip), depths with 6, flags as 0/1.
enum class ColumnFormat { count, milliseconds, ratio, millimetres, flag };

struct ColumnSpec {
  std::string_view name;
  ColumnFormat format = ColumnFormat::count;
  std::string_view doc;  // docs/replay.md's column table
};

// Every effect's columns in registry order; a name two effects declare is one column holding
// their sum (the water's and the goo's triangles). Built once from the registry.
std::span<const ColumnSpec> frameColumnCatalogue();
// The column's index in the catalogue; -1 when no effect declares it.
int frameColumnIndex(std::string_view name);

// One frame's values of the catalogue's columns (0 where no listed effect fills one).
struct FrameColumns {
  std::vector<double> values = std::vector<double>(frameColumnCatalogue().size(), 0.0);
  // The effect's own columns only: an undeclared name is a programming error (assert).
  void set(std::string_view name, double value);
  void add(std::string_view name, double value);
  double get(std::string_view name) const;  // 0 for an undeclared name
};

struct SoakProbe;  // game/soak_checks.hpp

}  // namespace game
