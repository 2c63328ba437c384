#pragma once
// Writing SurfaceMesh to disk (used by `fluiddemo mesh`).
//   .obj  text: "v x y z", "vn x y z", "f a//a b//b c//c" (1-based), counter-clockwise outward
//   .ply  binary little-endian: vertex (float x y z nx ny nz), face (uchar count, uint indices)
// Positions are written as stored plus the origin the mesh was made with (world units).
// Seam vertices duplicated by block subdivision are welded (equal SurfaceMesh::edgeKeys with
// equal positions), so the file is one closed, indexed mesh. Existing files are not replaced
// unless asked.

#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <filesystem>

namespace fluid {

struct MeshWriteOptions {
  OverwritePolicy overwrite = OverwritePolicy::refuse;
  bool weldSeams = true;
  double originX = 0.0, originY = 0.0, originZ = 0.0;  // added back to positions
};

// Format from the extension (.obj or .ply, case-insensitive); anything else is an error.
IoStatus writeSurfaceMesh(const std::filesystem::path& path, const SurfaceMesh& mesh,
                          const MeshWriteOptions& options = {});

}  // namespace fluid
