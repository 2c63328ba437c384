#pragma once
// VTK files: particles in and out (legacy .vtk), triangle meshes out (legacy .vtk and XML .vtu),
// readable by ParaView and VTK 9.
//   particles in   legacy "# vtk DataFile Version x.y", ASCII or BINARY (big-endian, as VTK
//                  writes it), any DATASET holding POINTS (POLYDATA, UNSTRUCTURED_GRID, ...):
//                  the points are the particles, float or double; the rest of the file is ignored.
//                  readParticleFile and parseParticleVtk (particle_io.hpp) read them.
//   particles out  legacy POLYDATA with POINTS and one VERTICES cell per particle.
//   meshes out     legacy BINARY POLYDATA (POINTS, POLYGONS, POINT_DATA NORMALS), or
//                  .vtu UnstructuredGrid (ASCII XML, VTK_TRIANGLE cells, point data "Normals").
// Errors name the file and the line (text) or the point (binary) and never crash.

#include "fluid/io/particle_io.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <span>
#include <string>

namespace fluid {

enum class VtkEncoding { ascii, binary };

IoStatus writeParticleVtk(const std::filesystem::path& path, const ParticlePositions& particles,
                          VtkEncoding encoding = VtkEncoding::binary,
                          OverwritePolicy overwrite = OverwritePolicy::refuse);

// An indexed triangle mesh as plain arrays (3 indices per triangle, one normal per position).
struct TriangleMeshView {
  std::span<const glm::vec3> positions;
  std::span<const glm::vec3> normals;
  std::span<const std::uint32_t> indices;
};

// Stream writers (the caller opened `out` in binary mode); mesh_io.cpp picks by extension.
void writeMeshLegacyVtk(std::ostream& out, const TriangleMeshView& mesh);
void writeMeshVtu(std::ostream& out, const TriangleMeshView& mesh);

}  // namespace fluid
