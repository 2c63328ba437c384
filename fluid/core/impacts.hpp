#pragma once
// Impacts found in particle motion, for sound synthesis (engine/audio, game/effects/audio.cpp):
// a particle that was flying and is suddenly stopped or turned (a drop landing in the pool, the jet
// entering the water, a goo particle slapping a wall) is an impact. Moss, Yeh, Hong, Lin & Manocha
// 2010 ("Sounding Liquids", ACM TOG 29(3)) §4-5 make bubbles where the simulated surface is hit; a
// particle fluid has no surface to read curvature from, so we read the impact from the particle's
// own velocity: its speed at the step's start, carried through the step by gravity alone, against
// its speed at the step's end. What was lost in one step is what the water took from it.
//
// Impacts in the same cell of a grid (cell_size) in one step are one event, as a splash of several
// particles is one bigger drop: its size is the count of particles, its speed their mean. Results
// depend only on the particles' order and values (serial loops, a sort with a total order), so the
// same simulation gives the same impacts at any thread count.

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

struct ImpactParams {
  float min_speed = 1.0f;           // m/s: slower particles make no sound
  float min_speed_loss = 1.2f;      // m/s lost in one step beyond what gravity explains
  float cell_size = 0.25f;          // m: impacts within one cell of this size merge
  std::uint32_t max_id = 1u << 22;  // ids at or above are ignored (the tracker is indexed by id)
};

struct Impact {
  glm::vec3 position{0.0f};  // m: the mean of the merged particles
  float speed = 0.0f;        // m/s: their mean speed before the impact
  float speed_loss = 0.0f;   // m/s: their mean loss
  std::uint32_t particles = 0;
};

// Per particle id: its velocity after the last call, and the call that saw it (an id is known when
// the previous call saw it with a finite velocity; nothing is cleared between calls).
struct ImpactTracker {
  std::vector<glm::vec3> velocity;
  std::vector<std::uint32_t> seen_in;  // call number + 1 of the call that last saw the id; 0 = never
  std::uint32_t calls = 0;
  struct Hit {
    std::uint64_t cell = 0;
    std::uint32_t index = 0;
    float speed = 0.0f, loss = 0.0f;
  };
  std::vector<Hit> hits;  // scratch
};

// Finds this step's impacts among `count` particles read through pointer + stride views (bytes
// between consecutive elements; meshoptimizer's convention), with their ids (null: the index is the
// id). `gravity` (m/s^2) and `dt` (s, the step) say what free flight would have done. Appends to
// `out` (cleared first) in cell order. The tracker then holds the end-of-step velocities; an id
// not present this call is forgotten (a pumped particle comes back as new, not as an impact).
void findImpacts(const glm::vec3* positions, std::size_t position_stride, const glm::vec3* velocities,
                 std::size_t velocity_stride, const std::uint32_t* ids, std::size_t count, glm::vec3 gravity, float dt,
                 const ImpactParams& params, ImpactTracker& tracker, std::vector<Impact>& out);

}  // namespace fluid
