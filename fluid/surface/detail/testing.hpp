#pragma once
// Internal test hook: exposes one block's 2D-projection 1D-lookup particle cache (paper §6) so
// tests can compare every lookup with brute force. Not for production use.

#include "fluid/surface/detail/field.hpp"

#include <memory>
#include <vector>

namespace fluid::detail {

class BlockCacheProbe {
 public:
  // Builds the cache of block (bx, by, bz) of a grid of blockCubes-sized blocks starting at
  // lattice index 0 (the same cache code extract() uses; extract() fits its grid to the data).
  BlockCacheProbe(const SurfaceInput& input, const SurfaceParams& params, int bx, int by, int bz);
  ~BlockCacheProbe();
  BlockCacheProbe(const BlockCacheProbe&) = delete;
  BlockCacheProbe& operator=(const BlockCacheProbe&) = delete;

  // Input indices of the particles the cache returns at local corner (x, y, z), 0 <= x,y,z <= n,
  // in the order the field sums them.
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found);

  int n = 0;                        // cubes per expanded block edge
  int margin = 0;                   // margin cubes; local corner 0 is lattice index b * blockCubes - margin
  std::vector<Particle> particles;  // all particles, prepared (sorted by (z, index))

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fluid::detail
