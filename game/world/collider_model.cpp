// Model files read with assimp for the depth-map colliders (collider_model.hpp).
#include "game/world/collider_model.hpp"

#include "fluid/collide/mesh_checks.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

namespace game {

namespace {

// Opens regular files only: a model that names /dev/zero or a FIFO as its material file must
// not hang the bake. With `none` set nothing is opened at all (models read from memory).
class RegularFilesOnly : public Assimp::DefaultIOSystem {
 public:
  explicit RegularFilesOnly(bool none) : none_(none) {}
  bool Exists(const char* file) const override { return allowed(file) && DefaultIOSystem::Exists(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    return allowed(file) ? DefaultIOSystem::Open(file, mode) : nullptr;
  }

 private:
  bool allowed(const char* file) const {
    std::error_code ec;
    return !none_ && file != nullptr && std::filesystem::is_regular_file(file, ec);
  }
  bool none_;
};

constexpr unsigned kImportFlags =
    aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices | aiProcess_SortByPType;

std::string formatVec(const aiVector3D& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%g, %g, %g)", static_cast<double>(p.x), static_cast<double>(p.y),
                static_cast<double>(p.z));
  return text;
}

// All triangles of all meshes (node transforms applied by aiProcess_PreTransformVertices).
bool convertScene(const aiScene* scene, const Assimp::Importer& importer, const std::string& label, ColliderModel& out,
                  std::string& error) {
  out = {};
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    error = label + ": cannot load model: " + importer.GetErrorString();
    return false;
  }
  const float limit = fluid::kMaxColliderCoordinate;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      const glm::vec3 q{p.x, p.y, p.z};
      if (fluid::firstBadVertex(std::span(&q, 1), limit) >= 0) {
        char bound[32];
        std::snprintf(bound, sizeof bound, "%g", static_cast<double>(limit));
        error = label + ": mesh " + std::to_string(m) + " vertex " + std::to_string(v) + " at " + formatVec(p) +
                (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)
                     ? std::string(" is beyond the collider coordinate limit +-") + bound
                     : std::string(" has a non-finite coordinate"));
        return false;
      }
      out.positions.push_back(q);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines after triangulation
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) {
          error = label + ": mesh " + std::to_string(m) + " face " + std::to_string(f) + " names vertex " +
                  std::to_string(face.mIndices[k]) + " of " + std::to_string(mesh->mNumVertices);
          return false;
        }
        out.indices.push_back(base + face.mIndices[k]);
      }
    }
  }
  if (out.indices.empty()) {
    error = label + ": the model has no triangles";
    return false;
  }
  return true;
}

// ---- OBJ pre-check --------------------------------------------------------------------
// assimp 5.2.5's OBJ importer crashes on some malformed files (libFuzzer found a write through
// a wild pointer for "normals\nmtllib m\n"), and its messages name no line. So an OBJ file is
// read once here first: only the statements of the OBJ format that describe polygonal
// geometry and its grouping are accepted, with numbers where numbers belong and every face,
// line and point index naming an element defined before it (1-based, or negative = relative).
// What passes is plain enough for assimp; what fails gets "FILE:LINE: ...".

std::string_view nextToken(std::string_view& rest) {
  std::size_t i = 0;
  while (i < rest.size() && (rest[i] == ' ' || rest[i] == '\t' || rest[i] == '\r')) ++i;
  std::size_t j = i;
  while (j < rest.size() && rest[j] != ' ' && rest[j] != '\t' && rest[j] != '\r') ++j;
  const std::string_view token = rest.substr(i, j - i);
  rest.remove_prefix(j);
  return token;
}

std::string shownToken(std::string_view token) {
  std::string out;
  for (char c : token.substr(0, 40)) out += static_cast<unsigned char>(c) < 0x20 ? '?' : c;
  return token.size() > 40 ? out + "..." : out;
}

// One "v/vt/vn" reference of an f, l or p statement against the counts so far.
std::string checkObjReference(std::string_view ref, const std::size_t (&counts)[3]) {
  static constexpr const char* kKinds[3] = {"vertex", "texture coordinate", "normal"};
  for (int k = 0; k < 3; ++k) {
    const std::size_t slash = ref.find('/');
    const std::string_view part = ref.substr(0, slash);
    ref = slash == std::string_view::npos ? std::string_view{} : ref.substr(slash + 1);
    if (part.empty() && (k > 0 || slash != std::string_view::npos)) {
      if (k == 0) return "a reference without a vertex index";
      if (slash == std::string_view::npos) break;
      continue;
    }
    long long index = 0;
    const auto [end, errc] = std::from_chars(part.data(), part.data() + part.size(), index);
    if (errc != std::errc() || end != part.data() + part.size()) return "'" + shownToken(part) + "' is not an index";
    const long long count = static_cast<long long>(counts[k]);
    if (index == 0 || index > count || index < -count) {
      return std::string(kKinds[k]) + " index " + std::to_string(index) + " names no " + kKinds[k] + " (" +
             std::to_string(count) + " defined so far)";
    }
    if (slash == std::string_view::npos) break;
  }
  if (!ref.empty()) return "a reference with more than three parts";
  return {};
}

