#pragma once
// Asset loading: triangle meshes through assimp (OBJ, glTF, ...) and PNG images through
// stb_image. A missing, truncated or corrupt file gives `false` and an error naming the file;
// nothing here throws or crashes on bad content.

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace engine {

// Indexed triangle mesh, all of a file's meshes merged in world (file) space.
// positions/normals/uvs have the same length; indices.size() is a multiple of 3.
struct MeshData {
  std::vector<glm::vec3> positions;  // model units (our content: metres, y up)
  std::vector<glm::vec3> normals;    // unit length (generated smooth if the file has none)
  std::vector<glm::vec2> uvs;        // (0,0) where the file has none; v already flipped for GL
  std::vector<std::uint32_t> indices;
  glm::vec3 bounds_min{0.0f};
  glm::vec3 bounds_max{0.0f};
};

// RGBA8, top row first (as stored in the file).
struct ImageData {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
};

// Fails on: missing file, a file assimp cannot parse, no triangles, a non-finite coordinate.
bool loadMesh(const std::filesystem::path& path, MeshData& out, std::string& error);

// Fails on: missing file, undecodable data, zero size or more than 16384 pixels per side.
bool loadImage(const std::filesystem::path& path, ImageData& out, std::string& error);

}  // namespace engine
