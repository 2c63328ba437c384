#pragma once
// Particle position files shared by every command that reads or writes particles
// (`fluiddemo mesh`, `simulate`, `query-collider`) and by the tests and benchmarks.
//
// Formats, chosen by extension (case-insensitive):
//   .xyz  one particle per line, "x y z" separated by spaces/tabs; blank lines and lines
//         starting with '#' are ignored; extra columns after z are ignored.
//   .csv  "x,y,z" per line; an optional first header row is allowed when it names the
//         columns (x, y and z are then picked by name, in any order).
//   .ply  ASCII or binary (little/big endian) PLY with a `vertex` element holding float or
//         double properties x, y, z; other properties and elements are skipped.
//   .vtk  legacy VTK, ASCII or BINARY: the POINTS of any dataset (fluid/io/vtk_io.hpp).
// Errors name the file and the 1-based line (text) or vertex index (binary) and never crash.
// NaN/inf coordinates are rejected.

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fluid {

// Particle positions owned by the caller: packed vec3, the layout the SPH store and the goo keep and
// the surface mesher reads in place (fluid::pointView in fluid/surface/marching_slices.hpp).
using ParticlePositions = std::vector<glm::vec3>;

// Empty error == success. The message is complete ("file.xyz:12: ..."), ready to print.
struct IoStatus {
  std::string error;
  bool ok() const { return error.empty(); }
};

// Reads `path` into `out` (cleared first). On failure `out` is left empty.
IoStatus readParticleFile(const std::filesystem::path& path, ParticlePositions& out);

// Parses text in the given format ("xyz" or "csv"); `name` is used in messages.
IoStatus parseParticleText(const std::string& text, const std::string& format, const std::string& name,
                           ParticlePositions& out);

// Parses a whole legacy .vtk file held in `bytes` (fluid/io/vtk_io.hpp says which); `name` is
// used in messages.
IoStatus parseParticleVtk(const std::string& bytes, const std::string& name, ParticlePositions& out);

enum class OverwritePolicy { refuse, replace };

// Writes "x y z" lines with round-trip precision (max_digits10). Refuses to replace an
// existing file unless told to, so nothing a user made is lost silently.
IoStatus writeParticleXyz(const std::filesystem::path& path, const ParticlePositions& particles,
                          OverwritePolicy overwrite = OverwritePolicy::refuse);

// Like writeParticleXyz with a fourth column, the particle's id: "x y z id" per line (ids.size() must
// equal particles.size(), else an error naming the file). Readers of .xyz skip columns after z, so
// the file reads back as positions.
IoStatus writeParticleXyzWithIds(const std::filesystem::path& path, const ParticlePositions& particles,
                                 const std::vector<std::uint32_t>& ids,
                                 OverwritePolicy overwrite = OverwritePolicy::refuse);

// Writes a binary little-endian PLY with float x, y, z.
IoStatus writeParticlePly(const std::filesystem::path& path, const ParticlePositions& particles,
                          OverwritePolicy overwrite = OverwritePolicy::refuse);

}  // namespace fluid
