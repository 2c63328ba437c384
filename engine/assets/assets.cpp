#include "engine/assets/assets.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <stb_image.h>
#include <assimp/Importer.hpp>

#include <cmath>
#include <system_error>

namespace engine {
namespace {

bool checkReadable(const std::filesystem::path& path, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    error = path.string() + ": file not found";
    return false;
  }
  if (std::filesystem::file_size(path, ec) == 0 || ec) {
    error = path.string() + ": file is empty";
    return false;
  }
  return true;
}

glm::mat4 toGlm(const aiMatrix4x4& m) {
  // assimp is row-major, glm column-major.
  return glm::mat4(m.a1, m.b1, m.c1, m.d1, m.a2, m.b2, m.c2, m.d2, m.a3, m.b3, m.c3, m.d3, m.a4, m.b4, m.c4, m.d4);
}

void appendNode(const aiScene& scene, const aiNode& node, const glm::mat4& parent, MeshData& out) {
  const glm::mat4 transform = parent * toGlm(node.mTransformation);
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      out.positions.push_back(glm::vec3(transform * glm::vec4(p.x, p.y, p.z, 1.0f)));
      glm::vec3 n(0.0f, 1.0f, 0.0f);
      if (mesh.mNormals != nullptr) {
        n = normal_matrix * glm::vec3(mesh.mNormals[v].x, mesh.mNormals[v].y, mesh.mNormals[v].z);
        const float length = glm::length(n);
        n = length > 1e-12f ? n / length : glm::vec3(0.0f, 1.0f, 0.0f);
      }
      out.normals.push_back(n);
      if (mesh.mTextureCoords[0] != nullptr) {
        out.uvs.emplace_back(mesh.mTextureCoords[0][v].x, mesh.mTextureCoords[0][v].y);
      } else {
        out.uvs.emplace_back(0.0f, 0.0f);
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points/lines left after triangulation
      for (unsigned i = 0; i < 3; ++i) out.indices.push_back(base + face.mIndices[i]);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) appendNode(scene, *node.mChildren[c], transform, out);
}

}  // namespace

bool loadMesh(const std::filesystem::path& path, MeshData& out, std::string& error) {
  out = MeshData{};
  if (!checkReadable(path, error)) return false;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                              aiProcess_GenSmoothNormals | aiProcess_FlipUVs |
                                                              aiProcess_SortByPType | aiProcess_ValidateDataStructure);
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    error = path.string() + ": cannot load model (" + importer.GetErrorString() + ")";
    return false;
  }
  appendNode(*scene, *scene->mRootNode, glm::mat4(1.0f), out);
  if (out.indices.empty()) {
    error = path.string() + ": model has no triangles";
    out = MeshData{};
    return false;
  }
  out.bounds_min = glm::vec3(INFINITY);
  out.bounds_max = glm::vec3(-INFINITY);
  for (std::size_t i = 0; i < out.positions.size(); ++i) {
    const glm::vec3& p = out.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      error = path.string() + ": vertex " + std::to_string(i) + " has a non-finite coordinate";
      out = MeshData{};
      return false;
    }
    out.bounds_min = glm::min(out.bounds_min, p);
    out.bounds_max = glm::max(out.bounds_max, p);
  }
  return true;
}

bool loadImage(const std::filesystem::path& path, ImageData& out, std::string& error) {
  out = ImageData{};
  if (!checkReadable(path, error)) return false;
  int width = 0, height = 0, channels = 0;
  stbi_uc* pixels = stbi_load(path.string().c_str(), &width, &height, &channels, 4);
  if (pixels == nullptr) {
    const char* reason = stbi_failure_reason();
    error = path.string() + ": cannot decode image (" + (reason ? reason : "unknown reason") + ")";
    return false;
  }
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    stbi_image_free(pixels);
    error = path.string() + ": unsupported image size " + std::to_string(width) + "x" + std::to_string(height);
    return false;
  }
  out.width = width;
  out.height = height;
  out.rgba.assign(pixels, pixels + static_cast<std::size_t>(width) * height * 4);
  stbi_image_free(pixels);
  return true;
}

}  // namespace engine