std::string checkObjText(std::string_view text, const std::string& label) {
  static constexpr std::string_view kGrouping[] = {"o",        "g",        "s",          "mg",       "usemtl",
                                                   "mtllib",   "maplib",   "usemap",     "lod",      "bevel",
                                                   "c_interp", "d_interp", "shadow_obj", "trace_obj"};
  std::size_t counts[3] = {0, 0, 0};  // v, vt, vn defined so far
  std::size_t line = 0, faces = 0;
  for (std::size_t at = 0; at <= text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    std::string_view rest = text.substr(at, end - at);
    at = end + 1;
    ++line;
    const std::string where = label + ":" + std::to_string(line) + ": ";
    const std::string_view keyword = nextToken(rest);
    if (keyword.empty() || keyword.front() == '#') continue;
    if (keyword == "v" || keyword == "vn" || keyword == "vt" || keyword == "vp") {
      std::size_t numbers = 0;
      for (std::string_view token = nextToken(rest); !token.empty(); token = nextToken(rest), ++numbers) {
        double value = 0.0;
        const auto [end_num, errc] = std::from_chars(token.data(), token.data() + token.size(), value);
        if (errc != std::errc() || end_num != token.data() + token.size())
          return where + "'" + shownToken(token) + "' is not a number";
      }
      const bool position = keyword == "v" || keyword == "vn";
      if (position ? numbers < 3 || numbers > 7 : numbers < 1 || numbers > 3)
        return where + std::string(keyword) + " with " + std::to_string(numbers) + " numbers";
      if (keyword == "v") ++counts[0];
      if (keyword == "vt") ++counts[1];
      if (keyword == "vn") ++counts[2];
    } else if (keyword == "f" || keyword == "l" || keyword == "p") {
      std::size_t refs = 0;
      for (std::string_view token = nextToken(rest); !token.empty(); token = nextToken(rest), ++refs) {
        if (std::string problem = checkObjReference(token, counts); !problem.empty())
          return where + std::string(keyword) + " item " + std::to_string(refs + 1) + ": " + problem;
      }
      const std::size_t least = keyword == "f" ? 3 : keyword == "l" ? 2 : 1;
      if (keyword == "f") ++faces;
      if (refs < least) return where + std::string(keyword) + " with " + std::to_string(refs) + " items";
    } else if (std::find(std::begin(kGrouping), std::end(kGrouping), keyword) == std::end(kGrouping)) {
      return where + "unknown or unsupported OBJ statement '" + shownToken(keyword) +
             "' (polygonal geometry only: v, vt, vn, f, l, p, o, g, s, usemtl, mtllib)";
    }
  }
  if (faces == 0)
    return label + ":" + std::to_string(line) + ": end of file and no face (f) statement: nothing to bake";
  return {};
}

bool isObj(std::string extension) {
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".obj" || extension == "obj";
}

// The OBJ text assimp gets: `mtllib` statements blanked. A collider needs no materials, and
// assimp's MTL parser is where libFuzzer found it crashing (on a memory read it even falls back
// to parsing the OBJ bytes themselves as the material file). Line numbers stay as they were.
std::string withoutMaterialLibraries(std::string text) {
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t start = text.find_first_not_of(" \t", at);
    if (start != std::string::npos && text.compare(start, 6, "mtllib") == 0) text[start] = '#';
    const std::size_t end = text.find('\n', at);
    at = end == std::string::npos ? text.size() : end + 1;
  }
  return text;
}

bool loadObj(std::string text, const std::string& label, ColliderModel& out, std::string& error) {
  if (error = checkObjText(text, label); !error.empty()) return false;
  text = withoutMaterialLibraries(std::move(text));
  Assimp::Importer importer;
  importer.SetIOHandler(new RegularFilesOnly(true));  // the importer owns it; an OBJ needs no other file
  const aiScene* scene = importer.ReadFileFromMemory(text.data(), text.size(), kImportFlags, "obj");
  return convertScene(scene, importer, label, out, error);
}

}  // namespace

bool loadColliderModel(const std::string& path, ColliderModel& out, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    error = path + ": no such file";
    return false;
  }
  if (isObj(std::filesystem::path(path).extension().string())) {
    std::ifstream in(path, std::ios::binary);
    return loadObj(std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), path, out,
                   error);
  }
  Assimp::Importer importer;
  importer.SetIOHandler(new RegularFilesOnly(false));  // the importer owns it
  const aiScene* scene = importer.ReadFile(path, kImportFlags);
  return convertScene(scene, importer, path, out, error);
}

bool loadColliderModelFromMemory(std::span<const std::uint8_t> bytes, const std::string& extension,
                                 const std::string& label, ColliderModel& out, std::string& error) {
  if (isObj(extension)) return loadObj(std::string(bytes.begin(), bytes.end()), label, out, error);
  Assimp::Importer importer;
  importer.SetIOHandler(new RegularFilesOnly(true));
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kImportFlags, extension.c_str());
  return convertScene(scene, importer, label, out, error);
}

std::string openMeshMessage(const ColliderModel& model, const std::string& label) {
  const fluid::ClosedMeshReport report = fluid::checkClosed({model.positions, model.indices});
  if (report.closed()) return {};
  char edge[160];
  std::snprintf(edge, sizeof edge, "(%g, %g, %g)-(%g, %g, %g)", static_cast<double>(report.edge_from.x),
                static_cast<double>(report.edge_from.y), static_cast<double>(report.edge_from.z),
                static_cast<double>(report.edge_to.x), static_cast<double>(report.edge_to.y),
                static_cast<double>(report.edge_to.z));
  return label + ": the mesh is open: " + std::to_string(report.boundary_edges) +
         " boundary edges (edges of one triangle, after welding coincident vertices), the first " + edge +
         "; depth maps of an open mesh call points inside it outside";
}

fluid::ModelLoader colliderModelLoader() {
  return [](const std::filesystem::path& model, std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices,
            std::string& error) {
    ColliderModel mesh;
    if (!loadColliderModel(model.string(), mesh, error)) return false;
    if (error = openMeshMessage(mesh, model.string()); !error.empty()) return false;
    positions = std::move(mesh.positions);
    indices = std::move(mesh.indices);
    return true;
  };
}

}  // namespace game
