#pragma once
// The voxel renderer's GPU stages against fluid/surface/voxel_reference's CPU ones, shared by the
// sphere tests (test_voxel.cpp) and the ellipsoid tests (test_voxel_aniso.cpp): every tile's
// splatted bits, then every pixel's compressed spans, must be the reference's exactly.
#include "engine/fluid_render/voxel.hpp"
#include "fluid/surface/voxel_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace voxel_test {

// The CPU bits of one tile (voxelizeReference of the spheres or of the ellipsoids).
using ReferenceBits = std::function<void(const fluid::VoxelTile&, std::vector<std::uint32_t>&)>;

// Splats and compresses every tile on the GPU, comparing each tile's bits with `reference`'s;
// returns the number of bits set (so a caller can check the scene was not empty).
inline std::uint64_t splatTilesLikeTheReference(engine::VoxelRenderer& r, const engine::VoxelParams& params,
                                                std::span<const fluid::VoxelTile> tiles,
                                                const ReferenceBits& reference) {
  std::uint64_t set_bits = 0;
  for (const fluid::VoxelTile& tile : tiles) {
    engine::voxelSplatTile(r, params, tile);
    std::vector<std::uint32_t> gpu, cpu;
    engine::readVoxelTileBits(r, tile, gpu);
    reference(tile, cpu);
    EXPECT_EQ(gpu.size(), cpu.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < gpu.size() && i < cpu.size(); ++i) {
      differ += gpu[i] != cpu[i];
      set_bits += static_cast<std::uint64_t>(__builtin_popcount(cpu[i]));
    }
    EXPECT_EQ(differ, 0u) << "tile " << tile.x << "," << tile.y;
    engine::voxelCompressTile(r, params, tile);
  }
  return set_bits;
}

struct SpanCounts {
  std::size_t overflowing = 0;  // columns with more spans than they store (the hidden gap used)
  std::size_t near_cut = 0;     // columns whose first span starts at the near plane
  std::size_t covered = 0;      // columns with water
};

// Every pixel's spans read back from the GPU against the CPU compression of `all`, the reference
// bits of the whole width x height screen as one tile. Stops at the first column whose span
// counts differ (a fatal failure; the caller checks HasFatalFailure()).
inline void expectSpansLikeTheReference(const engine::VoxelRenderer& r, const engine::VoxelDesc& desc,
                                        const engine::VoxelParams& params, int width, int height,
                                        std::span<const std::uint32_t> all, SpanCounts& counts) {
  std::vector<fluid::VoxelSpan> spans;
  std::vector<fluid::VoxelColumn> columns;
  engine::readVoxelSpans(r, spans, columns);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * width + x;
      const glm::vec3 ray = fluid::voxelPixelRay(r.view, x, y);
      const float ray_length = std::sqrt(ray.x * ray.x + ray.y * ray.y + ray.z * ray.z);
      fluid::VoxelSpan ref[7];
      fluid::VoxelColumn ref_column;
      fluid::compressColumnReference(all.subspan(i * r.layers.words, r.layers.words), r.layers, params.min_gap,
                                     ray_length, desc.max_spans, ref, ref_column);
      const fluid::VoxelColumn& got = columns[i];
      ASSERT_EQ(got.stored, ref_column.stored) << "pixel " << x << "," << y;
      ASSERT_EQ(got.total, ref_column.total) << "pixel " << x << "," << y;
      EXPECT_EQ(got.hidden_gap, ref_column.hidden_gap) << "pixel " << x << "," << y;
      for (std::uint32_t s = 0; s < got.stored; ++s) {
        EXPECT_EQ(spans[i * desc.max_spans + s].entry, ref[s].entry) << "pixel " << x << "," << y << " span " << s;
        EXPECT_EQ(spans[i * desc.max_spans + s].exit, ref[s].exit) << "pixel " << x << "," << y << " span " << s;
      }
      counts.overflowing += got.total > got.stored;
      counts.near_cut += got.stored > 0 && ref[0].entry == 0;
      counts.covered += got.stored > 0;
    }
  }
}

}  // namespace voxel_test
