#pragma once
// Internal test hook: exposes one block's 2D-projection 1D-lookup particle cache (paper §6) so
// tests can compare every lookup with brute force. Not for production use.

#include "fluid/surface/detail/field.hpp"

#include <vector>

namespace fluid::detail {

class BlockCacheProbe {
 public:
  // Builds the cache of block (bx, by, bz) exactly as extract() would (same particles, margin).
  BlockCacheProbe(const SurfaceInput& input, const SurfaceParams& params, int bx, int by, int bz);
  ~BlockCacheProbe();
  BlockCacheProbe(const BlockCacheProbe&) = delete;
  BlockCacheProbe& operator=(const BlockCacheProbe&) = delete;

  // Input indices of the particles the cache returns at local corner (x, y, z), 0 <= x,y,z <= n.
  void lookup(int x, int y, int z, std::vector<std::uint32_t>& found);

  int n = 0;       // cubes per expanded block edge
  int margin = 0;  // margin cubes
  // Global lattice index of local corner 0 on each axis is b * blockCubes - margin.

 private:
  std::vector<Particle> particles_, blockParticles_;
  void* setup_ = nullptr;
  void* worker_ = nullptr;
  void* out_ = nullptr;
  void* block_ = nullptr;
  void* mesher_ = nullptr;
};

}  // namespace fluid::detail
