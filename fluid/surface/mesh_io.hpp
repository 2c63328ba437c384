#pragma once
// Writing SurfaceMesh to disk (used by `fluiddemo mesh`).
//   .obj  text: "v x y z", "vn x y z", "f a//a b//b c//c" (1-based), counter-clockwise outward
//   .ply  binary little-endian: vertex (float x y z nx ny nz), face (uchar count, uint indices)
//   .vtk  legacy VTK, binary POLYDATA with point normals; .vtu  VTK XML UnstructuredGrid (ASCII)
// Positions are written as stored plus the origin the mesh was made with (world units).
// Seam vertices duplicated by block subdivision are welded (equal SurfaceMesh::edgeKeys with
// equal positions), so the file is one closed, indexed mesh. Existing files are not replaced
// unless asked.

#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fluid {

struct MeshWriteOptions {
  OverwritePolicy overwrite = OverwritePolicy::refuse;
  bool weldSeams = true;
  double originX = 0.0, originY = 0.0, originZ = 0.0;  // added back to positions
};

// The mesh as written: block seams welded (when options.weldSeams), vertices in first-use order,
// positions plus the options' origin. writeSurfaceMesh writes exactly these arrays.
struct WeldedMesh {
  std::vector<glm::vec3> positions, normals;
  std::vector<std::uint32_t> indices;  // 3 per triangle, counter-clockwise seen from outside
};
void weldSurfaceMesh(const SurfaceMesh& mesh, const MeshWriteOptions& options, WeldedMesh& out);

// What `fluiddemo mesh` does around SurfaceExtractor::extract, shared with the Python module so
// both give the same bits. Sets params.origin* to the lattice point (a multiple of params.cube)
// nearest the centre of the particles' bounds, so float vertices stay precise far from zero
// without moving the lattice (unchanged for no particles).
void centreSurfaceOrigin(const SurfaceInput& input, SurfaceParams& params);

// Empty when params.threshold can be reached; else the message saying it cannot (the mesh would
// be empty), naming the option as the caller calls it (`option`, e.g. "--threshold") and the
// particles' source (`source`, e.g. the file name). Any T < 1/4 is reached at a lone particle.
std::string unreachableThreshold(const SurfaceInput& input, const SurfaceParams& params, const std::string& option,
                                 const std::string& source);

// Format from the extension (.obj, .ply, .vtk or .vtu, case-insensitive); anything else is an error.
IoStatus writeSurfaceMesh(const std::filesystem::path& path, const SurfaceMesh& mesh,
                          const MeshWriteOptions& options = {});

}  // namespace fluid
