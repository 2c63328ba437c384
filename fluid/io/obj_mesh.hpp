#pragma once
// Triangle meshes from Wavefront OBJ text, for baking colliders without a model importer
// (the examples, the Python module). Reads the polygonal subset:
//   v x y z [w]         positions (w ignored)
//   f a b c ...         faces of 3 or more vertices (a, a/t, a//n, a/t/n; 1-based or negative =
//                       relative to the end), fanned into triangles around the first vertex
// vt, vn, o, g, s, usemtl, mtllib, l, p and '#' comments are skipped; anything else is an error.
// Errors name the file and 1-based line; a file with no face is an error (nothing to bake).
// Winding is kept as written (fluid/collide's baker flips a mesh wound inward throughout).

#include "fluid/io/particle_io.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace fluid {

struct ObjMesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;  // 3 per triangle, each < positions.size()
};

// Reads `path` into `out` (cleared first; left empty on failure).
IoStatus readObjMesh(const std::filesystem::path& path, ObjMesh& out);

// Parses OBJ `text`; `name` is used in messages.
IoStatus parseObjMesh(const std::string& text, const std::string& name, ObjMesh& out);

}  // namespace fluid
