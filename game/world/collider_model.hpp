#pragma once
// Model input of the depth-map colliders (`fluiddemo bake-collider`, the level caches, the blob's
// street; defined in collider_model.cpp): every triangle of
// a model file read with assimp, node transforms applied, checked for what a depth-map collider
// needs (fluid/collide/mesh_checks.hpp). Also used by the fuzz targets (tests/fuzz).

#include "fluid/collide/collider_cache.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace game {

struct ColliderModel {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;  // 3 per triangle
};

// Reads `path` (any format assimp reads). Only regular files are opened, the model and the
// files it names (materials, buffers), never devices or pipes. Fails with "PATH: ..." when the
// file cannot be read, has no triangles, or a vertex is non-finite or beyond
// fluid::kMaxColliderCoordinate (the message names the mesh, the vertex and its coordinates).
bool loadColliderModel(const std::string& path, ColliderModel& out, std::string& error);

// The same from memory, `extension` (e.g. "obj") choosing the importer; `label` names it in
// messages. Files the model refers to are not opened.
bool loadColliderModelFromMemory(std::span<const std::uint8_t> bytes, const std::string& extension,
                                 const std::string& label, ColliderModel& out, std::string& error);

// "" when the mesh is closed, else the message for an open one ("LABEL: the mesh is open: ...").
std::string openMeshMessage(const ColliderModel& model, const std::string& label);

// loadColliderModel as the loader of fluid::loadOrBakeCollider / fluid::loadLevelColliders
// (fluid/collide/collider_cache.hpp), which read no model formats themselves. An open mesh is
// an error here (a collider cache never bakes one).
fluid::ModelLoader colliderModelLoader();

}  // namespace game
